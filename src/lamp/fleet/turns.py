"""Coroutines on threads: object loops that take turns with their scheduler, one at a time.

The fleet schedule drives one closed loop per object (``lamp.planners.closed_loop``), each
a plain blocking function that calls its executor. :class:`Turns` runs each loop on its
own thread but lets exactly one thread run at any moment: the scheduler ``resume``\\ s an
object's thread and waits until that thread ``pause``\\ s (blocked on its executor) or
ends. Nothing runs concurrently, so a run is as deterministic as a single-threaded one:
the order of every computation is the scheduler's order.

Guarantees (``tests/test_fleet_turns.py``): ``resume(k)`` returns only once thread ``k``
paused or finished; an exception raised in a thread is raised again by the ``resume`` that
ran it; ``close`` ends every thread still paused (they see :class:`Abandoned`).

Memory: glibc gives every new thread a malloc arena of its own (up to 8 per core), and
memory freed into one is not handed back or reused by the others. Threads that never run
at once gain nothing from that, so :func:`share_malloc_arenas` caps the process at
``MALLOC_ARENAS`` before the first thread starts: ``fleet-16`` (11 loops alive at once)
peaks at 1.52 GB instead of 2.12 GB with the same result (``/usr/bin/time -v lamp run
fleet-16``). glibc also raises its mmap threshold to the size of every large block freed
(up to 32 MB), after which the loops' many short-lived arrays of a few hundred kB to a
few MB (robot spaces, distance tiles, lattice potentials) come from those two heaps and
stay there, fragmented; the threshold is therefore pinned at ``MMAP_THRESHOLD``, so each
such array is mapped on its own and handed back when freed.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import threading
from collections.abc import Callable
from typing import Any

__all__ = ["MALLOC_ARENAS", "MMAP_THRESHOLD", "Abandoned", "Turns", "share_malloc_arenas"]

#: malloc arenas the process keeps once fleet threads start (glibc's ``M_ARENA_MAX``): the
#: main thread's and one more for the libraries' own worker threads
MALLOC_ARENAS = 2
#: blocks of at least this many bytes are mapped on their own (glibc's ``M_MMAP_THRESHOLD``,
#: its initial value, pinned: set, it no longer grows with the blocks freed)
MMAP_THRESHOLD = 128 * 1024
_M_ARENA_MAX = -8  # glibc <malloc.h>
_M_MMAP_THRESHOLD = -3


@functools.cache
def share_malloc_arenas() -> bool:
    """Cap glibc's malloc arenas at ``MALLOC_ARENAS`` and pin its mmap threshold at
    ``MMAP_THRESHOLD`` (see the module docstring), once per process; True when the C
    library took both settings (False elsewhere: not glibc)."""
    name = ctypes.util.find_library("c")
    try:
        mallopt = ctypes.CDLL(name).mallopt
    except (OSError, AttributeError, TypeError):
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    pinned = mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD) == 1
    return mallopt(_M_ARENA_MAX, MALLOC_ARENAS) == 1 and pinned


class Abandoned(BaseException):
    """Raised in a paused thread when its scheduler closes (it unwinds the thread)."""


class Turns:
    """Threads that run one at a time, handing the turn to and from the scheduler."""

    def __init__(self) -> None:
        share_malloc_arenas()
        self._cv = threading.Condition()
        self._turn: int | None = None  # None: the scheduler's turn
        self._threads: dict[int, threading.Thread] = {}
        self._done: set[int] = set()
        self._error: BaseException | None = None
        self._closing = False

    def start(self, key: int, fn: Callable[[], Any]) -> None:
        """Create thread ``key`` running ``fn``; it waits for its first ``resume``."""
        if key in self._threads and key not in self._done:
            raise ValueError(f"Turns: thread {key} is still running")
        self._done.discard(key)

        def body() -> None:
            try:
                self._wait_turn(key)
                fn()
            except Abandoned:
                pass
            except BaseException as exc:  # noqa: BLE001 - handed to the scheduler
                self._error = exc
            finally:
                with self._cv:
                    self._done.add(key)
                    self._turn = None
                    self._cv.notify_all()

        thread = threading.Thread(target=body, name=f"lamp-fleet-{key}", daemon=True)
        self._threads[key] = thread
        thread.start()

    def finished(self, key: int) -> bool:
        """Whether thread ``key`` has ended."""
        return key in self._done

    def resume(self, key: int) -> None:
        """Give the turn to thread ``key`` and wait until it pauses or ends (scheduler)."""
        if key in self._done:
            raise ValueError(f"Turns: thread {key} has finished")
        with self._cv:
            self._turn = key
            self._cv.notify_all()
            self._cv.wait_for(lambda: self._turn is None)
        if self._error is not None:
            error, self._error = self._error, None
            raise error

    def pause(self, key: int) -> None:
        """Hand the turn back to the scheduler and wait for the next ``resume`` (thread)."""
        with self._cv:
            self._turn = None
            self._cv.notify_all()
        self._wait_turn(key)

    def _wait_turn(self, key: int) -> None:
        with self._cv:
            self._cv.wait_for(lambda: self._turn == key or self._closing)
        if self._closing:
            raise Abandoned

    def close(self) -> None:
        """End every thread still paused (each unwinds with :class:`Abandoned`)."""
        with self._cv:
            self._closing = True
            self._cv.notify_all()
        for thread in self._threads.values():
            thread.join(timeout=10.0)
