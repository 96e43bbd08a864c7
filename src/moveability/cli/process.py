"""The ``moveability`` console script's process: how it starts and how it ends.

A command allocates and frees many large numpy arrays. glibc's allocator
returns each block above its mmap threshold to the system when it is freed,
so the next array of that size is mapped again and every page of it faults on
first touch. :func:`tune_allocator` keeps freed blocks below
:data:`KEPT_BLOCK` for reuse (``mallopt``; nothing where the C library has no
``mallopt``).

Once the command has run, its output is flushed and the handlers registered
with :mod:`atexit` (logging's among them) have run, the interpreter's objects
need not be torn down one by one: :func:`finish` ends the process at once
(``os._exit``). It does so only when the main thread is the only one left;
otherwise it exits as usual, so that threads are joined as Python joins them.

Examples
--------
>>> exit_status(None), exit_status(2), exit_status(True)
(0, 2, 1)
"""

from __future__ import annotations

import atexit
import os
import sys
import threading
from typing import Any

__all__ = ["KEPT_BLOCK", "exit_status", "finish", "tune_allocator"]

#: freed blocks up to this size stay with the process for reuse (bytes)
KEPT_BLOCK = 64 << 20

# mallopt's parameters (glibc's malloc.h)
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3


def tune_allocator(kept: int = KEPT_BLOCK) -> bool:
    """Keep freed blocks up to ``kept`` bytes for reuse, and the free memory at
    the top of the heap up to twice that; True where the C library took both."""
    try:
        import ctypes

        mallopt = ctypes.CDLL(None).mallopt
    except (AttributeError, OSError):  # no mallopt (musl, macOS, Windows)
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    return bool(mallopt(_M_MMAP_THRESHOLD, kept)) and bool(mallopt(_M_TRIM_THRESHOLD, 2 * kept))


def exit_status(code: Any) -> int:
    """The status ``sys.exit(code)`` ends a process with (a message, printed on
    stderr by the caller, gives 1)."""
    if code is None:
        return 0
    if isinstance(code, int) and not isinstance(code, bool):
        return code
    return 1


def finish(code: Any) -> None:
    """End the process as ``sys.exit(code)`` would: the :mod:`atexit` handlers
    run and stdout and stderr are flushed; then, if the main thread is the only
    one, the process ends at once (``os._exit``), else by ``sys.exit``."""
    if threading.active_count() > 1:
        sys.exit(code)
    if code is not None and not isinstance(code, int):
        print(code, file=sys.stderr)
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except (OSError, ValueError):  # a reader gone, a stream closed
            pass
    os._exit(exit_status(code))
