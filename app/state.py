"""What one browser tab is looking at: the frame, whether it plays, which layers and panels
are shown, and the parameter sets the engine runs with (A, and B when comparing).

The state is a small frozen value; controls replace it with `dataclasses.replace` and the
renderer only ever sees a snapshot, so a frame's image and its overlays always agree.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

from core.params import Params


@dataclass(frozen=True)
class Layers:
    """Which overlays are drawn on the camera image; the bird's-eye view follows radar,
    vehicles, tracks and coasting (`app.bird_eye.bird_eye_geometry`)."""

    radar: bool = True  # radar crosses, coloured by what each target did
    areas: bool = False  # the search areas of the radar targets
    vehicles: bool = True  # vehicle boxes by verdict
    guardrails: bool = True  # guard-rail lines and areas skipped by overlap
    pedestrians: bool = True  # pedestrian boxes kept
    rejected: bool = True  # with reasons: vehicle boxes the size filter dropped, pedestrians
    # a fusion filter rejected
    pruned: bool = False  # pedestrian candidates the size and shape constraints dropped
    strip: bool = False  # the pedestrian search strip
    horizon: bool = True  # horizon, vanishing point and the pitch detector's lines
    tracks: bool = True  # the ids of the tracks measured this frame
    coasting: bool = True  # the ids of the tracks missed this frame ("#id ?"), at their last box
    truth: bool = False  # ground truth, when the drive has it
    # the confirmed tracks measured this frame, boxed with their ids: what a demo shows
    # (what was found and confirmed over frames, nothing a single frame proposed)
    confirmed: bool = False

    @staticmethod
    def names() -> tuple[str, ...]:
        return tuple(f.name for f in fields(Layers))


INSPECTOR_LAYERS = Layers()  # what the inspector opens with

# what a demo draws (the presenter, an exported video): what was found and confirmed over
# frames, not how: no single frame's proposals (raw boxes, radar verdicts, guard-rail lines)
DEMO_LAYERS = Layers(
    radar=False,
    areas=False,
    vehicles=False,
    guardrails=False,
    pedestrians=False,
    rejected=False,
    pruned=False,
    strip=False,
    horizon=False,
    tracks=False,
    coasting=False,
    truth=False,
    confirmed=True,
)


# the stage pictures under the camera, one at a time ("timings" is a table, "none" nothing)
STAGES = ("motion_stereo", "symmetry", "pedestrians", "guard_rails", "timings", "none")


@dataclass(frozen=True)
class Panels:
    """What is drawn beside the camera: only what is shown is drawn."""

    bird_eye: bool = True  # the bird's-eye view in the 3D scene
    can: bool = True  # CAN speed and yaw rate around the playhead
    stage: str = "motion_stereo"  # the one stage picture under the camera, of STAGES

    def __post_init__(self) -> None:
        if self.stage not in STAGES:
            raise ValueError(f"stage: expected one of {', '.join(STAGES)}, got {self.stage!r}")

    @staticmethod
    def switches() -> tuple[str, ...]:
        """The on/off panels."""
        return tuple(f.name for f in fields(Panels) if f.type in ("bool", bool))


@dataclass(frozen=True)
class ViewState:
    """Per-client view: frame index into the drive, playback flag, overlay layers, panels,
    the parameters the engine runs with, a second set B to compare with (None: no
    comparison), and whether the tab annotates (its pictures then include the bare frame)."""

    frame: int = 0
    playing: bool = False
    layers: Layers = INSPECTOR_LAYERS
    params: Params = field(default_factory=Params)
    panels: Panels = field(default_factory=Panels)
    params_b: Params | None = None
    annotating: bool = False

    def __post_init__(self) -> None:
        if self.frame < 0:
            raise ValueError(f"frame: expected an index >= 0, got {self.frame}")
