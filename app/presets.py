"""Named parameter sets the inspector saves and loads: one YAML file per preset in one folder.

    store = PresetStore(Path("~/.local/share/fusionscope/presets").expanduser())
    store.save("tight-rails", params); store.load("tight-rails"); store.names()

A name is a plain file stem (letters, digits, '-', '_'; at most NAME_MAX_CHARS), so a preset
can only ever be `folder/<name>.yaml`: no path separators, no dots, nothing written
elsewhere. The files are `core.params.save_params` files, readable by `--params` of the
command line. A save writes a temporary file in the folder, syncs it and renames it over
the old one, so a failed save leaves the previous preset whole. The built-in presets
(`core.params.BUILTIN_PRESETS`: "papers", the papers' pipeline) are listed first and load
as `--params NAME` does; their names cannot be saved.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

from core.params import BUILTIN_PRESETS, Params, ParamsError, load_params, params_from, save_params

NAME_MAX_CHARS = 64
NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]*")
SUFFIX = ".yaml"


def check_name(name: str) -> str:
    """`name` stripped of surrounding spaces; ParamsError when it is no preset name."""
    stripped = name.strip()
    if not NAME_PATTERN.fullmatch(stripped) or len(stripped) > NAME_MAX_CHARS:
        raise ParamsError(
            f"preset name: expected letters, digits, '-' or '_' (at most {NAME_MAX_CHARS},"
            f" starting with a letter or digit), got {name!r}"
        )
    return stripped


class PresetStore:
    """The presets in `folder` (created on the first save)."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)

    def names(self) -> list[str]:
        """The built-in presets, then the sorted names of the presets saved so far."""
        return [*BUILTIN_PRESETS, *self.saved()]

    def saved(self) -> list[str]:
        """Sorted names of the presets saved so far."""
        if not self.folder.is_dir():
            return []
        return sorted(
            p.stem
            for p in self.folder.glob(f"*{SUFFIX}")
            if p.is_file() and NAME_PATTERN.fullmatch(p.stem) and p.stem not in BUILTIN_PRESETS
        )

    def path(self, name: str) -> Path:
        return self.folder / f"{check_name(name)}{SUFFIX}"

    def save(self, name: str, params: Params) -> Path:
        """Write `params` as preset `name`, replacing one of that name; its path.

        ParamsError for a bad name, a built-in one, or when the folder cannot be written
        (naming it)."""
        target = self.path(name)
        if target.stem in BUILTIN_PRESETS:
            raise ParamsError(
                f"preset name: {target.stem!r} is built in (the papers' pipeline); choose another"
            )
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            fd, temporary = tempfile.mkstemp(prefix=f".{target.stem}.", dir=self.folder)
        except OSError as err:
            raise ParamsError(f"{self.folder}: cannot write presets here: {err.strerror}") from err
        os.close(fd)
        try:
            save_params(params, temporary)
            with open(temporary, "rb") as written:
                os.fsync(written.fileno())
            os.replace(temporary, target)
        except OSError as err:
            raise ParamsError(f"{target}: cannot save the preset: {err.strerror}") from err
        finally:
            Path(temporary).unlink(missing_ok=True)
        return target

    def load(self, name: str) -> Params:
        """The parameters of preset `name`; ParamsError naming the file when it is missing
        or not a valid parameter file."""
        target = self.path(name)
        if target.stem in BUILTIN_PRESETS:
            return params_from(target.stem)
        if not target.is_file():
            raise ParamsError(f"{target}: no such preset; saved here: {self.saved() or 'none'}")
        return load_params(target)
