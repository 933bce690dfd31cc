"""How much of an array's memory is resident now (``mincore(2)``, no page touched): the
tests of stores that hand their pages back read it."""

from __future__ import annotations

import ctypes
import ctypes.util
import mmap

import numpy as np

_LIBC = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
_LIBC.mincore.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p]


def resident_bytes(a: np.ndarray) -> int:
    """Bytes of the pages holding ``a`` (contiguous) that are resident now."""
    address, size = a.ctypes.data, a.nbytes
    start = address - address % mmap.PAGESIZE
    pages = -(-(address + size - start) // mmap.PAGESIZE)
    vec = (ctypes.c_ubyte * pages)()
    if _LIBC.mincore(ctypes.c_void_p(start), ctypes.c_size_t(pages * mmap.PAGESIZE), vec):
        raise OSError(ctypes.get_errno(), "mincore failed")
    return int(np.count_nonzero(np.frombuffer(vec, dtype=np.uint8) & 1)) * mmap.PAGESIZE
