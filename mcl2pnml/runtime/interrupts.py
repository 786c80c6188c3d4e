"""The signals that stop a run: SIGINT, SIGTERM and SIGHUP, each ending it with its safe state.

``kill``, ``timeout``, ``systemctl stop``, ``docker stop`` send SIGTERM, a
dropped terminal or SSH session SIGHUP, Ctrl-C SIGINT. Python's own
handling would end the process at once on the first two (no safe stop, no
log) and let a second Ctrl-C cut the safe state short. For the length of a
run, :func:`guard` handles all three alike (docs/running.md, "Outcomes, exit
statuses and the safe stop"):

* the **first** signal while the mission runs raises :class:`Interrupted`
  in the main thread, which the run loop turns into the outcome INTERRUPTED
  with its safe stop and the vehicle's safe state;
* while the run is ending (its safe stop and safe state, then its log and
  its outcome), a signal is only said on standard error: the **second**
  changes nothing, the **third** cuts the safe state short
  (:class:`SafeStateCut`: the run says so, and still writes its log and
  outcome). Past the safe state, the log is written whatever comes; the
  outcome is printed unless three signals come meanwhile (a standard output
  that nobody reads must not keep the process for ever: :class:`Interrupted`).

A signal that was ignored when the run started (``nohup`` ignores SIGHUP,
a shell's background job SIGINT) stays ignored. Handlers can only be set
in the main thread: elsewhere :func:`guard` changes nothing, and the
process's own handling stays.
"""
from __future__ import annotations

import enum
import os
import signal
import threading
from contextlib import contextmanager
from typing import Iterator

#: The signals a run handles, each ending it the same way.
SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
#: The signal, counted from the first, that cuts a running safe state short.
CUT_AT = 3


def exit_status(signum: int) -> int:
    """The exit status of a run a signal stopped: 128 + its number, as a shell reports a
    process the signal ended (130 SIGINT, 143 SIGTERM, 129 SIGHUP)."""
    return 128 + signum


def name_of(signum: int) -> str:
    """The signal's name, as ``kill -l`` says it (SIGTERM)."""
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


class Interrupted(KeyboardInterrupt):
    """A signal stopped the run. A KeyboardInterrupt, as Ctrl-C's is: an adapter's
    ``except Exception`` does not take it, and it is passed on as an interrupt."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum

    @property
    def reason(self) -> str:
        """The run's diagnosis: "interrupted by SIGTERM"."""
        return f"interrupted by {name_of(self.signum)}"


class SafeStateCut(BaseException):
    """The third signal came while the safe state was running: it is cut short."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


class Phase(enum.Enum):
    """Where the run is, for what a signal does."""

    RUNNING = "running"
    """The mission runs: the first signal stops it (:class:`Interrupted`)."""

    SECURING = "securing"
    """The safe stop and the safe state run: a signal is said; the third cuts them short."""

    ENDING = "ending"
    """The vehicle is left as it will be; the log is written: a signal is said, and
    changes nothing."""

    PRINTING = "printing"
    """The outcome is printed (the command line's guard): a signal is said; the third
    since the printing began stops it."""


class Guard:
    """What one run's signals have done so far (:func:`guard` installs it)."""

    def __init__(self, phase: Phase = Phase.RUNNING) -> None:
        self.phase = phase
        #: the signal that stopped the mission (None: none did)
        self.signum: int | None = None
        self.count = 0
        self.cut = False
        #: steps being written down (:meth:`recording`), and a cut that waits for them
        self.held = 0
        self.deferred: int | None = None

    def handle(self, signum: int, frame=None) -> None:
        """The handler of every signal of :data:`SIGNALS` while the guard is installed."""
        self.count += 1
        name = name_of(signum)
        if self.phase is Phase.RUNNING and self.signum is None:
            self.signum = signum
            raise Interrupted(signum)
        if self.count >= CUT_AT and not self.cut and self.phase in (Phase.SECURING,
                                                                    Phase.PRINTING):
            self.cut = True
            if self.phase is Phase.SECURING:
                _say(f"mcl2pnml: {name} again: the safe state is cut short; the vehicle may "
                     "not be in its safe state")
                if self.held:       # a step half written down: it is cut once written
                    self.deferred = signum
                    return
                raise SafeStateCut(signum)
            _say(f"mcl2pnml: {name} again: the outcome is not printed")
            raise Interrupted(signum)
        if self.phase is Phase.SECURING:
            _say(f"mcl2pnml: {name}: the safe state goes on (a third signal cuts it short)")
        else:
            _say(f"mcl2pnml: {name}: the run is ending; its log and outcome are being written")

    @contextmanager
    def recording(self) -> Iterator[None]:
        """A step of the safe state being written down (said, and kept in the log): a cut
        waits for the block's end, so that a step said is a step in the log."""
        self.held += 1
        try:
            yield
        finally:
            self.held -= 1
        if not self.held and self.deferred is not None:
            signum, self.deferred = self.deferred, None
            raise SafeStateCut(signum)

    @contextmanager
    def securing(self) -> Iterator[None]:
        """The safe stop and safe state: signals are said, the third cuts them short; after
        it, the run is ending (a signal changes nothing)."""
        self.phase = Phase.SECURING
        try:
            yield
        finally:
            self.phase = Phase.ENDING


#: The guard of the run in progress in this process (None: no run, or not the main thread).
_current: Guard | None = None


def current() -> Guard:
    """The run's guard, in the main thread where one is installed; elsewhere a guard that
    no signal reaches (a run in another thread must not change the main one's phase)."""
    if _current is not None and threading.current_thread() is threading.main_thread():
        return _current
    return Guard()


def _say(text: str) -> None:
    # os.write, not sys.stderr: a handler may run while the main thread is inside
    # a write to stderr, and a buffered stream is not reentrant
    try:
        os.write(2, (text + "\n").encode())
    except OSError:
        pass


@contextmanager
def guard(phase: Phase = Phase.RUNNING) -> Iterator[Guard]:
    """Handle :data:`SIGNALS` as the module says for the block, from ``phase`` on (a run's
    guard starts RUNNING; the command line prints a run's outcome PRINTING); the previous
    handlers after. Within another guard, that one goes on.

    Outside the main thread it installs nothing (the guard it yields is never
    signalled)."""
    global _current
    if threading.current_thread() is not threading.main_thread():
        yield Guard(phase)
        return
    if _current is not None:
        yield _current
        return
    g = Guard(phase)
    previous = {}
    for sig in SIGNALS:
        before = signal.getsignal(sig)
        if before is signal.SIG_IGN:
            continue         # nohup's SIGHUP, a background job's SIGINT: left ignored
        previous[sig] = before
        signal.signal(sig, g.handle)
    _current = g
    try:
        yield g
    finally:
        _current = None
        for sig, before in previous.items():
            # None: a handler set outside Python, which cannot be put back; the default then
            signal.signal(sig, before if before is not None else signal.SIG_DFL)
