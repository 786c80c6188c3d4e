"""Campaigns: many simulated runs of a mission with a vehicle model, on Dask.

A campaign flies the mission ``runs`` times against a
:class:`~mcl2pnml.runtime.vehicle_model.ModelVehicle` drawing its answers,
run ``k`` with the seed ``seed + k`` (so that any run can be flown again
alone: ``mcl2pnml run MISSION --vehicle model:MODEL.json@SEED``), through the
run loop users run (:func:`~mcl2pnml.runtime.engine.run`) on either engine.

The runs go out in batches of consecutive seeds to a Dask cluster
(``distributed``): a local one on this machine's cores by default, or a
user's scheduler. Dask reschedules the batches of a worker that dies; a batch's
result is counted once, by its first seed, so no run is lost or counted twice.
Results are taken in seed order, so the figures (and where a sequential test
stops) depend on the seeds only, not on which worker was faster.

Every wait on a user's scheduler has a deadline (:class:`SchedulerTimeouts`):
its address is probed first, Dask's opening message read within a size bound
and the handshake's deadline (a port that says nothing, trickles bytes or
answers something else than Dask is refused before Dask reads from it, whose
reader would allocate whatever length it is sent); mid-run, a scheduler that
answers nothing for the silence bound (frozen, or without a worker) ends the
campaign. The client runs on an event loop of the call's own, so that what a
deadline abandons is cancelled with it and no thread is left behind; Dask's
logs and warnings are silenced while it runs (a lost scheduler is one
message, not Dask's tracebacks).

The figures: each ending's frequency with its Wilson score interval, the end
times' mean, spread and quantiles, and optionally Wald's sequential
probability ratio test of "P(OK) >= target", which stops the campaign as soon
as it is decided at the asked confidence (Wald, *Sequential Analysis*, 1947).
"""
from __future__ import annotations

import logging
import io
import math
import os
import random
import signal
import struct
import threading
import uuid
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from importlib import import_module
from importlib.util import find_spec
from pathlib import Path
from statistics import NormalDist
from typing import Callable, Iterator
from urllib.parse import urlsplit

from mcl2pnml.core.bounds import MAX_RUN_TIME
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.files import atomic_write_bytes
from mcl2pnml.core.settings import SettingError
from mcl2pnml.runtime.interrupts import Interrupted
from mcl2pnml.runtime.options import RunOptions

#: Runs per task sent to a worker.
BATCH = 500
#: Seconds a user's scheduler may take to complete Dask's handshake (the probe and the
#: client's registration, together), unless ``--scheduler-timeout`` says otherwise.
HANDSHAKE_TIMEOUT = 5.0
#: Seconds mid-run with no batch done and no answer from the scheduler (or no worker
#: on it) after which a campaign ends, unless ``--scheduler-timeout`` says otherwise.
SILENCE_TIMEOUT = 60.0
#: The most seconds either bound may be given (a day).
MAX_SCHEDULER_TIMEOUT = 86_400.0
#: The largest opening message the probe reads from a scheduler: Dask's handshake is a
#: small dictionary (its compression, Python version and pickle protocol), about 100
#: bytes; a length beyond this is not Dask.
HANDSHAKE_MAX_BYTES = 64 << 10
#: The most frames the handshake message may say it has (it has one).
HANDSHAKE_MAX_FRAMES = 16
#: Seconds between the watch's questions to the scheduler mid-run (at most: a fourth
#: of the silence bound when that is shorter).
PING_EVERY = 2.0
#: Seconds a local cluster may take to start its worker processes, and any cluster to
#: close (a frozen scheduler is abandoned then, not waited for).
LOCAL_START, CLOSE_BOUND = 120.0, 5.0
#: Seconds a stopped campaign (a signal) has to close its client and its cluster (each
#: within :data:`CLOSE_BOUND`) before it is abandoned.
STOP_BOUND = 3 * CLOSE_BOUND
#: What ``--plot`` can write (matplotlib's writers, by the file's suffix).
PLOT_SUFFIXES = (".png", ".svg", ".pdf")
#: What ``--table`` can write.
TABLE_SUFFIXES = (".csv", ".parquet")
#: The signals that stop a campaign as Ctrl-C (SIGINT) does.
STOP_SIGNALS = (signal.SIGTERM, signal.SIGHUP)
#: The loggers of Dask and of what it runs on, silenced while a campaign runs.
DASK_LOGGERS = ("distributed", "tornado", "asyncio", "bokeh")
#: The indifference region of the sequential test, either side of its target.
INDIFFERENCE = 0.02
#: The confidence of the intervals and the sequential test, unless told (``--confidence``).
CONFIDENCE = 0.99


