"""The memory budget of one command: how much it may hold, and what a stage would need.

A command is given a budget in bytes (``analyze --max-memory``; by default
half the memory available when it starts, on top of what the process holds
then). A stage whose need can be told before it runs (reading a file,
enumerating what grows with the net) estimates it first and refuses or
gives up that part; a stage whose need cannot be told (the fill-in of an
elimination) runs under :func:`guard`, which stops it when the process
reaches the budget. Either way the command ends with its own message, a
partial answer or a refusal, before the kernel kills it.

The estimates of :func:`load_estimate` are what reading takes per element
of the file, measured on PNML, TINA and LoLA files of 10^5 and 10^6 places
(``tests/support/bignets.py`` writes them) and on compiled missions, and rounded up:
a parsed XML element and the node or arc it becomes cost 1 to 2 KB.
"""
from __future__ import annotations

import _thread
import os
import signal
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import open_regular

#: Bytes that reading costs per place or transition element of a PNML file and
#: per arc (the XML tree, then the net: fitted to 0.95 and 1.9 KB on generated
#: nets), per payload of our tool data (decoded JSON: 2.3 KB on a compiled
#: mission of 90,000 places), and per other element (names, markings,
#: graphics: about 200 bytes).
PNML_NODE = 1_000
PNML_ARC = 2_000
PNML_PAYLOAD = 3_000
PNML_OTHER = 200
#: Bytes that reading costs per word (a run of characters between blanks) of a
#: text format: measured 1.05 KB for TINA, 0.37 KB for LoLA.
TEXT_WORD = {".net": 1_200, ".lola": 450, ".ll": 450}
#: The estimates are the fitted costs times this, in percent: the fits are within
#: 3% of what was measured, nets of other shapes may differ more.
SAFETY = 110
#: What the interpreter and the modules a command imports hold at least, beyond
#: which a budget is useful: a smaller one is refused outright.
FLOOR = 64 << 20
#: A stage estimated below this runs whatever the budget: the interpreter alone
#: holds more, and a budget smaller than the process (``--max-memory 1K``) still
#: gets the small results, and a partial exploration.
NEGLIGIBLE = 1 << 20
#: What a stage run past a budget smaller than the process may still grow the process
#: by: imports on first use and the allocator's arenas grow it by over a mebibyte for a
#: stage of a few kilobytes of its own, so that with a floor of :data:`NEGLIGIBLE` the
#: same small stage was stopped or not by when the guard looked (one run in ten under load).
SLACK = 16 << 20


class BudgetExceeded(Mcl2PnmlError):
    """A stage would go, or went, past the memory budget."""


def resident() -> int:
    """The bytes this process holds now (VmRSS), or 0 where that is unknown."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def default_memory() -> int:
    """Half of the memory available to this process now, or 2 GiB where that is unknown.

    Available is the least of the machine's ``MemAvailable``, what its control
    group may still take (``memory.max`` less ``memory.current``) and its
    address-space limit (``ulimit -v``, ``prlimit --as``): a process given 4 GB
    of a 24 GB machine budgets 2 GB, not 12.
    """
    import resource   # Unix only: where a budget is asked, not on importing the core
    # read as bytes in one call each: every exploration with the default budget asks
    # (a contract check explores thousands of small nets), and a file object decoding
    # the lines cost more than the kernel's writing them
    available = []
    try:
        info = _read("/proc/meminfo")
        at = info.find(b"MemAvailable:")
        while at > 0 and info[at - 1] != ord("\n"):   # only at the start of a line
            at = info.find(b"MemAvailable:", at + 1)
        if at >= 0:
            end = info.find(b"\n", at)
            available.append(int((info[at:] if end < 0 else info[at:end]).split()[1]) * 1024)
    except OSError:
        pass
    try:
        top = _read("/sys/fs/cgroup/memory.max").strip()
        if top != b"max":
            used = int(_read("/sys/fs/cgroup/memory.current"))
            available.append(max(0, int(top) - used))
    except (OSError, ValueError):
        pass
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY:
        available.append(max(0, soft - resident()))
    return min(available) // 2 if available else 2 << 30


def _read(path: str) -> bytes:
    """A small file of /proc or /sys whole, as bytes (its first MiB: they are a few KiB)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        chunks, size = [], 0
        while size < 1 << 20 and (chunk := os.read(fd, 1 << 16)):
            chunks.append(chunk)
            size += len(chunk)
        return b"".join(chunks)
    finally:
        os.close(fd)


