"""``mcl2pnml campaign MISSION``: the mission flown many times on Dask (:mod:`mcl2pnml.campaign`),
with a vehicle model or on the kinematic simulator, faults injected if asked; each
ending's frequency with its interval, the end times, how often each property holds."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator

from mcl2pnml import campaign as campaigns
from mcl2pnml.campaign import CONFIDENCE, Campaign, SchedulerTimeouts
from mcl2pnml.commands.common import ENGINE, MISSION_SIZE, PROPERTIES_SIZE, mission_net, \
    properties_file
from mcl2pnml.core.bounds import MAX_PROPERTY_ATOMS, MAX_RUN_TIME
from mcl2pnml.core.files import check_outputs
from mcl2pnml.core.progress import Notes
from mcl2pnml.core.settings import SettingError

#: Runs of a campaign, unless told (``--runs``).
RUNS = 1000


@dataclass(frozen=True)
class CampaignOptions:
    """``campaign``'s settings, by the names of its options (``--help`` says each)."""

    #: the vehicle model the runs draw their answers from (None: the simulator)
    model: Path | None = None
    #: the simulator's world (None: MISSION.world.json beside it, else the default)
    world: Path | None = None
    faults: Path | None = None
    properties: str | None = None
    max_props_size: str = PROPERTIES_SIZE
    max_atoms: int = MAX_PROPERTY_ATOMS
    runs: int = RUNS
    engine: str = ENGINE
    #: run k draws with seed SEED+k
    seed: int = 0
    confidence: float = CONFIDENCE
    #: stop as soon as P(OK) >= target is decided (Wald's sequential test)
    target: float | None = None
    #: processes of the local cluster (None: one per core)
    workers: int | None = None
    #: a user's Dask scheduler (tcp://HOST:PORT) instead of a local cluster
    scheduler: str | None = None
    scheduler_timeout: SchedulerTimeouts = SchedulerTimeouts()
    table: Path | None = None
    plot: Path | None = None
    max_time: float = MAX_RUN_TIME
    max_mission_size: str = MISSION_SIZE


@dataclass(frozen=True)
class CampaignOutcome:
    """A campaign flown: its runs and figures (:class:`mcl2pnml.campaign.Campaign`), of the
    mission named ``mission``."""

    flown: Campaign
    mission: str

    def as_json(self) -> dict[str, Any]:
        return self.flown.as_json()

    def lines(self) -> list[str]:
        """What ``campaign`` prints: each ending's frequency with its interval, the end times,
        the properties, the first run not OK, the sequential test."""
        return list(_lines(self.flown, self.mission))


def campaign(mission: Path, options: CampaignOptions = CampaignOptions(), *,
             notes: Notes | None = None,
             progress: Callable[[int, int], None] | None = None) -> CampaignOutcome:
    """``mcl2pnml campaign`` with ``options``: ``runs`` simulated runs of a mission, each
    judged on the mission's properties if asked; the table and the plot written if asked.
    Every file is read and checked here, before any run; ``progress`` hears the runs done
    (and the runs asked) as batches end."""
    o, notes = options, Notes() if notes is None else notes
    world, props = _checked(mission, o, notes)
    fleet = campaigns.Fleet(*(str(f.resolve()) if f is not None else None
                              for f in (o.model, world, o.faults)))
    flown = campaigns.fly(mission, fleet, o.runs, engine=o.engine, seed=o.seed,
                          confidence=o.confidence, target=o.target, workers=o.workers,
                          scheduler=o.scheduler, max_time=o.max_time, properties=props,
                          timeouts=o.scheduler_timeout, progress=progress)
    first = next((r for r in flown.runs if r.outcome != "OK"), None)
    if first is not None:     # the command as the user wrote the files
        given = campaigns.Fleet(*(str(f) if f is not None else None
                                  for f in (o.model, world, o.faults)))
        flown.again = (first.seed, first.outcome, given.replay(str(mission), first.seed))
    if o.table is not None:
        campaigns.write_table(flown, o.table)
        notes(f"wrote {o.table}")
    if o.plot is not None:
        what = o.model.name if o.model is not None else \
            (world.name if world is not None else "the default world")
        what += f", faults of {o.faults.name}" if o.faults is not None else ""
        campaigns.plot(flown, o.plot, f"{mission.name} with {what}")
        notes(f"wrote {o.plot}")
    return CampaignOutcome(flown, mission.name)


