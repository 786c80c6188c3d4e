"""``mcl2pnml show WHAT``: the token-game page of a mission, a net or a template, written, or
served on loopback following a run as it is logged."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mcl2pnml import pipeline
from mcl2pnml.commands.common import MISSION_SIZE
from mcl2pnml.core.errors import visible
from mcl2pnml.core.files import atomic_write_text, check_outputs
from mcl2pnml.core.net import Net
from mcl2pnml.core.progress import Announcement, Notes
from mcl2pnml.core.settings import UsageProblem

#: Seconds the live page is served after it was handed the run's outcome, unless told.
LINGER = 10.0


@dataclass(frozen=True)
class ShowOptions:
    """``show``'s settings, by the names of its options (``--help`` says each)."""

    #: where the page goes (None: NAME.html)
    output: Path | None = None
    #: a run to follow: a log of ``run --log``
    run_log: Path | None = None
    #: also the reachability graph the page draws, as JSON
    graph_json: Path | None = None
    #: serve the page on loopback following the run this log is being written with
    live_log: Path | None = None
    #: with ``live_log``: the port (0: one the system picks)
    port: int = 0
    linger: float = LINGER
    net_id: str | None = None
    lenient: bool = False
    max_mission_size: str = MISSION_SIZE


@dataclass(frozen=True)
class ShowOutcome:
    """The page written (None: served), and the reachability graph's JSON if written."""

    page: Path | None
    graph: dict[str, Any] | None = None

    def lines(self) -> list[str]:
        return []

    def as_json(self) -> dict[str, Any]:
        return {"page": None if self.page is None else str(self.page)}


def show(what: str, options: ShowOptions = ShowOptions(), *,
         notes: Notes | None = None) -> ShowOutcome:
    """``mcl2pnml show`` with ``options``: the page written, or with ``live_log`` served
    until Ctrl-C or ``linger`` seconds after the run's outcome was shown."""
    o, notes = options, Notes() if notes is None else notes
    if o.live_log is None and (o.port, o.linger) != (ShowOptions.port, ShowOptions.linger):
        raise UsageProblem("--port and --linger go with --live")
    if o.live_log is not None and any(path is not None for path in (o.output, o.run_log,
                                                                    o.graph_json)):
        raise UsageProblem("--live serves the page: leave out -o, --run and --graph-json")
    if o.live_log is not None:
        shown = pipeline.show_nets(what, with_run=True, net_id=o.net_id, lenient=o.lenient,
                                   max_mission_size=o.max_mission_size)

        _serve(shown, o, Announcement(notes, f"serving {shown.title} on ",
                                      f" , following {o.live_log} (Ctrl-C stops)"))
        return ShowOutcome(None)
    shown = pipeline.show_nets(what, with_run=o.run_log is not None, net_id=o.net_id,
                               lenient=o.lenient, max_mission_size=o.max_mission_size)
    output = o.output or Path(f"{shown.title}.html")
    check_outputs([("output", output), ("graph_json", o.graph_json)],
                  [("the run log (--run)", o.run_log),
                   ("the net or mission", what if Path(what).is_file() else None)])
    pipeline.save_show_page(output, shown, o.run_log)
    notes(f"wrote {visible(str(output))}: {shown.nets[0][0].summary()}")
    graph = None
    if o.graph_json is not None:
        graph = save_reachability_json(shown.nets[0][0], o.graph_json)
        notes(f"wrote {o.graph_json}: " + (f"{len(graph['markings']):,} markings, "
                                           f"{len(graph['edges']):,} edges"
                                           if "markings" in graph else graph["reason"]))
    return ShowOutcome(output, graph)


def _serve(shown: pipeline.Shown, o: ShowOptions, ready: Announcement) -> None:
    """Serve the token-game page of ``shown`` on loopback, following the run of ``live_log``
    as it is written (:func:`mcl2pnml.view.show.serve_live`): ``ready`` is given the
    page's URL; returns on Ctrl-C or ``linger`` seconds after the run's end was served."""
    from mcl2pnml.view.show import LiveLog, page, serve_live   # graphviz, 65 ms: only show
    tree = pipeline.drawn(shown)
    html = page(shown.title, shown.drawn, None, tree, live=True)
    serve_live(html, LiveLog(shown.nets[0][0], o.live_log), port=o.port, linger=o.linger,
               ready=ready)


def save_reachability_json(net: Net, path: Path) -> dict[str, Any]:
    """Write the reachability graph the page draws (:mod:`mcl2pnml.view.reachability`)
    to ``path`` as JSON, with the place and transition ids its indices refer to, or
    why there is none (``reason``); returns what was written."""
    # the explorers, numpy 0.1 s: only a page's graph
    from mcl2pnml.view.reachability import reachability_graph
    graph = reachability_graph(net).to_json()
    graph["places"] = [p.id for p in net.places]
    graph["transitions"] = [t.id for t in net.transitions]
    atomic_write_text(path, json.dumps(graph, ensure_ascii=False) + "\n")
    return graph