@dataclass(frozen=True)
class SchedulerTimeouts:
    """The deadlines on a campaign's scheduler (``--scheduler-timeout HANDSHAKE[,SILENCE]``):
    the handshake on a user's, the silence on any (a local cluster's too)."""

    #: seconds to reach the scheduler and complete Dask's handshake, all told
    handshake: float = HANDSHAKE_TIMEOUT
    #: seconds mid-run with no batch done and no answer from a scheduler with workers
    silence: float = SILENCE_TIMEOUT

    @classmethod
    def parse(cls, text: str) -> "SchedulerTimeouts":
        """``HANDSHAKE`` or ``HANDSHAKE,SILENCE``, in seconds; a ValueError saying what is
        wrong."""
        parts = text.split(",")
        if len(parts) > 2 or not all(p.strip() for p in parts):
            raise ValueError(f"'{text}' is not HANDSHAKE[,SILENCE] (seconds, e.g. "
                             f"{cls()})")
        values = []
        for part in parts:
            try:
                value = float(part)
            except ValueError:
                raise ValueError(f"'{part.strip()}' is not a number of seconds") from None
            if not 0 < value <= MAX_SCHEDULER_TIMEOUT:    # NaN fails too
                raise ValueError(f"'{part.strip()}' is not a number of seconds above 0 and "
                                 f"at most {MAX_SCHEDULER_TIMEOUT:g}")
            values.append(value)
        return cls(*values)

    def __str__(self) -> str:
        return f"{self.handshake:g},{self.silence:g}"


def scheduler_address(text: str) -> str:
    """A Dask scheduler's address, ``tcp://HOST:PORT`` (or ``HOST:PORT``), as Dask takes it;
    a ValueError saying what is wrong (another scheme, no port, a port out of range)."""
    said = text.strip()
    if not said:
        raise ValueError("the address is empty (tcp://HOST:PORT)")
    parts = urlsplit(said if "://" in said else f"tcp://{said}")
    if parts.scheme != "tcp":
        raise ValueError(f"'{text}' is not a Dask scheduler's address: it is "
                         "tcp://HOST:PORT (Dask's default port is 8786)")
    try:
        port = parts.port
    except ValueError:
        port = 0
    host = parts.hostname
    if not host or parts.path not in ("", "/") or parts.query or parts.fragment \
            or parts.username is not None:
        raise ValueError(f"'{text}' is not tcp://HOST:PORT")
    if port is None:
        raise ValueError(f"'{text}' has no port (tcp://HOST:PORT; Dask's default is 8786)")
    if not 0 < port < 65536 or not parts.netloc.rsplit(":", 1)[1].isdigit():
        raise ValueError(f"the port of '{text}' is not a number from 1 to 65535")
    return f"tcp://[{host}]:{port}" if ":" in host else f"tcp://{host}:{port}"


def check_outputs(table: Path | None, plot: Path | None) -> None:
    """Refuse, before any run, a table or a plot that could not be written once the runs
    are done: a suffix that says no format we write, a folder that does not exist, a
    Parquet table without pyarrow (one :class:`~mcl2pnml.core.settings.SettingError`)."""
    for setting, path, suffixes in (("table", table, TABLE_SUFFIXES),
                                    ("plot", plot, PLOT_SUFFIXES)):
        if path is None:
            continue
        if path.suffix.lower() not in suffixes:
            raise SettingError(setting, f"'{path}' has no suffix of a format it is written "
                                        f"in: {', '.join(suffixes)}")
        folder = path.parent if str(path.parent) else Path(".")
        if not folder.is_dir():
            raise SettingError(setting, f"the folder of '{path}' does not exist")
        if not os.access(folder, os.W_OK | os.X_OK):
            raise SettingError(setting, f"the folder of '{path}' cannot be written to")
    if table is not None and table.suffix.lower() == ".parquet":
        if find_spec("pyarrow") is None:
            raise SettingError("table", "a Parquet table needs pyarrow (pip install "
                                        "pyarrow); or write .csv")


@dataclass(frozen=True)
class Fleet:
    """How each run's vehicle is built: a vehicle model drawing its answers, or the
    kinematic simulator in a world; the faults of a fault file injected into either
    (docs/faults.md). Paths as strings: sent to the workers, which read the files."""

    #: a vehicle model (docs/odds.md); None: the simulator
    model: str | None = None
    #: the simulator's world (docs/simulator.md); None: the default world
    world: str | None = None
    #: the faults injected into every run (None: none)
    faults: str | None = None

    def files(self) -> tuple[str, ...]:
        return tuple(f for f in (self.model, self.world, self.faults) if f is not None)

    def replay(self, mission: str, seed: int) -> str:
        """The command that flies run ``seed`` again, alone."""
        from shlex import quote     # a command to paste into a shell, whatever the names
        vehicle = f"model:{self.model}@{seed}" if self.model else f"sim@{seed}"
        world = f" --world {quote(self.world)}" if self.world else ""
        faults = f" --faults {quote(self.faults)}" if self.faults else ""
        return f"mcl2pnml run {quote(mission)} --vehicle {quote(vehicle)}{world}{faults}"


@dataclass(frozen=True)
class Flown:
    """One run: its seed, how it ended and when; whether it failed each property
    watched (None: not judged, a run stopped by the time limit); and for the first
    runs of a simulated campaign, the vehicle's track (x, y), thinned."""

    seed: int
    outcome: str
    time: float
    fails: tuple[bool | None, ...] = ()
    track: tuple[tuple[float, float], ...] = ()


