"""Pausing Python's cyclic garbage collector while large nets are built.

A compiled mission of 10,000 calls is a million arcs, each a small tuple.
Every few hundred allocations the collector walks the young objects, and
every so often all of them: with millions alive, those walks make building
a net quadratic in practice (23 s instead of 11 s at 10,000 calls, measured).
Nets are acyclic immutable data, so nothing is lost by not collecting
while they are built; when the work is done, what was built goes straight
to the oldest generation (see :func:`_promote`), which only full
collections look at.
"""
from __future__ import annotations

import functools
import gc
from contextlib import contextmanager
from typing import Callable, Iterator, TypeVar

F = TypeVar("F", bound=Callable)


#: How many objects a block must leave behind for them to be promoted at once.
#: Below it, the next collections walk them as usual: promoting what a small
#: block left would also promote its garbage cycles (an exception and its
#: traceback, on every file that fails to parse) into the oldest generation,
#: which full collections visit too rarely to keep up with a process that
#: parses thousands of files (a fuzzing campaign grew to 24 GB that way).
PROMOTE_ABOVE = 100_000


@contextmanager
def paused_gc() -> Iterator[None]:
    """Disable the cyclic collector inside the block; nested blocks are fine."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            if gc.get_count()[0] > PROMOTE_ABOVE:
                _promote()
            gc.enable()


def _promote() -> None:
    """Move every tracked object to the oldest generation, without walking any.

    What the block built is in the youngest generation, and it is nearly
    all alive: left there, the next collections walk it object by object
    to learn that, first as young, then again as middle-aged (0.3 s each
    for a compiled 10,000-call mission). ``gc.freeze()`` followed by
    ``gc.unfreeze()`` splices the generations' lists into the oldest one
    instead, where only a full collection looks at them, and any garbage
    cycle among them is still found then. Skipped while objects are frozen
    on purpose (a forking server's), since unfreezing would release them.
    """
    if gc.get_freeze_count() == 0:
        gc.freeze()
        gc.unfreeze()


def without_gc(function: F) -> F:
    """Decorator form of :func:`paused_gc`, for the stages that build big data."""
    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        with paused_gc():
            return function(*args, **kwargs)
    return wrapper  # type: ignore[return-value]
