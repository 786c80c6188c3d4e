"""Fig. 5 again, from a real autopilot's own track: the SAUC-E mission flown on ArduSub.

Section 3 of the paper runs Algorithm 1 on the real vehicle and plots, in
Fig. 5, the navigation's estimate against the set points. Here the mission
is flown on ArduSub (``mcl2pnml run examples/sauce.mcl --vehicle mavlink
--connect tcp:127.0.0.1:5760 --log RUN.jsonl``, docs/ardusub.md) and the
figure is drawn from the run's log alone: the autopilot's EKF position
(``track`` lines, in the world's frame), the targets it was given
(``setpoint`` lines), where the marker was released (``marker``), and the
outcome. Nothing is simulated here but what the log says was::

    python -m paper_repro.ardusub CROSS.jsonl [NO_CROSS.jsonl] -o fig5-ardusub.png
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.runtime.engine import Outcome
from mcl2pnml.view.show import read_run

from paper_repro.experiment import CROSS, Trial, plot


def _point(entry: dict, key: str, size: int, where: Location) -> list[float]:
    value = entry.get(key)
    if not isinstance(value, list) or len(value) < size or \
            not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise Mcl2PnmlError(f"'{key}' is a list of {size} numbers", where)
    return [float(v) for v in value[:size]]


def trial_from_log(path: str | Path, label: str,
                   cross: tuple[float, float] | None) -> Trial:
    """The run of a log written by ``run --vehicle mavlink --log``, as Fig. 5 plots it."""
    trajectory, setpoints, markers, actions = [], [], [], []
    outcome, end = None, 0.0
    for n, entry in enumerate(read_run(path), 1):
        where = Location(str(path), n, 1)
        t = entry.get("t", 0.0)
        if not isinstance(t, (int, float)) or isinstance(t, bool):
            raise Mcl2PnmlError("'t' is a number of seconds", where)
        if "track" in entry:
            trajectory.append((float(t), *_point(entry, "track", 3, where)))
        elif "setpoint" in entry:
            setpoints.append((float(t), *_point(entry, "setpoint", 3, where)))
        elif "marker" in entry:
            markers.append(tuple(_point(entry, "marker", 2, where)))
        elif entry.get("action") == "enable":
            actions.append(f"enable {entry.get('primitive')}")
        elif "outcome" in entry:
            try:
                outcome = Outcome.from_json(entry["outcome"])
            except (ValueError, KeyError, TypeError):
                raise Mcl2PnmlError(f"unknown outcome {entry['outcome']!r}", where) from None
            end = float(t)
    if outcome is None or not trajectory:
        raise Mcl2PnmlError("not the log of an autopilot's whole run: it needs its track "
                            "and its outcome (run --vehicle mavlink --log)", Location(str(path)))
    return Trial(label, outcome, end, trajectory, setpoints or [trajectory[0]], markers,
                 actions, cross)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m paper_repro.ardusub",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("cross", type=Path, help="the log of the run with the cross")
    parser.add_argument("no_cross", type=Path, nargs="?",
                        help="the log of the run without it (a world with \"cross\": null)")
    parser.add_argument("-o", "--output", type=Path, default=Path("fig5-ardusub.png"))
    args = parser.parse_args(argv)
    try:
        runs = [trial_from_log(args.cross, "ArduSub, cross on the survey path", CROSS)]
        if args.no_cross:
            runs.append(trial_from_log(args.no_cross, "ArduSub, no cross", None))
    except Mcl2PnmlError as e:
        print(e, file=sys.stderr)
        return 2
    plot(runs, args.output, vehicle="vehicle (ArduSub's EKF)",
         title="flown on ArduSub (software in the loop)")
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
