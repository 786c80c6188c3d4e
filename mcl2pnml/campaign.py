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

The figures: each ending's frequency with its Wilson score interval, the end
times' mean, spread and quantiles, and optionally Wald's sequential
probability ratio test of "P(OK) >= target", which stops the campaign as soon
as it is decided at the asked confidence (Wald, *Sequential Analysis*, 1947).
"""
from __future__ import annotations

import math
import random
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

from mcl2pnml.core.errors import Mcl2PnmlError

#: Runs per task sent to a worker.
BATCH = 500
#: How long a scheduler may take to answer, in seconds.
CONNECT_TIMEOUT = 5
#: The indifference region of the sequential test, either side of its target.
INDIFFERENCE = 0.02


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
    from analysis.observers import Watcher
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
    import os

    from mcl2pnml.language.checker import check
    from mcl2pnml.language.compiler import compile_checked
    from mcl2pnml.language.parser import parse_file
    from mcl2pnml.runtime.executor import PetriEngine
    from mcl2pnml.runtime.reference import ReferenceEngine
    key = (mission, fleet, engine, os.stat(mission).st_mtime_ns,
           *(os.stat(f).st_mtime_ns for f in fleet.files()))
    found = _PREPARED.get(key)
    if found is None:
        # not bounded again: the facade read it within --max-mission-size before any batch
        checked = check(parse_file(mission))
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
    from dataclasses import replace

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

    confidence: float = 0.99
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
    from statistics import NormalDist
    return NormalDist().inv_cdf(0.5 + confidence / 2)


def fly(mission: Path, fleet: Fleet, runs: int, *, engine: str = "petri", seed: int = 0,
        confidence: float = 0.99, target: float | None = None, workers: int | None = None,
        scheduler: str | None = None, max_time: float = 24 * 3600.0,
        properties: tuple = (),
        progress: Callable[[int, int], None] | None = None) -> Campaign:
    """Fly the campaign (the module's documentation) and return its runs in seed order,
    each judged on ``properties`` (compiled on the mission's net: the Petri-net engine's
    markings are read)."""
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise Mcl2PnmlError("a campaign runs on Dask: pip install 'dask[distributed]'") \
            from None
    campaign = Campaign(confidence, sprt=Sprt(target, confidence) if target else None,
                        properties=tuple(p.name for p in properties), fleet=fleet)
    batches = [list(range(seed + k, seed + min(k + BATCH, runs))) for k in range(0, runs, BATCH)]
    args = (str(mission.resolve()), fleet, engine)
    tracks_below = seed + TRACKS if fleet.model is None else -1
    cluster = None
    try:
        if scheduler is None:
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=50)
            client = Client(cluster)
        else:
            client = Client(scheduler, timeout=f"{CONNECT_TIMEOUT}s")
    except OSError as e:
        raise Mcl2PnmlError(f"cannot reach the Dask scheduler {scheduler or '(local)'} "
                            f"within {CONNECT_TIMEOUT} s: {e}") from None
    try:
        # keys of this campaign alone: a scheduler shared with other campaigns (another
        # user's, another mission) must never take one's batch for another's
        tag = uuid.uuid4().hex
        futures = {client.submit(fly_batch, *args, batch, max_time, tuple(properties),
                                 tracks_below, pure=False,
                                 key=f"mcl2pnml-runs-{tag}-{batch[0]}"): batch[0]
                   for batch in batches}
        arrived: dict[int, list[Flown]] = {}
        order = [b[0] for b in batches]
        nxt = 0
        for future in as_completed(futures):
            first = futures[future]
            if first in arrived:            # a batch counted already (a retried task)
                continue
            try:
                arrived[first] = future.result()
            except Exception as e:          # noqa: BLE001 (a worker's error, whatever it is)
                if future.status == "cancelled" or client.status != "running":
                    raise Mcl2PnmlError(f"the Dask scheduler was lost after {len(campaign.runs):,} "
                                        "runs; nothing was written") from None
                raise Mcl2PnmlError(f"the runs from seed {first} failed on a worker: "
                                    f"{type(e).__name__}: {e}") from None
            while nxt < len(order) and order[nxt] in arrived and not campaign.done:
                for flown in arrived.pop(order[nxt]):
                    campaign.add(flown)
                    if campaign.done:
                        break
                nxt += 1
            if progress:
                progress(len(campaign.runs), runs)
            if campaign.done:
                break
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return campaign


def write_table(campaign: Campaign, path: Path) -> None:
    """The runs as a table: Parquet (``.parquet``, with pyarrow) or CSV; a column per
    property watched, ``fails_NAME`` (true, false, or empty: not judged)."""
    from mcl2pnml.core.files import atomic_write_bytes
    columns: dict[str, list] = {"seed": [r.seed for r in campaign.runs],
                                "outcome": [r.outcome for r in campaign.runs],
                                "time": [r.time for r in campaign.runs]}
    for k, name in enumerate(campaign.properties):
        columns[f"fails_{name}"] = [r.fails[k] for r in campaign.runs]
    if path.suffix == ".parquet":
        try:
            import io

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
    import io

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mcl2pnml.core.files import atomic_write_bytes
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
    fig.savefig(sink, format=path.suffix.lstrip(".") or "png")
    plt.close(fig)
    atomic_write_bytes(path, sink.getvalue())


def _map(ax, fleet: Fleet, runs: list[Flown]) -> None:
    """The world seen from above (the tank, the cross, the dock, the obstacles) and the
    runs' tracks, each in its outcome's colour."""
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


def lines(campaign: Campaign, mission: str) -> Iterable[str]:
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
