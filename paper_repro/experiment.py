"""Section 3 and Fig. 5 of the paper: the SAUC-E mission run on the simulated AUV.

``examples/sauce.mcl`` (the paper's Algorithm 1) runs on
:class:`~mcl2pnml.runtime.simulator.AUVSimulator` in the paper's 16 x 8 x 5 m tank,
through the Petri-net executor, twice: with the cross on the floor under
the survey path, and without it. With the cross, the survey is aborted when
the camera sees it, the vehicle dives, drops the marker and surfaces;
without it, it surfaces at the end of the survey. Fig. 5 plots the vehicle's
trajectory against the desired one (the path through the set points the
mission gave: the waypoints, then the depths), as the paper's Fig. 5 does
with the DVL's estimate: seen from above and as depth over time.
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


#: The survey's waypoints, ``WayPoint_1`` and ``WayPoint_2`` of examples/sauce.mcl (x, y).
WAYPOINTS = ((10.0, 0.0), (10.0, 8.0))


def plot(runs: list[Trial], path: Path, vehicle: str = "vehicle (simulated)",
         title: str = "on the simulated AUV") -> Path:
    """Fig. 5, one row per run: the top view (x-y, to scale: the tank, the waypoints,
    the cross, the markers dropped) and the depth over time (depth downwards), the
    vehicle against what it was asked (the set points of section 3).

    Two flat views rather than one 3-D perspective, in which a 2 m depth read as
    4.5 m: each axis here is read off its own scale.
    """
    import matplotlib
    matplotlib.use("Agg")   # files only, no display
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    width, length, depth = World().tank
    fig, axes = plt.subplots(len(runs), 2, figsize=(12, 4.2 * len(runs)), squeeze=False,
                             gridspec_kw={"width_ratios": [1.25, 1]})
    for (top, side), r in zip(axes, runs):
        ts, xs, ys, zs = zip(*r.trajectory)
        # desired: from where the vehicle was when each set point was given, straight to it
        legs = []
        for t0, x, y, z in r.setpoints[1:]:
            k = min(bisect.bisect_left(ts, t0), len(ts) - 1)
            legs.append(((xs[k], ys[k]), (x, y), t0, z))
        top.add_patch(Rectangle((0, 0), width, length, fill=False, lw=1.2, color="gray",
                                label=f"tank {width:g} x {length:g} m"))
        for k, ((px, py), (x, y), _, _) in enumerate(legs):
            top.plot([px, x], [py, y], color="tab:red", ls="--", lw=1,
                     label="desired" if k == 0 else None)
        top.plot(xs, ys, color="tab:blue", lw=1.5, label=vehicle)
        top.plot([xs[0]], [ys[0]], "o", color="tab:blue", ms=5)
        for k, (wx, wy) in enumerate(WAYPOINTS, 1):
            top.plot([wx], [wy], "D", color="tab:red", ms=6, label="waypoints" if k == 1 else None)
            top.annotate(f"WayPoint_{k}", (wx, wy), textcoords="offset points",
                         xytext=(6, 6 if wy < length / 2 else -12), fontsize=8)
        if r.cross is not None:
            top.plot([r.cross[0]], [r.cross[1]], "x", ms=10, mew=2.5, color="black",
                     label="cross (on the floor)")
        for k, (mx, my) in enumerate(r.markers):
            top.plot([mx], [my], "v", ms=8, color="tab:green",
                     label="marker dropped" if k == 0 else None)
        top.set_xlim(-0.5, width + 0.5)
        top.set_ylim(-0.5, length + 0.5)
        top.set_aspect("equal")
        top.set_xlabel("x (m)")
        top.set_ylabel("y (m)")
        top.set_title(f"{r.label}: top view", fontsize=10)
        top.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
        # depth over time, the set depths as steps from the time each was given
        side.plot(ts, zs, color="tab:blue", lw=1.5, label=vehicle)
        steps_t = [t0 for _, _, t0, _ in legs] + [ts[-1]]
        steps_z = [z for *_, z in legs]
        side.step(steps_t, steps_z + steps_z[-1:], where="post", color="tab:red", ls="--",
                  lw=1, label="desired depth")
        side.set_ylim(depth, 0)           # depth grows downwards
        side.set_xlim(0, ts[-1])
        side.set_xlabel("time (s)")
        side.set_ylabel("depth (m)")
        side.set_title(f"depth: {r.outcome.value} at t = {r.time:.1f} s", fontsize=10)
        side.grid(alpha=0.3)
        side.legend(fontsize=7, loc="lower right")
    fig.suptitle(f"Fig. 5. The SAUC-E mission (Algorithm 1) {title}, "
                 f"{width:g} x {length:g} x {depth:g} m tank", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
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
