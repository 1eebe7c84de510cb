"""glibc allocator settings for training processes.

A training iteration allocates and frees the same few hundred tensors of 0.1–10 MB again and again. glibc's
``malloc`` serves blocks above a (dynamic) threshold with fresh ``mmap`` pages and hands freed memory back to the
kernel, so each iteration pays for hundreds of thousands of page faults — every new page zeroed by the kernel. Keeping
those blocks on the heap (a high ``M_MMAP_THRESHOLD``) and not trimming it (a high ``M_TRIM_THRESHOLD``) removes
about half of the faults and made training ≈ 8 % faster on the 2-core reference machine (``benchmarks/``). The cost:
the process keeps its peak heap (a few hundred MB in training) instead of returning it between iterations.

The same effect is what jemalloc / tcmalloc via ``LD_PRELOAD`` give PyTorch CPU training; ``mallopt`` needs no
extra library and can be applied from inside the process. A no-op where the C library is not glibc.
"""

from __future__ import annotations

import ctypes
import ctypes.util

M_TRIM_THRESHOLD = -1
M_TOP_PAD = -2
M_MMAP_THRESHOLD = -3

MMAP_THRESHOLD = 32 << 20
"""Blocks up to 32 MiB (glibc's largest allowed threshold on 64-bit) come from the heap [bytes]."""
TRIM_THRESHOLD = 1 << 30
"""Free heap kept before glibc returns memory to the kernel [bytes]."""
TOP_PAD = 64 << 20
"""Extra heap requested with each growth [bytes]."""

_applied = False


def keep_heap() -> bool:
    """Apply the settings above to this process (and the worker processes it forks later); once per process.
    Returns whether they are in effect (``False`` without glibc)."""
    global _applied
    if _applied:
        return True
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    _applied = all(mallopt(p, v) == 1 for p, v in ((M_MMAP_THRESHOLD, MMAP_THRESHOLD),
                                                    (M_TRIM_THRESHOLD, TRIM_THRESHOLD), (M_TOP_PAD, TOP_PAD)))
    return _applied