def release() -> None:
    """Give the memory freed since the last call back to the system (glibc's
    ``malloc_trim``), so that what the process holds is what it uses.

    Reading a file frees its XML tree once the net is built, but the C library
    keeps the pages: a net of 10^5 places leaves 516 MB resident, 188 MB after
    this. Elsewhere than on glibc it does nothing.
    """
    global _trim
    if _trim is None:
        try:
            import ctypes   # 2 ms on the CLI's start (python -X importtime): only to trim
            _trim = ctypes.CDLL("libc.so.6").malloc_trim
        except (OSError, AttributeError):
            _trim = False
    if _trim:
        _trim(0)


_trim = None


def size_text(n: float) -> str:
    """``1.5 GB``, ``200 MB``, ``12 KB``, ``80 bytes``: powers of 1024, as ``--max-memory``."""
    for unit, shift in (("T", 40), ("G", 30), ("M", 20), ("K", 10)):
        if n >= 1 << shift:
            return f"{n / (1 << shift):.1f} {unit}B"
    return f"{int(n)} bytes"


class Budget:
    """What the process may hold at most, ``limit`` bytes, and what is left of it.

    ``max_memory`` None: the default budget, half of what is available now on
    top of what the process already holds.
    """

    def __init__(self, max_memory: int | None = None):
        self.given = max_memory is not None
        self.limit = (resident() + default_memory()) if max_memory is None else max_memory

    def free(self) -> int:
        """Bytes the process may still take before it reaches the budget."""
        return self.limit - resident()

    def says(self) -> str:
        """The budget, as messages name it."""
        return (f"the budget is {size_text(self.limit)} (--max-memory)" if self.given else
                f"the budget is {size_text(self.limit)}, half of the memory available "
                "(--max-memory sets it)")

    def check(self, need: int, what: str, location: Location | None = None) -> None:
        """Raise :class:`BudgetExceeded` when ``need`` more bytes would pass the budget
        (never for a need below :data:`NEGLIGIBLE`)."""
        if need > max(self.free(), NEGLIGIBLE):
            raise BudgetExceeded(f"{what} would need about {size_text(need)}; {self.says()}"
                                 + (f", {size_text(max(0, resident()))} of it in use"
                                    if resident() > FLOOR else ""), location)


# -- reading a file -----------------------------------------------------------------------

#: What the net read from a PNML file as a stream takes, per byte of the file, at most:
#: 3.6 on the 10,000-call mission (201 MB, a peak of 733 MB with the interpreter), less
#: on the contest's models, whose nodes are written with more text each.
STREAMED = 4

_CHUNK = 16 << 20


def _counts(path: Path, patterns: tuple[bytes, ...]) -> list[int]:
    """How often each pattern occurs in the file, read a chunk at a time (nothing held)."""
    counts = [0] * len(patterns)
    # each pattern is counted in the chunk with the end of the one before, one byte
    # shorter than the pattern: an occurrence across the cut is seen once, none twice
    tails = [b""] * len(patterns)
    # through the readers' one check: a FIFO or a device is refused, not waited on
    with os.fdopen(open_regular(path), "rb") as f:
        while True:
            chunk = f.read(_CHUNK)
            if not chunk:
                break
            for i, p in enumerate(patterns):
                data = tails[i] + chunk
                counts[i] += data.count(p)
                tails[i] = data[len(data) - len(p) + 1:] if len(p) > 1 else b""
    return counts


def load_estimate(path: str | Path, streamed: bool = False) -> tuple[int, str]:
    """Bytes reading ``path`` takes at its peak, and what it holds, in words for messages.

    Counted from the file without parsing it: PNML's place, transition and
    arc elements and its other elements; a text format's words. A ``.mcl``
    mission compiles to a net about as large as its text is long, and its
    file size is counted as PNML would be. ``streamed``: a PNML file read as a
    stream (the strict reading), which holds the net but never the file's tree.
    """
    path = Path(path)
    size = path.stat().st_size
    suffix = path.suffix.lower()
    if suffix in TEXT_WORD:
        blanks, newlines = _counts(path, (b" ", b"\n"))
        words = blanks + newlines
        return (size + words * TEXT_WORD[suffix]) * SAFETY // 100, f"{words:,} words"
    if streamed:   # read as a stream (the strict PNML reading): no tree, only the net,
        # which its file's size bounds (a place or an arc is written in more bytes than
        # it takes in memory, over STREAMED times), and a stat tells it without a read
        return size * STREAMED * SAFETY // 100, f"a PNML file of {size_text(size)}"
    places, transitions, arcs, payloads, opens, closes, heads = _counts(
        path, (b"<place", b"<transition", b"<arc", b"<payload", b"<", b"</", b"<?"))
    other = max(0, opens - closes - heads - places - transitions - arcs - payloads)
    what = (f"{places:,} places, {transitions:,} transitions and {arcs:,} arcs"
            if places + transitions + arcs else f"{size:,} bytes")
    need = (size + (places + transitions) * PNML_NODE + arcs * PNML_ARC
            + payloads * PNML_PAYLOAD + other * PNML_OTHER)
    return need * SAFETY // 100, what


