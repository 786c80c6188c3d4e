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
class Flown:
    """One run: its seed, how it ended and when."""

    seed: int
    outcome: str
    time: float


def fly_batch(mission: str, model: str, engine: str, seeds: list[int],
              max_time: float) -> list[Flown]:
    """Fly the runs of ``seeds`` (a task of a worker)."""
    from mcl2pnml.runtime.engine import run
    from mcl2pnml.runtime.vehicle_model import Draw, ModelVehicle
    make, vehicle_model = _prepared(mission, model, engine)
    out = []
    for seed in seeds:
        r = run(make(), ModelVehicle(vehicle_model, Draw(random.Random(seed))),
                max_time=max_time)
        out.append(Flown(seed, r.outcome.value, float(r.time)))
    return out


#: What a worker has compiled, by mission, model and engine (and their files' times):
#: the batches of one campaign compile the mission once per worker.
_PREPARED: dict[tuple, tuple] = {}


def _prepared(mission: str, model: str, engine: str) -> tuple[Callable, object]:
    import os

    from mcl2pnml.language.checker import check
    from mcl2pnml.language.compiler import compile_checked
    from mcl2pnml.language.parser import parse_file
    from mcl2pnml.runtime.executor import PetriEngine
    from mcl2pnml.runtime.reference import ReferenceEngine
    from mcl2pnml.runtime.vehicle_model import VehicleModel
    key = (mission, model, engine, os.stat(mission).st_mtime_ns, os.stat(model).st_mtime_ns)
    found = _PREPARED.get(key)
    if found is None:
        checked = check(parse_file(mission))
        if engine == "petri":
            make = PetriEngine(compile_checked(checked)).clone
        else:
            def make():
                return ReferenceEngine(checked)
        _PREPARED.clear()
        found = _PREPARED[key] = (make, VehicleModel.load(model))
    return found


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
        if self.sprt is not None:
            out["test"] = {"hypothesis": f"P(OK) >= {self.sprt.target:g}",
                           "decided": self.sprt.decided, "after_runs": self.sprt.after}
        return out


def _z(confidence: float) -> float:
    from statistics import NormalDist
    return NormalDist().inv_cdf(0.5 + confidence / 2)


def fly(mission: Path, model: Path, runs: int, *, engine: str = "petri", seed: int = 0,
        confidence: float = 0.99, target: float | None = None, workers: int | None = None,
        scheduler: str | None = None, max_time: float = 24 * 3600.0,
        progress: Callable[[int, int], None] | None = None) -> Campaign:
    """Fly the campaign (the module's documentation) and return its runs in seed order."""
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise Mcl2PnmlError("a campaign runs on Dask: pip install 'dask[distributed]'") \
            from None
    campaign = Campaign(confidence, sprt=Sprt(target, confidence) if target else None)
    batches = [list(range(seed + k, seed + min(k + BATCH, runs))) for k in range(0, runs, BATCH)]
    args = (str(mission.resolve()), str(model.resolve()), engine)
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
        futures = {client.submit(fly_batch, *args, batch, max_time, pure=False,
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
    """The runs as a table: Parquet (``.parquet``, with pyarrow) or CSV."""
    from mcl2pnml.core.files import atomic_write_bytes
    rows = [(r.seed, r.outcome, r.time) for r in campaign.runs]
    if path.suffix == ".parquet":
        try:
            import io

            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            raise Mcl2PnmlError("a Parquet table needs pyarrow (pip install pyarrow); "
                                "or write .csv") from None
        table = pa.table({"seed": [r[0] for r in rows], "outcome": [r[1] for r in rows],
                          "time": [r[2] for r in rows]})
        sink = io.BytesIO()
        pq.write_table(table, sink)
        atomic_write_bytes(path, sink.getvalue())
        return
    lines = ["seed,outcome,time"] + [f"{s},{o},{t:g}" for s, o, t in rows]
    atomic_write_bytes(path, ("\n".join(lines) + "\n").encode())


def plot(campaign: Campaign, path: Path, title: str) -> None:
    """The outcomes' frequencies with their intervals, and the end times' histogram."""
    import io

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mcl2pnml.core.files import atomic_write_bytes
    data = campaign.as_json()
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    names = list(data["outcomes"])
    freq = [data["outcomes"][o]["frequency"] for o in names]
    low = [f - data["outcomes"][o]["interval"][0] for o, f in zip(names, freq)]
    high = [data["outcomes"][o]["interval"][1] - f for o, f in zip(names, freq)]
    left.bar(names, freq, yerr=[low, high], capsize=6, color="#4c78a8")
    left.set_ylim(0, 1)
    left.set_title(f"outcomes of {data['runs']:,} runs ({campaign.confidence:.0%} intervals)")
    ended = [r.time for r in campaign.runs if r.outcome in ("OK", "FAIL", "ABORTED")]
    right.hist(ended, bins=40, color="#f58518")
    right.set_xlabel("end time (s)")
    right.set_title("end times")
    fig.suptitle(title)
    fig.tight_layout()
    sink = io.BytesIO()
    fig.savefig(sink, format=path.suffix.lstrip(".") or "png")
    plt.close(fig)
    atomic_write_bytes(path, sink.getvalue())


def lines(campaign: Campaign, mission: str) -> Iterable[str]:
    data = campaign.as_json()
    yield (f"{mission}: {data['runs']:,} simulated runs "
           f"({campaign.confidence:.0%} Wilson intervals):")
    for o, d in data["outcomes"].items():
        low, high = d["interval"]
        yield f"  {o:<9} {d['runs']:>7,}  {d['frequency']:.4f}  [{low:.4f}, {high:.4f}]"
    t = data["end_time"]
    if t:
        yield (f"  end time: mean {t['mean']:.2f} s (± {t['mean_interval_halfwidth']:.2f}), "
               f"standard deviation {t['std']:.2f} s; 5% by {t['p5']:g} s, half by "
               f"{t['p50']:g} s, 95% by {t['p95']:g} s")
    if "test" in data:
        test = data["test"]
        yield (f"  {test['hypothesis']}: " + (f"decided {test['decided']} after "
                                              f"{test['after_runs']:,} runs"
                                              if test["decided"] else "not decided"))
