"""One run of a mission: a vehicle, an engine, the log and the journal, wired together.

What ``mcl2pnml run`` does between reading its options and printing the
outcome (docs/running.md, ``run``): resume a journal's run with the
journal's own options, take the world beside the mission for the simulator
given none (``NAME.world.json``), build the vehicle
(:mod:`mcl2pnml.runtime.vehicles`) with the user's simulated primitives,
check that it offers the primitives the mission uses, journal the run or
replay a journal, drive the engine in virtual time or, against a real
vehicle, on the wall clock (:mod:`mcl2pnml.runtime.engine`), and write the
JSON-lines log. The engine comes from the caller, which knows how to read a
mission (MCL or a compiled net): this layer does not.
"""
from __future__ import annotations

import io
import random
from dataclasses import fields, replace
from pathlib import Path
from typing import IO, Callable

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import atomic_write_text, check_outputs
from mcl2pnml.core.settings import SettingError
from mcl2pnml.core.timing import Assumptions, seconds_text as seconds
from mcl2pnml.runtime import interrupts, journal as journals
from mcl2pnml.runtime.aal import LiveVehicle
from mcl2pnml.runtime.engine import Engine, Run, run as drive, run_realtime
from mcl2pnml.runtime.faults import Faults, FaultyVehicle
from mcl2pnml.runtime.link import LinkOptions
from mcl2pnml.runtime.options import RunOptions
from mcl2pnml.runtime.runlog import RunLog
from mcl2pnml.runtime.simprims import load_file
from mcl2pnml.runtime.vehicles import VehicleKind, kind_of, refuse_sim_primitives, seed_of

#: The options of a run that its journal's header records, and a resume reuses.
JOURNALED = ("engine", "vehicle", "world", "max_time", "sim_primitives", "ack_within",
             "report_gap", "stop_on_breach")
#: What a journal that leaves out an option (an older one) says of it: its default.
UNSAID = {"sim_primitives": [], "ack_within": seconds(Assumptions.ack_within),
          "report_gap": seconds(Assumptions.report_gap), "stop_on_breach": False}


def assumed(options: RunOptions) -> dict[str, str | bool]:
    """The assumptions watched (docs/time.md), as a journal's header records them: each
    number of seconds in decimal, however the user wrote it (0.50, 1/2)."""
    a = options.assumptions()
    return {"ack_within": seconds(a.ack_within), "report_gap": seconds(a.report_gap),
            "stop_on_breach": options.stop_on_breach}


def resumed(options: RunOptions) -> tuple[RunOptions, journals.Loaded | None]:
    """The options of the journal's run, for ``--resume`` (unchanged otherwise)."""
    if options.resume is None:
        return options, None
    if options.journal is not None:
        raise SettingError("journal", "--resume appends to its own journal; leave out --journal")
    loaded = journals.load(options.resume)
    header = loaded.header
    given = {"engine": options.engine, "vehicle": options.vehicle,
             "world": options.world and str(options.world), "max_time": options.max_time,
             "sim_primitives": [str(p) for p in options.sim_primitives], **assumed(options)}
    for key in JOURNALED:
        # a journal without simulated primitives of its own says nothing of them
        recorded = header.get(key, UNSAID.get(key))
        if key in options.explicit and given[key] != recorded:
            raise Mcl2PnmlError(f"the journal's run has --{key.replace('_', '-')} "
                                f"{recorded}, not {given[key]}",
                                Location(str(options.resume), 1, 1))
    world = Path(header["world"]) if header.get("world") else None
    return replace(options, engine=header["engine"], vehicle=header["vehicle"],
                   max_time=header["max_time"], world=world,
                   sim_primitives=tuple(map(Path, header.get("sim_primitives", []))),
                   **{key: header.get(key, UNSAID[key])
                      for key in ("ack_within", "report_gap", "stop_on_breach")}), loaded


