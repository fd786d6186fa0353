"""glibc's malloc told to keep freed frame-sized blocks for the next frame.

A process that renders frame after frame (a video export, the inspector's server) allocates
and frees arrays of 0.1 to 2 MB each frame. glibc serves blocks that large with their own
mmap, and hands memory freed at the top of its heap back to the system, so the next frame
takes the same memory back one page fault per 4 KB page. `keep_freed_memory` raises both
thresholds: freed blocks stay in the heap and are reused. On recordings/highway,
`fusionscope export-video` goes from about 650 page faults a frame to about 160, and its
frames come about 5 % faster (the README's Demo section has the figures); in `fusionscope
serve`, the motion stereo stage picture (five tiles, captioned and stacked: 2 MB) went from
5.1 ms and 1,900 page faults to 0.45 ms and none, and a seek's or parameter change's
picture reaches the page 10-20 ms sooner (the README's inspector figures).

The cost: the process keeps up to TRIM_THRESHOLD_BYTES of freed memory instead of returning
it. Elsewhere than glibc (macOS, musl) nothing changes.
"""

from __future__ import annotations

import ctypes

# glibc's malloc.h
M_TRIM_THRESHOLD = -1
M_MMAP_THRESHOLD = -3
# glibc refuses an mmap threshold above half its largest heap, 32 MB on 64-bit systems
MMAP_THRESHOLD_BYTES = 32 << 20
TRIM_THRESHOLD_BYTES = 128 << 20


def keep_freed_memory() -> bool:
    """Raise glibc's mmap and trim thresholds for this process (module docstring). Returns
    whether it could: False where the C library is not glibc."""
    try:
        mallopt = ctypes.CDLL(None).mallopt  # the C library this process runs on
    except (OSError, AttributeError):  # not glibc
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    mallopt.restype = ctypes.c_int
    return bool(
        mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES)
        and mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES)
    )