def check_load(path: str | Path, budget: Budget, streamed: bool = False) -> None:
    """Refuse, before reading it, a file whose net the budget cannot hold.

    The message names the file, what it holds, what reading it would take
    and the budget: ``big.pnml: 1,000,000 places, ... would need about 6.1 GB
    to read; the budget is 2.0 GB (--max-memory)``.
    """
    try:
        need, what = load_estimate(path, streamed)
    except OSError:
        return   # the reader names the file and why it cannot be read
    budget.check(need, f"{what} to read", Location(str(path)))


# -- stopping a stage whose need cannot be told beforehand ---------------------------------

#: How often the guard looks at the process's size, in seconds. An interpreter
#: allocates some hundreds of MB a second at most: a tenth of that is the
#: overshoot the guard's margin takes (:func:`guard`).
POLL = 0.01
#: How far below the budget the guard stops a stage (or a fiftieth of the budget,
#: if more): what the body may still allocate before the interruption lands.
#: Compiling a mission allocates fastest (about 500 MB/s): it went 13 MB past
#: the point where it was interrupted.
MARGIN = 16 << 20


def margin(limit: int) -> int:
    """How far below ``limit`` the guard stops a stage: the body goes on growing
    until the interruption lands. A stage that bounds itself (the explorers) is
    given the budget less twice this, so that it stops on its own first."""
    return max(MARGIN, limit // 50)


class _Stop(BaseException):
    """Raised in the guarded body at the budget; a BaseException, so that no
    ``except Exception`` in a library's code takes it for its own."""


def _land() -> None:
    # a loop's backward jump is where the interpreter runs pending signal handlers
    for _ in range(2):
        pass


def floored(budget: Budget) -> Budget:
    """``budget``, or one that lets the process grow by :data:`SLACK`
    past what it holds now when that is more: a budget smaller than the process can only
    stop what grows. The guard stops a stage :func:`margin` below
    its limit, so the limit is raised by that too (without it the guard tripped at its
    first look, and a small stage's result was kept or not by how long it took)."""
    floor = resident() + SLACK
    if budget.limit - margin(budget.limit) >= floor:
        return budget
    # past 50 margins' worth the margin is a fiftieth of the limit
    limit = max(floor + margin(floor), -(-floor * 50 // 49))
    raised = Budget(limit)
    raised.given, raised.limit = budget.given, limit
    return raised


@contextmanager
def guard(budget: Budget, what: str) -> Iterator[None]:
    """Run the body until it ends or the process reaches ``budget.limit``.

    A thread looks at the process's size every :data:`POLL` seconds; at the
    budget it interrupts the main thread, where the body's next Python
    instruction stops it, and the guard raises :class:`BudgetExceeded`
    (``what`` names the stage). Code in C does not see the interruption until
    it returns to Python, so the stages that run C at length estimate their
    need first. Only the main thread can be interrupted: elsewhere the guard
    does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    stop, tripped, closing = threading.Event(), threading.Event(), threading.Event()

    def on_interrupt(signum, frame):
        if closing.is_set():
            return            # the body is over: an interruption still pending is moot
        if tripped.is_set():
            raise _Stop
        # a real Ctrl-C, handled as it was before the guard: ignored where the process
        # ignores it (a script's background job), else Python's KeyboardInterrupt
        if previous is signal.SIG_IGN:
            return
        if callable(previous):
            return previous(signum, frame)
        raise KeyboardInterrupt

    trip = budget.limit - margin(budget.limit)

    def watch():
        while not stop.wait(POLL):
            if resident() >= trip:
                tripped.set()
                _thread.interrupt_main(signal.SIGINT)
                # again later only if the body took no notice (a C call still running)
                if stop.wait(1.0):
                    return

    previous = signal.signal(signal.SIGINT, on_interrupt)
    watcher = threading.Thread(target=watch, name="memory guard", daemon=True)
    stopped = False
    try:
        # started inside the try: a process already past the budget is interrupted
        # while ``start`` waits for the thread to run, before the body begins
        watcher.start()
        yield
    except _Stop:
        stopped = True
    finally:
        # an interruption may still land until ``closing`` is set (the body ended just
        # as the watcher tripped): taken here, never let out of the guard as a traceback
        while True:
            try:
                closing.set()
                break
            except _Stop:
                stopped = True
        stop.set()
        watcher.join()
        _land()
        signal.signal(signal.SIGINT, previous)
    if stopped or tripped.is_set():
        raise BudgetExceeded(
            f"{what} stopped at the memory budget of {size_text(budget.limit)}"
            + ("" if budget.given else " (half of the memory available; --max-memory sets it)"))