def _vehicle(options: RunOptions) -> tuple[VehicleKind, object]:
    kind = kind_of(options.vehicle)
    if kind.realtime and (options.resume or options.journal):
        raise SettingError("resume" if options.resume else "journal",
                           "a journal replays a vehicle of its own (sim or a script); a real "
                           "vehicle's run cannot be replayed")
    if options.world and not kind.takes_world:
        raise SettingError("world", "a world is for the simulator (--vehicle sim)")
    refuse_sim_primitives(kind, options.sim_primitives)
    if not kind.realtime:
        for name in ("connect",) + _LINK:
            if getattr(options, name) != _DEFAULTS[name]:
                raise SettingError(name, "only for a real vehicle "
                                   "(--vehicle bridge:MAPPING.json --connect HOST:PORT)")
    if options.faults and kind.realtime:
        raise SettingError("faults", "faults are injected into a simulated vehicle (sim, a "
                                     "vehicle model, a script), not a real one")
    if options.faults and (options.journal or options.resume):
        raise SettingError("faults", "a journal does not record injected faults: a run "
                                     "with --faults is replayed by its seed, not resumed")
    # the opening of the link counts against the run's time limit too (wall seconds for a bridge)
    link = LinkOptions(**{name: getattr(options, name) for name in _LINK}, max_time=options.max_time)
    vehicle = kind.build(options.vehicle, options.connect, options.world, link)
    if options.sim_primitives:
        table = dict(vehicle.table)
        for path in options.sim_primitives:
            table = load_file(path, table)
        vehicle.offer(table)
    if options.faults:
        # the stream a campaign draws run SEED's faults from (mcl2pnml.campaign)
        seed = seed_of(options.vehicle) or 0
        vehicle = FaultyVehicle(vehicle, Faults.load(options.faults),
                                random.Random(f"faults-{seed}"))
    return kind, vehicle


#: The options of the live link, as RunOptions and LinkOptions both name them.
_LINK = ("secret", "tls_ca", "tls_cert", "tls_key", "heartbeat", "liveness", "send_timeout",
         "max_line")
_DEFAULTS = {f.name: f.default for f in fields(RunOptions)}


#: A mission's world, by convention: beside it, ``NAME.world.json``; the
#: simulator takes it when no ``--world`` is given (docs/simulator.md).
WORLD_SUFFIX = ".world.json"


def with_world(mission: Path, options: RunOptions) -> RunOptions:
    """The options with the world beside the mission, for the simulator given none.

    Each example of ``examples/`` has the place it is written for (a dock, a
    dam, a patch of sea) beside it, as it has its vehicle script; a world
    given, a resumed run (its journal names its own) or another vehicle
    keep theirs.
    """
    beside = mission.with_name(mission.stem + WORLD_SUFFIX)
    if options.world is not None or options.resume is not None \
            or not kind_of(options.vehicle).takes_world or not beside.is_file():
        return options
    return replace(options, world=beside)


#: A mission's vehicle script, by convention: beside it, ``NAME.vehicle.json``
#: (every example of ``examples/`` but the paper's has one), named when the simulator
#: does not offer a primitive the mission uses.
SCRIPT_SUFFIX = ".vehicle.json"


def _check_primitives(engine: Engine, vehicle, mission: Path, options: RunOptions) -> None:
    """The vehicle must offer every primitive the mission uses (section 2.1)."""
    needed = engine.primitives_used()
    offered = vehicle.primitives
    if offered is not None and needed - offered:
        missing = sorted(needed - offered)[0]
        who, hint = "this vehicle", ""
        if "vehicle" not in options.explicit:
            # the user never chose the simulator: say it was the default, and what to give
            script = mission.with_name(mission.stem + SCRIPT_SUFFIX)
            who = "the simulator (the default vehicle)"
            hint = (". Run it against a vehicle script: "
                    + (f"--vehicle {script}" if script.is_file() else
                       '--vehicle SCRIPT.json ({"PRIMITIVE": ["ok@5", "fail@3", "never"]})'))
        message = (f"the mission uses '{missing}', which {who} does not offer; it offers "
                   f"{', '.join(sorted(offered))}{hint}")
        raise SettingError("vehicle", message)
    vehicle.check_primitives(needed)
    if isinstance(vehicle, LiveVehicle):    # before anything is sent to a real vehicle
        vehicle.check_enables(engine.enable_arguments())


