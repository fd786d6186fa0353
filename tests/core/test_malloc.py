"""core.malloc: freed frame-sized blocks are reused instead of faulted back page by page.

Measured in a child process each, as the setting is the whole process's."""

from __future__ import annotations

import platform
import subprocess
import sys

import pytest

# 20 frames that each fill and free three 4 MB blocks; prints the minor page faults taken
# after the first frame.
CHILD = """
import resource, sys
import numpy as np
from core.malloc import keep_freed_memory
if sys.argv[1] == "keep":
    assert keep_freed_memory()
def frame():
    blocks = [np.ones(1 << 22, np.uint8) for _ in range(3)]
frame()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(20):
    frame()
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""
PAGES_PER_BLOCK = (1 << 22) // 4096


def faults(mode: str) -> int:
    done = subprocess.run(
        [sys.executable, "-c", CHILD, mode], capture_output=True, text=True, check=True
    )
    return int(done.stdout)


@pytest.mark.skipif(
    platform.system() != "Linux" or platform.libc_ver()[0] != "glibc", reason="glibc only"
)
def test_a_freed_block_is_reused_without_page_faults() -> None:
    # glibc's defaults: freed blocks go back to the system, each frame faults one back in
    assert faults("default") >= 20 * PAGES_PER_BLOCK // 2
    assert faults("keep") < PAGES_PER_BLOCK  # every frame reuses the first frame's pages