def _checked(mission: Path, o: CampaignOptions, notes: Notes) -> tuple[Path | None, tuple]:
    """Every input of the campaign read and checked, with its place, not on a worker: the
    world flown in (the one beside the mission if none is given) and the properties."""
    # the simulator, the vehicle model, the faults: the runtime, 30 ms; only a campaign
    from mcl2pnml.runtime.executor import PetriEngine
    from mcl2pnml.runtime.faults import Faults
    from mcl2pnml.runtime.session import WORLD_SUFFIX
    from mcl2pnml.runtime.simulator import AUVSimulator, World
    from mcl2pnml.runtime.vehicle_model import VehicleModel
    world = o.world
    if mission.suffix != ".mcl":
        raise SettingError("mission", f"'{mission}' is not a mission (.mcl)")
    if o.scheduler is not None and o.workers is not None:
        raise SettingError("workers", "the scheduler's cluster has its own workers")
    if o.model is not None and world is not None:
        raise SettingError("world", "a world is for the simulator; a vehicle model answers "
                                    "without one (give --vehicle-model or --world)")
    if o.properties is not None and o.engine != "petri":
        raise SettingError("properties", "properties are judged on the net's markings: "
                                         "--engine petri")
    beside = mission.with_name(mission.name[:-len(".mcl")] + WORLD_SUFFIX)
    if o.model is None and world is None and beside.is_file():
        world = beside
        notes(f"world: {world}, the one beside the mission (--world to give another)")
    extra = None if o.properties is None else properties_file(mission, o.properties)
    check_outputs([("table", o.table), ("plot", o.plot)],
                  [("the mission", mission), ("the vehicle model", o.model),
                   ("the world (--world)", world), ("the faults (--faults)", o.faults),
                   ("the properties file (--properties)", extra)])
    campaigns.check_outputs(o.table, o.plot)
    net, props = mission_net(mission, extra, o)
    used = PetriEngine(net).primitives_used()
    if o.model is not None:
        VehicleModel.load(o.model).check_primitives(used)
    else:
        flown_in = World.load(world) if world else World()
        offered = AUVSimulator(flown_in).primitives
        if not flown_in.noise and o.faults is None:
            notes("every run flies alike: the world has no noise and no faults are injected "
                  '("noise" in the world file, or --faults, makes runs differ)')
        if used - offered:
            raise SettingError("model", f"the mission uses '{sorted(used - offered)[0]}', "
                                        "which the simulator does not offer (it offers "
                                        f"{', '.join(sorted(offered))}): fly it with a "
                                        "vehicle model")
    if o.faults is not None:
        Faults.load(o.faults).check_primitives(used)
    return world, props


def _lines(campaign: Campaign, mission: str) -> Iterator[str]:
    data = campaign.as_json()
    fleet = campaign.fleet
    vehicle = (f"the vehicle model {Path(fleet.model).name}" if fleet.model else
               f"the simulator in {Path(fleet.world).name}" if fleet.world else
               "the simulator in its default world")
    if fleet.faults:
        vehicle += f", with the faults of {Path(fleet.faults).name}"
    yield (f"{mission}: {data['runs']:,} simulated runs with {vehicle} "
           f"({campaign.confidence:.0%} Wilson intervals):")
    for o, d in data["outcomes"].items():
        low, high = d["interval"]
        yield f"  {o:<9} {d['runs']:>7,}  {d['frequency']:.4f}  [{low:.4f}, {high:.4f}]"
    t = data["end_time"]
    if t:
        yield (f"  end time: mean {t['mean']:.2f} s (± {t['mean_interval_halfwidth']:.2f}), "
               f"standard deviation {t['std']:.2f} s; 5% by {t['p5']:g} s, half by "
               f"{t['p50']:g} s, 95% by {t['p95']:g} s")
    if "properties" in data:
        yield "  the properties (how often each held, on the runs that ended or stalled):"
        width = max(len(p["property"]) for p in data["properties"])
        for p in data["properties"]:
            if p["holds"] is None:
                yield f"    {p['property']:<{width}}  not judged (every run hit the time limit)"
                continue
            low, high = p["interval"]
            first = p["first_failing_seed"]
            yield (f"    {p['property']:<{width}}  {p['holds']:.4f}  [{low:.4f}, {high:.4f}]"
                   + (f"  first fails on seed {first}" if first is not None else ""))
    if campaign.again is not None:
        seed, outcome, command = campaign.again
        yield f"  the first run not OK, {outcome}, flies again alone: {command}"
    if "test" in data:
        test = data["test"]
        yield (f"  {test['hypothesis']}: " + (f"decided {test['decided']} after "
                                              f"{test['after_runs']:,} runs"
                                              if test["decided"] else "not decided"))
