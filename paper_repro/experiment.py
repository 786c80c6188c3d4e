"""Section 3 and Fig. 5 of the paper: the SAUC-E mission run on the simulated AUV.

``examples/sauce.mcl`` (the paper's Algorithm 1) runs on
:class:`~mcl2pnml.runtime.simulator.AUVSimulator` in the paper's 16 x 8 x 5 m tank,
through the Petri-net executor, twice: with the cross on the floor under
the survey path, and without it. With the cross, the survey is aborted when
the camera sees it, the vehicle dives, drops the marker and surfaces;
without it, it surfaces at the end of the survey. Fig. 5 plots the vehicle's
3-D trajectory against the desired one (the path through the set points the
mission gave: the waypoints, then the depths), as the paper's Fig. 5 does
with the DVL's estimate.
"""
from __future__ import annotations

import bisect
from dataclasses import dataclass
from pathlib import Path

from mcl2pnml.runtime.engine import Outcome, run
from mcl2pnml.runtime.executor import PetriEngine
from mcl2pnml.pipeline import compile_file
from mcl2pnml.runtime.simulator import AUVSimulator, World

MISSION = Path(__file__).resolve().parents[1] / "examples" / "sauce.mcl"
CROSS = (10.0, 4.0)


@dataclass
class Trial:
    """One run of the mission: what the vehicle did and what it was asked to do."""

    label: str
    outcome: Outcome
    time: float
    trajectory: list[tuple[float, float, float, float]]   # t, x, y, z
    setpoints: list[tuple[float, float, float, float]]
    markers: list[tuple[float, float]]
    actions: list[str]
    cross: tuple[float, float] | None


def trial(cross: tuple[float, float] | None, label: str, noise: float = 0.03,
          seed: int = 7) -> Trial:
    net = compile_file(MISSION)
    vehicle = AUVSimulator(World(cross=cross, noise=noise, seed=seed))
    result = run(PetriEngine(net), vehicle, max_time=3600)
    actions = [f"{e.kind.value} {e.primitive}" for e in result.entries
               if hasattr(e, "args") and e.kind.value == "enable"]
    return Trial(label, result.outcome, result.time, vehicle.trajectory, vehicle.setpoints,
                 vehicle.markers, actions, cross)


def trials() -> list[Trial]:
    return [trial(CROSS, "cross on the survey path"), trial(None, "no cross")]


def plot(runs: list[Trial], path: Path) -> Path:
    """Fig. 5: the 3-D trajectory of each run against the desired one (depth downwards)."""
    import matplotlib
    matplotlib.use("Agg")   # files only, no display
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(11, 5))
    for k, r in enumerate(runs):
        ax = fig.add_subplot(1, len(runs), k + 1, projection="3d")
        xs, ys, zs = zip(*[(x, y, z) for _, x, y, z in r.trajectory])
        ax.plot(xs, ys, zs, color="tab:blue", lw=1.5, label="vehicle (simulated)")
        # desired: from where the vehicle was when each set point was given, straight to it
        times = [t for t, *_ in r.trajectory]
        for k, (t0, x, y, z) in enumerate(r.setpoints[1:]):
            _, px, py, pz = r.trajectory[min(bisect.bisect_left(times, t0), len(times) - 1)]
            ax.plot([px, x], [py, y], [pz, z], color="tab:red", ls="--", lw=1, marker="o",
                    ms=3, label="desired" if k == 0 else None)
        if r.cross is not None:
            ax.scatter([r.cross[0]], [r.cross[1]], [5.0], marker="x", s=80, color="black",
                       label="cross (floor)")
        for mx, my in r.markers:
            ax.scatter([mx], [my], [5.0], marker="v", s=50, color="tab:green", label="marker")
        ax.set_xlim(0, 16)
        ax.set_ylim(0, 8)
        ax.set_zlim(5, 0)           # depth grows downwards
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_zlabel("depth (m)")
        ax.set_title(f"{r.label}: {r.outcome.value} at t={r.time:.1f} s", fontsize=10)
        ax.legend(fontsize=7, loc="upper left")
    fig.suptitle("Fig. 5. The SAUC-E mission (Algorithm 1) on the simulated AUV, "
                 "16 x 8 x 5 m tank", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def checks(runs: list[Trial]) -> list:
    """The paper's account of the experiment (section 4), each claim against the runs."""
    import math

    from paper_repro.checks import Row

    found, missed = runs
    enabled = [a.split()[1] for a in found.actions]
    rows = []
    distance = (min(math.dist(m, found.cross) for m in found.markers)
                if found.markers and found.cross else math.inf)
    rows.append(Row(0, "sauce.mcl, cross on the path",
                    "the survey is aborted when the cross is found; the vehicle dives, "
                    "drops a marker and surfaces",
                    f"{found.outcome.value} at {found.time:.1f} s; enabled: "
                    + " -> ".join(enabled) + f"; marker {distance:.2f} m from the cross",
                    found.outcome is Outcome.OK
                    and enabled[-3:] == ["KeepDepth", "ReleaseMarker", "KeepDepth"]
                    and enabled.count("GoToWayPoint") < 3 and distance < 2.0
                    and found.trajectory[-1][3] < 0.25))
    m_enabled = [a.split()[1] for a in missed.actions]
    rows.append(Row(0, "sauce.mcl, no cross",
                    "the vehicle surfaces at the end of the survey",
                    f"{missed.outcome.value} at {missed.time:.1f} s; enabled: "
                    + " -> ".join(m_enabled),
                    missed.outcome is Outcome.OK and "ReleaseMarker" not in m_enabled
                    and m_enabled.count("GoToWayPoint") == 2 and m_enabled[-1] == "KeepDepth"
                    and missed.trajectory[-1][3] < 0.25))
    return rows