def _journal(mission: Path, options: RunOptions, kind: VehicleKind,
             loaded: journals.Loaded | None):
    """Where the log's lines go besides the log: a new journal, a replay, or nowhere."""
    if options.resume is None and options.journal is None:
        return None
    # the files the run depends on, as they are now: a resume needs them unchanged
    files = {"mission": mission, "vehicle": kind.source(options.vehicle),
             "world": options.world,
             **{f"sim_primitives_{i}": p for i, p in enumerate(options.sim_primitives)}}
    digests = {f"{k}_sha256": journals.digest(f) for k, f in files.items() if f}
    if loaded is not None:
        for key, value in digests.items():
            if loaded.header.get(key) != value:
                raise Mcl2PnmlError(f"{files[key[:-7]]} has changed since this journal was "
                                    "written: its run cannot be resumed",
                                    Location(str(options.resume), 1, 1))
        return journals.Replay(loaded)
    return journals.create(options.journal, {
        "mission": str(mission), "engine": options.engine, "vehicle": options.vehicle,
        "world": options.world and str(options.world), "max_time": options.max_time,
        **({"sim_primitives": [str(p) for p in options.sim_primitives]}
           if options.sim_primitives else {}),
        **assumed(options), **digests})


def run_session(mission: Path, options: RunOptions, make_engine: Callable[[str], Engine], *,
                text: IO[str] | None = None, log_path: Path | None = None,
                note: Callable[[str], None] = lambda line: None) -> Run:
    """Run ``mission`` as ``options`` say; the engine is ``make_engine(options.engine)``.

    ``text`` receives the live log, ``log_path`` the JSON-lines log (written
    whole, atomically, at the end: however the run ends, an error's too), ``note``
    what the user should know on the side (a torn journal line dropped). However
    the run ends, the engine loop's safe stop has disabled every primitive still
    enabled and brought the vehicle to its safe state; SIGINT, SIGTERM and SIGHUP
    end it INTERRUPTED (:mod:`mcl2pnml.runtime.interrupts`).
    """
    beside = with_world(mission, options)
    if beside.world != options.world:   # the user named none: say which world is flown
        note(f"world: {beside.world}, the one beside the mission (--world to give another)")
    options, loaded = resumed(beside)
    assumptions = options.assumptions()     # a bad one is refused before anything is built
    # no output may be a file the run reads, nor the other output (--journal j --log j)
    check_outputs([("journal", options.journal), ("log_path", log_path)],
                  [("the mission", mission), ("the world (--world)", options.world),
                   ("the faults (--faults)", options.faults),
                   ("the vehicle script (--vehicle)", kind_of(options.vehicle).source(
                       options.vehicle)), ("the journal it resumes (--resume)", options.resume)])
    if loaded is not None and loaded.torn:
        note(loaded.torn)
    kind, vehicle = _vehicle(options)
    engine = make_engine(options.engine)
    _check_primitives(engine, vehicle, mission, options)
    sink = _journal(mission, options, kind, loaded)
    jsonl = io.StringIO() if log_path else None
    log = RunLog(text, jsonl, options.transitions, sink)
    engine.on_fire = log.fired
    seen = 0

    def listener(entry) -> None:
        nonlocal seen
        if guard.signum is not None:
            # a signal stopped the run: what follows (its safe stop) is not the mission's,
            # and a journal that ends where the run was stopped can be resumed
            log.journal = None
        log.entry(entry)
        for event, reason in engine.ignored[seen:]:
            log.ignored(event, reason)
        seen = len(engine.ignored)

    result: Run | None = None
    with interrupts.guard() as guard:
        try:
            if kind.realtime:
                if hasattr(vehicle, "log"):     # an autopilot's own lines: what it says, its track
                    vehicle.log = log.vehicle
                try:
                    # opened only now, in the run loop: the mission and mapping are checked,
                    # and a signal while it connects and arms brings it to its safe state
                    result = run_realtime(engine, vehicle, listener=listener,
                                          max_time=options.max_time, open_vehicle=True,
                                          assumptions=assumptions,
                                          stop_on_breach=options.stop_on_breach)
                finally:
                    vehicle.close()
            else:
                result = drive(engine, vehicle, listener=listener, max_time=options.max_time,
                               assumptions=assumptions, stop_on_breach=options.stop_on_breach)
        except BaseException as e:
            if log_path is not None:    # the log of a run that ended in an error, to the error
                log.failed(log.last_t, _error_text(e))
                atomic_write_text(log_path, jsonl.getvalue())
            raise
        for event, reason in result.ignored[seen:]:
            log.ignored(event, reason)
        if result.signum is not None:
            log.journal = None
        log.end(result.time, result.outcome, result.diagnosis)
        if isinstance(sink, journals.Replay) and result.signum is None:
            sink.finish()
        if log_path is not None:
            atomic_write_text(log_path, jsonl.getvalue())
    return result


def _error_text(e: BaseException) -> str:
    return str(e) if isinstance(e, Mcl2PnmlError) else f"{type(e).__name__}: {e}"
