"""A burst of annotation edits in a process of its own, for test_store's crash test.

    python store_burst.py FOLDER COUNT

Edit k (k = 1, 2, ...) draws track k (`burst_track(k)`) and marks frame k fully annotated;
after each edit is acknowledged its revision is printed on a line of its own, flushed.
"""

from __future__ import annotations

import sys

from core.annotation.model import Keyframe, Track
from core.annotation.store import AnnotationStore, Edit

BOX_SIZE_PX = 20.0


def burst_track(k: int) -> Track:
    """Track k of the burst: one box on frame k, its left edge at k pixels."""
    return Track(k, "car", (Keyframe(k, (float(k), 10.0, k + BOX_SIZE_PX, 10.0 + BOX_SIZE_PX)),))


def main(folder: str, count: int) -> int:
    with AnnotationStore(folder) as store:
        if store.read_only_reason is not None:
            print(store.read_only_reason, file=sys.stderr)
            return 1
        for _ in range(count):
            k = store.revision + 1
            edit = Edit(store.revision, {k: burst_track(k)}, ((k, k, True),), f"draw {k}")
            print(store.apply(edit), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], int(sys.argv[2])))