#: The runs whose tracks a simulated campaign keeps (from its first seed), to draw.
TRACKS = 20
#: The most points kept of a track.
TRACK_POINTS = 400
#: The outcomes after which a run's properties are judged: it ended, or waits for ever
#: (nothing pending: a finite run). A run stopped by the time limit is not judged.
JUDGED = ("OK", "FAIL", "ABORTED", "STALLED")


def fly_batch(mission: str, fleet: Fleet, engine: str, seeds: list[int], max_time: float,
              properties: tuple = (), tracks_below: int = -1) -> list[Flown]:
    """Fly the runs of ``seeds`` (a task of a worker)."""
    # the observers and the engine: a worker's, not the command's start (the CLI reads
    # this module's scheduler options when it starts)
    from mcl2pnml.analysis.checking.observers import Watcher
    from mcl2pnml.runtime.engine import run
    make, build = _prepared(mission, fleet, engine)
    out = []
    for seed in seeds:
        mission_engine, vehicle = make(), build(seed)
        seen: list = []
        if properties:
            watcher = Watcher(properties, mission_engine.places)
            seen.append(watcher.start(mission_engine.marking))

            def read(_t, _name, e=mission_engine):
                seen[0] = watcher.read(seen[0], e.marking)
            mission_engine.on_fire = read
        r = run(mission_engine, vehicle, max_time=max_time)
        fails = tuple(watcher.pending(seen[0])) if properties and \
            r.outcome.value in JUDGED else (None,) * len(properties)
        track = ()
        if seed < tracks_below:
            path = getattr(getattr(vehicle, "inner", vehicle), "trajectory", ())
            step = max(1, len(path) // TRACK_POINTS)
            track = tuple((float(x), float(y)) for _, x, y, _ in (*path[::step], *path[-1:]))
        out.append(Flown(seed, r.outcome.value, float(r.time), fails, track))
    return out


#: What a worker has prepared, by mission, vehicles and engine (and their files' times):
#: the batches of one campaign compile the mission and read the files once per worker.
_PREPARED: dict[tuple, tuple] = {}


def _prepared(mission: str, fleet: Fleet, engine: str) -> tuple[Callable, Callable]:
    """The engine's maker and the vehicle's builder (by seed) of a campaign."""
    # lark and the compiler (40 ms), the engines: a worker's, not the command's start
    from mcl2pnml.language.semantics import check_program
    from mcl2pnml.language.compiler import compile_checked
    from mcl2pnml.language.parser import parse_file
    from mcl2pnml.runtime.executor import PetriEngine
    from mcl2pnml.runtime.reference import ReferenceEngine
    key = (mission, fleet, engine, os.stat(mission).st_mtime_ns,
           *(os.stat(f).st_mtime_ns for f in fleet.files()))
    found = _PREPARED.get(key)
    if found is None:
        # not bounded again: the facade read it within --max-mission-size before any batch
        checked = check_program(parse_file(mission))
        if engine == "petri":
            make = PetriEngine(compile_checked(checked)).clone
        else:
            def make():
                return ReferenceEngine(checked)
        _PREPARED.clear()
        found = _PREPARED[key] = (make, vehicle_builder(fleet))
    return found


def vehicle_builder(fleet: Fleet) -> Callable[[int], object]:
    """Run ``seed``'s vehicle: the model drawing with ``random.Random(seed)``, or the
    simulator whose world's noise is seeded ``seed``; the faults drawn from a stream
    of their own (``random.Random(f"faults-{seed}")``), so that injecting faults does
    not change what the vehicle would have drawn. ``run --vehicle model:MODEL@SEED``
    (or ``sim@SEED``) ``--faults FILE`` builds the same vehicle."""
    # the vehicles: a worker's, not the command's start
    from mcl2pnml.runtime.faults import Faults, FaultyVehicle
    from mcl2pnml.runtime.simulator import AUVSimulator, World
    from mcl2pnml.runtime.vehicle_model import Draw, ModelVehicle, VehicleModel
    faults = Faults.load(fleet.faults) if fleet.faults else None
    if fleet.model is not None:
        model = VehicleModel.load(fleet.model)

        def inner(seed: int):
            return ModelVehicle(model, Draw(random.Random(seed)))
    else:
        world = World.load(fleet.world) if fleet.world else World()

        def inner(seed: int):
            return AUVSimulator(replace(world, seed=seed))

    def build(seed: int):
        vehicle = inner(seed)
        return vehicle if faults is None else \
            FaultyVehicle(vehicle, faults, random.Random(f"faults-{seed}"))
    return build


def wilson(k: int, n: int, confidence: float) -> tuple[float, float]:
    """The Wilson score interval of ``k`` successes in ``n`` trials."""
    if n == 0:
        return 0.0, 1.0
    z = _z(confidence)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


@dataclass
class Sprt:
    """Wald's test of P(OK) >= ``target`` against P(OK) < it, with an indifference
    region of :data:`INDIFFERENCE` either side, both errors ``1 - confidence``."""

    target: float
    confidence: float
    llr: float = 0.0
    decided: str | None = None
    after: int = 0

    def __post_init__(self):
        self.p0 = max(self.target - INDIFFERENCE, 1e-9)
        self.p1 = min(self.target + INDIFFERENCE, 1 - 1e-9)
        alpha = 1 - self.confidence
        self.upper = math.log((1 - alpha) / alpha)
        self.lower = math.log(alpha / (1 - alpha))

    def add(self, ok: bool) -> None:
        if self.decided:
            return
        self.after += 1
        self.llr += math.log(self.p1 / self.p0) if ok else \
            math.log((1 - self.p1) / (1 - self.p0))
        if self.llr >= self.upper:
            self.decided = f"P(OK) >= {self.target:g}"
        elif self.llr <= self.lower:
            self.decided = f"P(OK) < {self.target:g}"


@dataclass
class Campaign:
    """A campaign's runs so far, in seed order, and its figures."""

    confidence: float = CONFIDENCE
    runs: list[Flown] = field(default_factory=list)
    sprt: Sprt | None = None
    #: the names of the properties judged on each run, in the order of ``Flown.fails``
    properties: tuple[str, ...] = ()
    #: what flew: the vehicle model, or the simulator's world, and the faults
    fleet: Fleet = field(default_factory=Fleet)
    #: the first run that did not end OK: its seed, its outcome, and the command that
    #: flies it again alone (None: every run ended OK)
    again: tuple[int, str, str] | None = None

    def add(self, flown: Flown) -> None:
        self.runs.append(flown)
        if self.sprt is not None:
            self.sprt.add(flown.outcome == "OK")

    @property
    def done(self) -> bool:
        return self.sprt is not None and self.sprt.decided is not None

    def as_json(self) -> dict:
        n = len(self.runs)
        counts: dict[str, int] = {}
        for r in self.runs:
            counts[r.outcome] = counts.get(r.outcome, 0) + 1
        outcomes = {o: {"runs": k, "frequency": k / n,
                        "interval": list(wilson(k, n, self.confidence))}
                    for o, k in sorted(counts.items())}
        ended = sorted(r.time for r in self.runs if r.outcome in ("OK", "FAIL", "ABORTED"))
        times = {}
        if ended:
            mean = sum(ended) / len(ended)
            var = sum((t - mean) ** 2 for t in ended) / max(len(ended) - 1, 1)
            times = {"mean": mean, "std": math.sqrt(var),
                     "mean_interval_halfwidth": _z(self.confidence) * math.sqrt(var / len(ended)),
                     **{f"p{q}": ended[min(len(ended) - 1, math.ceil(q / 100 * len(ended)) - 1)]
                        for q in (5, 50, 95)}}
        out = {"runs": n, "confidence": self.confidence, "outcomes": outcomes,
               "end_time": times}
        if self.properties:
            out["properties"] = [self._property(k, name) for k, name in
                                 enumerate(self.properties)]
        if self.again is not None:
            seed, outcome, command = self.again
            out["first_not_ok"] = {"seed": seed, "outcome": outcome, "replay": command}
        if self.sprt is not None:
            out["test"] = {"hypothesis": f"P(OK) >= {self.sprt.target:g}",
                           "decided": self.sprt.decided, "after_runs": self.sprt.after}
        return out


    def _property(self, k: int, name: str) -> dict:
        """How often property ``k`` held on the runs judged, with its interval."""
        judged = [r.fails[k] for r in self.runs if r.fails[k] is not None]
        held = judged.count(False)
        return {"property": name, "runs_judged": len(judged),
                "holds": held / len(judged) if judged else None,
                "interval": list(wilson(held, len(judged), self.confidence)),
                "first_failing_seed": next((r.seed for r in self.runs if r.fails[k]), None)}


def _z(confidence: float) -> float:
    return NormalDist().inv_cdf(0.5 + confidence / 2)


def fly(mission: Path, fleet: Fleet, runs: int, *, engine: str = RunOptions.engine,
        seed: int = 0,
        confidence: float = CONFIDENCE, target: float | None = None,
        workers: int | None = None, scheduler: str | None = None,
        timeouts: SchedulerTimeouts = SchedulerTimeouts(), max_time: float = MAX_RUN_TIME,
        properties: tuple = (),
        progress: Callable[[int, int], None] | None = None) -> Campaign:
    """Fly the campaign (the module's documentation) and return its runs in seed order,
    each judged on ``properties`` (compiled on the mission's net: the Petri-net engine's
    markings are read). ``scheduler`` is a user's (:func:`scheduler_address`), held to
    ``timeouts``; None: a local cluster of ``workers`` processes."""
    if find_spec("distributed") is None:
        raise Mcl2PnmlError("a campaign runs on Dask: pip install 'dask[distributed]'")
    if scheduler is not None:       # the CLI has checked it; a library caller may not
        try:
            scheduler = scheduler_address(scheduler)
        except ValueError as e:
            raise SettingError("scheduler", str(e)) from None
    campaign = Campaign(confidence, sprt=Sprt(target, confidence) if target else None,
                        properties=tuple(p.name for p in properties), fleet=fleet)
    flight = _Flight(campaign, runs, (str(mission.resolve()), fleet, engine), seed,
                     max_time, tuple(properties), progress)
    with _quiet():
        _on_own_loop(lambda: _flown(flight, scheduler, workers, timeouts))
    return campaign


@dataclass
class _Flight:
    """What one campaign sends out, and where its runs go."""

    campaign: Campaign
    runs: int
    #: the mission's path, the fleet and the engine, as each batch is told them
    args: tuple
    seed: int
    max_time: float
    properties: tuple
    progress: Callable[[int, int], None] | None


class _DaskOnly(logging.Filter):
    """Refuses the records of :data:`DASK_LOGGERS`' families."""

    def filter(self, record: logging.LogRecord) -> bool:
        return record.name.split(".")[0] not in DASK_LOGGERS


@contextmanager
def _quiet() -> Iterator[None]:
    """Dask's logs and warnings silenced: what goes wrong is the campaign's one message,
    not Dask's tracebacks. Dask's loggers are made on import (its own handler on
    ``distributed``): each is disabled; a logger made later is refused by every handler
    a record of it could reach (its family's, the root's, the last resort)."""
    import_module("distributed")    # its loggers made, to be disabled
    family = {logging.getLogger(name) for name in list(logging.root.manager.loggerDict)
              if name.split(".")[0] in DASK_LOGGERS}
    family |= {logging.getLogger(name) for name in DASK_LOGGERS}
    was = [(logger, logger.disabled) for logger in family]
    handlers = {h for logger in (*family, logging.root) for h in logger.handlers}
    handlers |= {logging.lastResort} if logging.lastResort else set()
    only = _DaskOnly()
    for logger in family:
        logger.disabled = True
    for handler in handlers:
        handler.addFilter(only)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield
    finally:
        for logger, disabled in was:
            logger.disabled = disabled
        for handler in handlers:
            handler.removeFilter(only)


def _on_own_loop(make: Callable) -> None:
    """Run the coroutine ``make()`` on an event loop of its own, which is closed when it
    ends (whatever a deadline abandoned in it cancelled then); from a thread of its own
    when the caller already runs a loop (a notebook)."""
    import asyncio     # where used: the CLI imports this module for its options
    try:
        asyncio.get_running_loop()
        inside = True
    except RuntimeError:
        inside = False
    if not inside:      # out of the except block: no error of the campaign's chained to it
        _stoppable(make)
        return
    failed: list[BaseException] = []

    def body():
        try:
            _stoppable(make)
        except BaseException as e:      # noqa: BLE001 (handed to the caller as it is)
            failed.append(e)
    thread = threading.Thread(target=body, name="mcl2pnml-campaign")
    thread.start()
    thread.join()
    if failed:
        raise failed[0]


def _stoppable(make: Callable) -> None:
    """Run the coroutine ``make()`` on a new event loop, SIGINT, SIGTERM and SIGHUP
    stopping it (in the main thread, unless the signal is ignored): the coroutine
    cancelled, its cluster closed, then the run time's
    :class:`~mcl2pnml.runtime.interrupts.Interrupted` (a KeyboardInterrupt naming the
    signal), which the CLI says as an interruption, exit 128 + the signal. The handlers
    there before are put back.

    Not ``asyncio.run``: it waits, unbounded, for a cancelled task to end, and Dask's
    tasks can swallow a cancellation (a stop while a local cluster started hung so). Here
    the stop waits :data:`STOP_BOUND` seconds for the campaign to close its cluster, and
    the loop's own closing :data:`CLOSE_BOUND` for what is left; what is still running
    then is abandoned with the loop."""
    import asyncio   # with Dask: only a campaign's flight, not the command's start
    loop = asyncio.new_event_loop()
    asyncio.set_event_loop(loop)        # as asyncio.run does: Dask may ask for it
    caught: list[int] = []
    stop = loop.create_future()
    before = {}
    if threading.current_thread() is threading.main_thread():
        for signum in (signal.SIGINT, *STOP_SIGNALS):
            handler = signal.getsignal(signum)
            # SIGINT: only while Python's own handler has it, as asyncio.run does
            if handler in (signal.SIG_IGN, None) or \
                    (signum == signal.SIGINT and handler is not signal.default_int_handler):
                continue
            before[signum] = handler
            loop.add_signal_handler(signum, lambda n=signum: (
                caught.append(n), stop.done() or stop.set_result(n)))
    try:
        task = loop.create_task(make())
        loop.run_until_complete(asyncio.wait({task, stop},
                                             return_when=asyncio.FIRST_COMPLETED))
        if task.done():
            task.result()
            return
        task.cancel()           # its own ending closes its cluster, each step bounded
        loop.run_until_complete(asyncio.wait({task}, timeout=STOP_BOUND))
        if task.done() and not task.cancelled():
            task.exception()    # taken: what failed while it stopped is not said apart
        raise Interrupted(caught[0])
    finally:
        for signum, handler in before.items():
            loop.remove_signal_handler(signum)
            signal.signal(signum, handler)
        _close_loop(loop)


def _close_loop(loop) -> None:
    """Close ``loop`` as ``asyncio.run`` does (its tasks cancelled, its generators and
    default executor shut down), each step within :data:`CLOSE_BOUND` seconds: a task
    that does not end when cancelled is abandoned with the loop, silently."""
    import asyncio   # with Dask: only a campaign's flight, not the command's start
    try:
        left = [t for t in asyncio.all_tasks(loop) if not t.done()]
        for task in left:
            task.cancel()
        for step in ([asyncio.gather(*left, return_exceptions=True)] if left else []) + \
                [loop.shutdown_asyncgens(), loop.shutdown_default_executor()]:
            loop.run_until_complete(asyncio.wait({loop.create_task(step) if
                                                  asyncio.iscoroutine(step) else step},
                                                 timeout=CLOSE_BOUND))
        if any(not t.done() for t in asyncio.all_tasks(loop)):
            # what was abandoned is destroyed pending with the loop: not a message of ours
            loop.set_exception_handler(lambda _loop, _context: None)
    finally:
        asyncio.set_event_loop(None)
        loop.close()


async def _within(awaitable, seconds: float):
    """``awaitable``'s result, or ``asyncio.TimeoutError`` after ``seconds``: it is then
    cancelled and left, not waited for (``asyncio.wait_for`` waits for a cancelled task to
    end, which one of Dask's that swallows its cancellation never does). Cancelled from
    outside, it cancels ``awaitable`` and ends at once, for the same reason."""
    import asyncio   # with Dask: only a campaign's flight, not the command's start
    task = asyncio.ensure_future(awaitable)
    # what a task left here ends in is taken when it ends: not an error said at its end
    task.add_done_callback(lambda t: t.cancelled() or t.exception())
    try:
        done, _ = await asyncio.wait({task}, timeout=seconds)
    except asyncio.CancelledError:
        task.cancel()
        raise
    if not done:
        task.cancel()
        raise asyncio.TimeoutError
    return task.result()


class _NotDask(Exception):
    """What the probe found at an address that does not speak Dask."""


async def _probe(address: str) -> None:
    """Read the scheduler's opening message (Dask's handshake: a scheduler speaks first)
    within :data:`HANDSHAKE_MAX_BYTES`, and check that it is one: a length read from the
    peer is judged before anything is read by it. The caller holds the deadline."""
    import asyncio   # with Dask: only a campaign's flight, not the command's start
    # Dask's distributed: most of a second to import; only a campaign's flight
    from distributed.protocol.core import loads
    from distributed.protocol.utils import unpack_frames
    parts = urlsplit(address)
    reader, writer = await asyncio.open_connection(parts.hostname, parts.port)
    try:
        word = struct.calcsize("Q")     # Dask's frame lengths, in its native layout
        (size,) = struct.unpack("Q", await reader.readexactly(word))
        if not 2 * word <= size <= HANDSHAKE_MAX_BYTES:
            raise _NotDask(f"its opening message claims {size:,} bytes")
        body = await reader.readexactly(size)
        (count,) = struct.unpack_from("Q", body)
        if not 0 < count <= HANDSHAKE_MAX_FRAMES or word * (1 + count) > size:
            raise _NotDask("its opening message is not Dask's framing")
        try:    # Dask's own unpacking, once the count of frames is bounded
            frames = unpack_frames(body)
        except AssertionError:          # frames longer than the message
            frames = None
        if frames is None or word * (1 + count) + sum(len(f) for f in frames) != size:
            raise _NotDask("its opening message is not Dask's framing")
        try:
            said = loads(frames, deserialize=False)
        except Exception:           # noqa: BLE001 (whatever the decoder makes of noise)
            said = None
        if not isinstance(said, dict) or "pickle-protocol" not in said:
            raise _NotDask("its opening message is not Dask's handshake")
    finally:
        writer.close()


async def _flown(flight: _Flight, scheduler: str | None, workers: int | None,
                 timeouts: SchedulerTimeouts) -> None:
    """The campaign on this loop: the cluster reached (or started), the batches sent, the
    runs taken in seed order, the scheduler watched; everything closed within a bound."""
    import asyncio   # with Dask: only a campaign's flight, not the command's start
    from dask.system import CPU_COUNT   # Dask: only a campaign's flight
    from distributed import Client, LocalCluster   # Dask: only a campaign's flight
    made: list = []     # the cluster and the client, as soon as each exists: to close

    async def local():
        # no more workers than batches: a worker with none to fly still started an
        # interpreter that imported Dask (a second and a half of CPU, for nothing, in a
        # campaign of one batch on two workers)
        count = max(1, min(workers or CPU_COUNT, -(-flight.runs // BATCH)))
        made.append(LocalCluster(n_workers=count, threads_per_worker=1, processes=True,
                                 dashboard_address=None, silence_logs=logging.CRITICAL,
                                 asynchronous=True))
        await made[-1]
        made.append(Client(made[-1], asynchronous=True, set_as_default=False))
        await made[-1]

    async def reach():
        await _probe(scheduler)
        made.append(Client(scheduler, asynchronous=True, set_as_default=False,
                           timeout=timeouts.handshake))
        await made[-1]
    try:
        if scheduler is None:
            try:
                await _within(local(), LOCAL_START)
            except asyncio.TimeoutError:
                raise Mcl2PnmlError(f"the local Dask cluster did not start within "
                                    f"{LOCAL_START:g} s") from None
        else:
            try:
                await _within(reach(), timeouts.handshake)
            except asyncio.TimeoutError:
                raise Mcl2PnmlError(f"the Dask scheduler {scheduler} did not complete "
                                    f"Dask's handshake within {timeouts.handshake:g} s "
                                    "(--scheduler-timeout)") from None
            except asyncio.IncompleteReadError:
                raise Mcl2PnmlError(f"{scheduler} is not a Dask scheduler: it closed the "
                                    "connection before Dask's handshake") from None
            except OSError as e:
                raise Mcl2PnmlError(f"cannot reach the Dask scheduler {scheduler}: "
                                    f"{e.strerror or e}") from None
            except _NotDask as e:
                raise Mcl2PnmlError(f"{scheduler} is not a Dask scheduler: {e}") from None
        named = f"the Dask scheduler {scheduler}" if scheduler else \
            "the local Dask cluster's scheduler"
        await _run(flight, made[-1], named, timeouts.silence)
    finally:
        for closing in reversed(made):      # the client, then its cluster
            try:
                await _within(closing.close(), CLOSE_BOUND)
            except Exception:    # noqa: BLE001 (a lost or frozen scheduler: abandoned)
                pass


# Its two tasks, taking the batches and watching the scheduler, share what was last heard
# and the workers counted, as closures over its state: each task is short, and apart they
# would hand that state back and forth; so the one function is 85 lines long.
async def _run(flight: _Flight, client, named: str, silence: float) -> None:
    """Send the batches, take their runs in seed order until the campaign is done, and
    end it if the scheduler (``named`` so in the messages) says nothing (no batch done,
    no answer with a worker) for ``silence`` seconds."""
    import asyncio   # with Dask: only a campaign's flight, not the command's start
    from distributed import as_completed   # Dask: only a campaign's flight
    loop = asyncio.get_running_loop()
    campaign, seed, runs = flight.campaign, flight.seed, flight.runs
    batches = [list(range(seed + k, seed + min(k + BATCH, runs))) for k in range(0, runs, BATCH)]
    tracks_below = seed + TRACKS if flight.args[1].model is None else -1
    # keys of this campaign alone: a scheduler shared with other campaigns (another
    # user's, another mission) must never take one's batch for another's
    tag = uuid.uuid4().hex
    futures = {client.submit(fly_batch, *flight.args, batch, flight.max_time,
                             flight.properties, tracks_below, pure=False,
                             key=f"mcl2pnml-runs-{tag}-{batch[0]}"): batch[0]
               for batch in batches}
    heard = [loop.time()]
    #: the workers the scheduler said it had when it last answered (None: no answer yet)
    workers: list[int | None] = [None]

    def lost() -> Mcl2PnmlError:
        return Mcl2PnmlError(f"{named} was lost after "
                             f"{len(campaign.runs):,} runs; nothing was written")

    async def take() -> None:
        arrived: dict[int, list[Flown]] = {}
        order = [b[0] for b in batches]
        nxt = 0
        async for future in as_completed(list(futures), loop=client.loop):
            heard[0] = loop.time()
            first = futures[future]
            if first in arrived:            # a batch counted already (a retried task)
                continue
            if future.status == "error":
                e = await future.exception()
                raise Mcl2PnmlError(f"the runs from seed {first} failed on a worker: "
                                    f"{type(e).__name__}: {e}")
            if future.status == "cancelled":    # the scheduler is gone
                raise lost()
            # finished, or its result lost with the worker that held it (killed after the
            # batch was done): Dask runs it again, and this waits for it
            arrived[first] = await future
            while nxt < len(order) and order[nxt] in arrived and not campaign.done:
                for flown in arrived.pop(order[nxt]):
                    campaign.add(flown)
                    if campaign.done:
                        break
                nxt += 1
            if flight.progress:
                flight.progress(len(campaign.runs), runs)
            if campaign.done:
                return

    async def watch() -> None:
        """Return once the scheduler has said nothing for ``silence`` seconds: each
        question bounded by what is left of it, asked every :data:`PING_EVERY` s."""
        while (left := heard[0] + silence - loop.time()) > 0:
            try:
                said = await _within(client.scheduler.identity(n_workers=0), left)
            except Exception:       # noqa: BLE001 (no answer, or one Dask raises as an error)
                said = None
            count = said.get("n_workers") if isinstance(said, dict) else None
            workers[0] = count if isinstance(count, int) else None
            if workers[0]:
                heard[0] = max(heard[0], loop.time())
            await asyncio.sleep(min(PING_EVERY, silence / 4,
                                    max(0.0, heard[0] + silence - loop.time())))

    taking, watching = asyncio.create_task(take()), asyncio.create_task(watch())
    try:
        done, _ = await asyncio.wait({taking, watching}, return_when=asyncio.FIRST_COMPLETED)
    finally:
        for task in (taking, watching):
            task.cancel()
        # bounded: a task awaiting Dask can swallow its cancellation (see _within)
        await asyncio.wait({taking, watching}, timeout=CLOSE_BOUND)
    if taking in done:
        taking.result()
        return
    if client.status != "running":
        raise lost()
    what = "had no worker" if workers[0] == 0 else "answered nothing"
    raise Mcl2PnmlError(f"{named} {what} for {silence:g} s, after "
                        f"{len(campaign.runs):,} runs (--scheduler-timeout); nothing was "
                        "written")


def write_table(campaign: Campaign, path: Path) -> None:
    """The runs as a table: Parquet (``.parquet``, with pyarrow) or CSV; a column per
    property watched, ``fails_NAME`` (true, false, or empty: not judged)."""
    columns: dict[str, list] = {"seed": [r.seed for r in campaign.runs],
                                "outcome": [r.outcome for r in campaign.runs],
                                "time": [r.time for r in campaign.runs]}
    for k, name in enumerate(campaign.properties):
        columns[f"fails_{name}"] = [r.fails[k] for r in campaign.runs]
    if path.suffix.lower() == ".parquet":
        try:
            # pyarrow: optional, and heavy to import; only a Parquet table
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            raise Mcl2PnmlError("a Parquet table needs pyarrow (pip install pyarrow); "
                                "or write .csv") from None
        sink = io.BytesIO()
        pq.write_table(pa.table(columns), sink)
        atomic_write_bytes(path, sink.getvalue())
        return

    def cell(v) -> str:
        return "" if v is None else ("true" if v is True else "false" if v is False
                                     else f"{v:g}" if isinstance(v, float) else str(v))
    lines = [",".join(columns)] + [",".join(cell(c[i]) for c in columns.values())
                                   for i in range(len(campaign.runs))]
    atomic_write_bytes(path, ("\n".join(lines) + "\n").encode())


#: The colour of each outcome, in the plots.
COLOURS = {"OK": "#54a24b", "FAIL": "#e45756", "ABORTED": "#f58518"}


def plot(campaign: Campaign, path: Path, title: str) -> None:
    """The outcomes' frequencies with their intervals, the end times' histogram, and for
    a simulated campaign, the first runs' tracks on the world's map."""
    # matplotlib: a quarter of a second and more to import; only a plot
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt   # once the backend is chosen: no display needed
    data = campaign.as_json()
    tracked = [r for r in campaign.runs if r.track]
    fig, axes = plt.subplots(1, 3 if tracked else 2, figsize=(15 if tracked else 10, 4.5))
    left, right = axes[0], axes[1]
    names = list(data["outcomes"])
    freq = [data["outcomes"][o]["frequency"] for o in names]
    low = [f - data["outcomes"][o]["interval"][0] for o, f in zip(names, freq)]
    high = [data["outcomes"][o]["interval"][1] - f for o, f in zip(names, freq)]
    left.bar(names, freq, yerr=[low, high], capsize=6,
             color=[COLOURS.get(o, "#888888") for o in names])
    left.set_ylim(0, 1)
    left.set_title(f"outcomes of {data['runs']:,} runs ({campaign.confidence:.0%} intervals)")
    ended = [r.time for r in campaign.runs if r.outcome in ("OK", "FAIL", "ABORTED")]
    right.hist(ended, bins=40, color="#4c78a8")
    right.set_xlabel("end time (s)")
    right.set_title("end times")
    if tracked:
        _map(axes[2], campaign.fleet, tracked)
    fig.suptitle(title)
    fig.tight_layout()
    sink = io.BytesIO()
    fig.savefig(sink, format=path.suffix.lstrip(".").lower())
    plt.close(fig)
    atomic_write_bytes(path, sink.getvalue())


def _map(ax, fleet: Fleet, runs: list[Flown]) -> None:
    """The world seen from above (the tank, the cross, the dock, the obstacles) and the
    runs' tracks, each in its outcome's colour."""
    # matplotlib's patches and the simulator's world: only a plot of a simulated campaign
    import matplotlib.patches as patches
    from mcl2pnml.runtime.simulator import World
    world = World.load(fleet.world) if fleet.world else World()
    (x0, y0), (w, h, _) = world.origin, world.tank
    ax.add_patch(patches.Rectangle((x0, y0), w, h, fill=False, edgecolor="#333333"))
    for x, y, _, radius in world.obstacles:
        ax.add_patch(patches.Circle((x, y), radius, color="#999999", alpha=0.6))
    if world.cross is not None:
        ax.plot(*world.cross, marker="P", markersize=12, color="#222222", linestyle="",
                label="cross")
    if world.dock is not None:
        ax.plot(world.dock[0], world.dock[1], marker="s", markersize=10, color="#222222",
                linestyle="", label="dock")
    ax.plot(world.start[0], world.start[1], marker="o", color="#222222", linestyle="",
            label="start")
    shown = set()
    for r in runs:
        xs, ys = zip(*r.track)
        ax.plot(xs, ys, linewidth=0.8, alpha=0.7, color=COLOURS.get(r.outcome, "#888888"),
                label=None if r.outcome in shown else r.outcome)
        shown.add(r.outcome)
    ax.set_aspect("equal")
    ax.set_xlim(x0 - 0.5, x0 + w + 0.5)
    ax.set_ylim(y0 - 0.5, y0 + h + 0.5)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"the tracks of the first {len(runs)} runs")
    ax.legend(fontsize=7, loc="upper right")
