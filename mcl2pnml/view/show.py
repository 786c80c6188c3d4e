"""``mcl2pnml show``: a net as one self-contained HTML page, to play the token game.

The page is for teaching Petri-net supervisors: it draws the net as its
static drawing does (:mod:`mcl2pnml.view.drawing`, laid out by
:func:`~mcl2pnml.view.layout.drawn_layout`), each node as large as dot laid it
out with its name inside (:func:`view_json`: no text lies on another), each arc
along dot's route
around the nodes (its bend points), a place that many transitions read or
give back to (a primitive's ON and OFF, a task's MTX) as a small dashed
copy beside each of them, the boxes of the drawing (the primitive of
Fig. 2's task, T1 and T2 of Fig. 4's structures, each instance of a
mission: :func:`~mcl2pnml.view.drawing.instance_clusters`), and it highlights the
fusion places where they meet; a student clicks an
enabled transition to fire it, steps back, resets, and sees the marking and
every P-invariant's value at each step (each must keep its value at M0: a
broken one would be a bug of ours, and is shown in red). A recorded run (the
JSON-lines log of ``mcl2pnml run --log``) can be followed step by step, with
the vehicle's actions and events beside the firings (and a counterexample's
log, ``analyze --counterexamples``, with its notes in the mission's terms), read by
:func:`read_run` or the page's file chooser against one schema (:func:`run_log_schema`);
and a mission or a
task can be switched to its reduced model (Fig. 3 of the paper: every task
started by B, ending in OK, FAIL or ABORTED, without its primitive).

One call at a time. A mission's page opens on the mission's own net, each call
it makes shut in a box named as MCL writes it (:mod:`mcl2pnml.view.calls`, laid
out by :func:`~mcl2pnml.view.layout.call_layouts`, :func:`calls_json`); a box
clicked opens its call, a breadcrumb goes back up, and a box shows whether its
inside runs and how many of its transitions may fire. The header is one row,
the side panels fold (folded on a narrow screen), and at *Fit* on a 1024 x 768
projector or a 1920 x 1080 screen every text of the paper's mission is at least
10 or 12 pixels high (``tests/view/test_show_screens.py``).

Watching a whole mission. *Fit* shows the whole view, and *follow* (on by
default) goes to each firing: to the call it is in, one call at a time; on the
whole net, to the transition and the places it took from and gave to. The
places the last firing changed are ringed and listed + or −; the marking
and the P-invariants can be filtered, and the invariants are one summary
line until opened. Beside the net, a mission's functional form (the
paper's Algorithm 2, section 3.2) is a tree (:func:`tree_data`) whose
nodes the page colours by state, computed from the marking and the firings
alone (:func:`tree_parts`: every structure and call site has the reduced
task's control interface, section 2.3 and Fig. 3), so it holds in the full
and the reduced model alike. A clock plays virtual time as TINA's stepper
does, in the engines' timed semantics (:mod:`mcl2pnml.runtime.executor`): a
time-out (``Timing``, the task's ``t03``) may fire only once it has been
enabled for its delay, its timer kept while it stays enabled and started
again when it is enabled again; the supervisor's steps (:func:`role`: neither
a time-out nor fired by a vehicle event) come first, so *Advance time* is
refused, and the page says why, while one is enabled; *Supervisor until it
waits* takes them in the executor's order (the one enabled longest first, ties
in the net's order, a call entry last) until the mission waits for the
vehicle or a time-out, or has its result, and stops a loop that never settles
after a bounded number of firings. A replayed run sets the clock from its
log, and its steps and the firings are listed with their times.

Playing a mission (docs/show.md). Who fires each transition (its
:func:`role`) is shown: the enabled ones are listed under the supervisor's,
the vehicle's (a primitive's reports and acknowledgements) and the
time-outs, and the drawing gives the vehicle's a thick blue border. *Play*
plays by itself, at a chosen speed: each step, the supervisor until it
waits, then a vehicle event at random (at a later time, before the next
time-out falls due) or time passes to the next time-out; the generator is
seeded, the odds of a goal achieved against failed are the student's, and
an event is chosen less when another undoes it (lost, regained), less the
more often it fired, and far less when it undoes the vehicle's last one (a
goal lost just after it was regained), so that a game reaches the
mission's result. An enabled transition is clicked in a square of at least
28 CSS pixels whatever the zoom (its bar is a few pixels wide at *Fit*). A place's tokens are set by
hand (*edit marking*, or shift-click: an editor beside it), the
P-invariants then naming those that break. A node is dragged where a student
wants it (its arcs drawn straight from there). The drawing as it is shown is
made, by the script, into a standalone SVG document and a PNG image (drawn
on a canvas: an SVG image would be an image to load, which the policy
forbids).
*SVG* and *PNG* download them (a link to a ``blob:`` URL the page mints for
its own Blob). And the reachability graph of a net of up to 2,000 markings
(:mod:`mcl2pnml.view.reachability`) is drawn layered, each edge labelled
with its transition, a marking clicked to play from it (the path from M0 to
it kept and drawn), the strongly connected components as nodes past a few
hundred markings, the current one expanded.

Following a run live (:func:`serve_live`, ``show --live LOG``): the page is
served on loopback under a random token and asks its own origin for the
log's new entries (:class:`LiveLog`: complete lines, checked as
:func:`read_run` checks them, bounded, from the one file first opened, which
must stay the file at its path), playing each as it comes; every connection
is bounded in time and their number capped.

Everything the page needs is inside it: the data as JSON, the script and
the style; it fetches nothing, so it opens from a file, offline, in any
browser. The page itself is ``show_page.html`` beside this module.

Security. Everything that comes from the input (file names, node ids and
names, doc lines, run logs, a mission's arguments in its tree, the places a
marking of the graph names) is data, never markup or code, whoever wrote
it; the page trusts only its own template, script and style:

* the template is filled in one pass (:func:`fill`): a regular expression
  finds its slots, ``__TITLE__``, ``__CSP__`` and ``__DATA__``, and what is put
  in one slot is never scanned again, so no input reaches another slot;
* the title is HTML-escaped text; the data is one JSON document in a
  ``<script type="application/json">`` element, which the browser never
  runs and the page reads with ``JSON.parse``. It is written in ASCII with
  ``<``, ``>``, ``&``, U+2028 and U+2029 as ``\\u`` escapes, so that no string
  can end the element or open an HTML comment (``</script>``, ``<!--``, which
  would put the parser in a state that swallows the page's script), and
  without NaN or infinities, which JSON has not: a run log holding them is
  refused, with the file, line and column (:func:`read_run`);
* the script never makes markup from data: text goes in with
  ``textContent``, the drawing is SVG elements made one by one, and no
  attribute it sets from data is a URL, a style or an event handler; the
  drawing's geometry (positions, bend points, copies, boxes) is sent as
  numbers only, and an arc's path is made of those numbers by the script;
* the one URL the script sets is a download link's, to a ``blob:`` URL that
  ``URL.createObjectURL`` mints for a Blob the page made (its drawing as
  SVG or PNG), never data or a URL from the input;
* a Content-Security-Policy (:func:`csp`) lets run only the page's one
  script and one style, named by their SHA-256 hashes computed here from the
  template (no ``'unsafe-inline'``), and nothing else: ``default-src 'none'``
  (no image, font, frame or connection, not even ``data:``),
  ``connect-src 'none'`` (the live page's ``'self'``: its server, for the
  log's new entries), ``form-action 'none'``, ``base-uri 'none'``, and
  Trusted Types (``require-trusted-types-for 'script'``), so that an HTML
  sink such as ``innerHTML`` would throw in browsers that have them (Chromium
  does). No policy keeps a page from navigating: ``navigate-to`` was dropped
  from the CSP draft and no browser enforces it (Chromium even reports it
  as an error on the console), so it is not written; the page's defence
  against being navigated away is that no input can run script or make a
  link or a form.
"""
from __future__ import annotations

import base64
import errno
import functools
import hashlib
import hmac
import io
import json
import math
import os
import re
import secrets
import stat
import threading
import time
from importlib import resources
from pathlib import Path
from typing import Any, Iterable, Mapping, Protocol, Sequence
from urllib.parse import parse_qs, urlsplit

from mcl2pnml.analysis.structure.invariants import p_invariant_basis
from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import atomic_write_text, read_text
from mcl2pnml.core.jsontext import offsets
from mcl2pnml.core.net import Net, thaw
from mcl2pnml.core.payloads import MissionPlace, TransitionPayload, doc_of, read_transition
from mcl2pnml.core.structure import structure
from mcl2pnml.view.calls import mission_calls, short_label
from mcl2pnml.view.drawing import border_out, instance_clusters
from mcl2pnml.view.layout import Drawn, call_layouts, drawn_layout
from mcl2pnml.view.reachability import reachability_graph

#: Above this many nodes the page would be a heap nobody can read: refused.
MAX_NODES = 5_000
#: How many P-invariants the page checks at each step, at most.
MAX_INVARIANTS = 400


class TreeNode(Protocol):
    """A node of a mission's functional form (the paper's Algorithm 2), as the page's tree
    view shows it: :class:`mcl2pnml.language.functional.Instance` is one. The facade
    hands these over; the view does not import the language."""

    name: str      # the prefix of its instance's node ids in the compiled net
    kind: str      # "call", or the structure (sequence, parallel, ...)
    label: str
    line: int
    parent: int    # index in its list, -1 for a root
    depth: int
    size: int      # nodes in its subtree: in pre-order, this one and the next size-1


#: The places by which the page tells an instance's state (section 2.3: every
#: structure and call site has the reduced task's control interface).
RESULTS = ("OK", "FAIL", "ABORTED")


def tree_data(trees: Sequence[tuple[str, Sequence[TreeNode]]]) -> list[dict[str, Any]]:
    """The functional forms, mission first, as one flat list in pre-order (a list, not
    nested objects: a block of 10,000 statements would nest JSON 10,000 deep)."""
    out: list[dict[str, Any]] = []
    for root, nodes in trees:
        base = len(out)
        out += [{"name": n.name, "kind": n.kind, "label": n.label, "line": n.line,
                 "parent": n.parent + base if n.parent >= 0 else -1, "depth": n.depth,
                 "size": n.size, "root": root} for n in nodes]
    return out


def tree_parts(net: Net, tree: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Where each node of the tree is in ``net``: its instance's places and transitions
    (by index), and the indices of its B and result places.

    The compiler prefixes an instance's node ids with its name and composes
    children before parents, so a fused control place keeps the child's id
    (``Goto-1.OK``, not its parent's slot ``mission.T1_OK``): the node
    ``mission.sequence-1.t2`` is the instance ``mission.sequence-1``'s, as
    :func:`~mcl2pnml.view.drawing.instance_clusters` groups them. The page tells a
    node's state from these alone, so it is right in the full model and in
    the reduced one (Fig. 3), whose tasks differ but whose instances do not.
    """
    places: dict[str, list[int]] = {}
    transitions: dict[str, list[int]] = {}
    index = {p.id: k for k, p in enumerate(net.places)}
    for k, p in enumerate(net.places):
        places.setdefault(p.id.rpartition(".")[0], []).append(k)
    for k, t in enumerate(net.transitions):
        transitions.setdefault(t.id.rpartition(".")[0], []).append(k)
    out = []
    for node in tree:
        name = node["name"]
        part = {"places": places.get(name, []), "transitions": transitions.get(name, [])}
        for role in ("B", *RESULTS):
            part[role] = index.get(f"{name}.{role}")
        out.append(part)
    return out


#: The places whose marking ends a run (the mission's result): the page's *Supervisor
#: until it waits* and its automatic play stop there, as the engines stop the run.
MISSION_RESULTS = tuple(p.id for p in (MissionPlace.OK, MissionPlace.FAIL, MissionPlace.ABORTED))


def role(payload: TransitionPayload, timed: bool) -> str:
    """Who fires a transition, as the executor (:mod:`mcl2pnml.runtime.executor`) reads
    its payload and timing; the page's *Supervisor until it waits*, *Advance time*, its
    automatic play and the list of enabled transitions (by who fires them) follow it:

    * ``"event"``: a vehicle event fires it (its payload names one);
    * ``"entry"``: a call site's ``enter``, a supervisor step taken last: only when no
      other step is enabled, then the first in the net's order;
    * ``"timeout"``: a timed transition (a task's time-out), fired when it has been
      enabled for its delay, once the supervisor has taken every step it can;
    * ``"step"``: the supervisor's other steps, taken at once, the one enabled longest
      first (ties in the net's order), before vehicle events and before time passes.
    """
    if payload.event is not None:
        return "event"
    if payload.entry is not None:
        return "entry"
    return "timeout" if timed else "step"


def variant(net: Net, label: str, tree: Sequence[dict[str, Any]] = (),
            clusters: Mapping[str, Sequence[str]] | None = None,
            labels: Mapping[str, str] | None = None) -> dict[str, Any]:
    """One net as the page draws it: its nodes, its arcs by index, its invariants, where
    the nodes of ``tree`` (:func:`tree_data`) are, its reachability graph, and its views
    (:func:`view_json`): the whole net, and with ``labels`` (a mission's calls named as
    MCL writes them: :func:`mcl2pnml.pipeline.call_labels`) each of its calls alone.

    ``clusters`` are the boxes of a template's drawing (its slots: the
    primitive of Fig. 2's task, T1 and T2 of Fig. 4); None, each instance
    of a compiled mission in its box.
    """
    nodes = len(net.places) + len(net.transitions)
    if nodes > MAX_NODES:
        raise Mcl2PnmlError(f"net '{net.name}' has {nodes:,} nodes; a page draws at most "
                            f"{MAX_NODES:,} (compile it to PNML or DOT instead)")
    drawn = drawn_layout(net, "auto", clusters)
    boxes = instance_clusters(net) if clusters is None else dict(clusters)
    kept = border_out(net, boxes)
    box_of = {n: name for name, members in kept.items() for n in members}
    index = {p.id: k for k, p in enumerate(net.places)}
    # the places a box had and border_out took out: where boxes meet
    border = {n for members in boxes.values() for n in members} - set(box_of)
    places = [{"id": p.id, "label": p.label,
               "tokens": net.initial[p.id], "interface": p.interface,
               "fusion": p.id in border, "group": box_of.get(p.id),
               "doc": _text(doc_of(p.payload))} for p in net.places]
    transitions = []
    for t in net.transitions:
        payload = read_transition(t)
        kind = ("event" if payload.event is not None else "timeout" if t.timing is not None
                else "action" if payload.actions else "call" if payload.entry is not None
                else "")
        transitions.append({
            "id": t.id, "label": t.label,
            "timing": str(t.timing) if t.timing is not None else None, "kind": kind,
            "role": role(payload, t.timing is not None),
            # what the vehicle reports by it (on, achieved, failed, off): automatic play's odds
            "event": payload.event.kind.value if payload.event is not None else None,
            # the timed token game's delay: enabled this long before it may fire
            "delay": t.timing.earliest if t.timing is not None else 0,
            "latest": t.timing.latest if t.timing is not None else None,
            "group": box_of.get(t.id), "doc": _text(payload.doc),
            "pre": [[index[a.source], a.weight] for a in net.pre[t.id]
                    if a.kind.value == "normal"],
            "read": [[index[a.source], a.weight] for a in net.pre[t.id]
                     if a.kind.value == "read"],
            "post": [[index[a.target], a.weight] for a in net.post[t.id]]})
    basis = p_invariant_basis(structure(net))[:MAX_INVARIANTS]
    invariants = [{"terms": [[index[p], c] for p, c in y.items()],
                   "value": sum(c * net.initial[p] for p, c in y.items())} for y in basis]
    groups = {name: drawn.boxes.get(name) or _around(drawn, members)
              for name, members in sorted(kept.items())}
    return {"label": label, "name": net.name, "places": places, "transitions": transitions,
            "results": [index[p] for p in MISSION_RESULTS if p in index],
            "invariants": invariants, "tree": tree_parts(net, tree),
            "whole": view_json(net, drawn, groups={n: (n, r) for n, r in groups.items()}),
            "calls": None if labels is None else calls_json(net, labels),
            "graph": reachability_graph(net).to_json()}


def _around(drawn: Drawn, members: Sequence[str]) -> tuple[float, float, float, float]:
    """A box around its nodes where the layout drew none (the layered layout)."""
    xs = [drawn.positions[n][0] for n in members if n in drawn.positions]
    ys = [drawn.positions[n][1] for n in members if n in drawn.positions]
    return (min(xs) - 28, min(ys) - 34, max(xs) + 28, max(ys) + 34) if xs else (0, 0, 0, 0)


#: A node's size where no layout gave one (the layered layout): a place's radius, a
#: transition's half width and half height, a text's size (points).
PLACE_RADIUS, HALF_WIDTH, HALF_HEIGHT, TEXT_SIZE = 16.0, 10.0, 10.0, 12


def view_json(net: Net, drawn: Drawn, *, groups: Mapping[str, tuple[str, Any]] = {},
              shut: Mapping[str, tuple[float, ...]] = {}, names: Mapping[str, str] = {},
              frames: Sequence[tuple] = (), box_arcs: Sequence[tuple] = ()
              ) -> dict[str, Any]:
    """A view of ``net`` as the page draws it, from its layout ``drawn``: each node drawn
    (its index, where, its size, its text and font size: as dot laid it out, the text
    inside), each copy of a place likewise, each arc between drawn nodes (its
    transition, role and rank in the transition's ``pre``, ``read`` or ``post``, the
    copy of its place it is drawn to, its bend points as one flat list), the open boxes
    (``groups``: name -> its title and rectangle), the shut ones (``shut``, the text in
    each ``names``, with ``box_arcs`` between them and their places) and the grey frames
    of calls."""
    index = {p.id: k for k, p in enumerate(net.places)}
    tindex = {t.id: k for k, t in enumerate(net.transitions)}
    pos, sizes, texts = drawn.positions, drawn.sizes, drawn.texts

    def text(node: str, default: str) -> list[Any]:
        return list(texts.get(node, (default, TEXT_SIZE)))
    copies, number = [], {}
    for c, (place, (x, y)) in drawn.copies.items():
        number[c] = len(copies)
        copies.append([index[place], x, y, sizes.get(c, (PLACE_RADIUS,))[0],
                       *text(c, net.place_index[place].label)])
    # the arcs drawn to a copy: (place, transition) or (transition, place) -> the copy
    to_copy: dict[tuple[str, str], str] = {}
    for a, b in drawn.bends:
        if a in drawn.copies:
            to_copy[(drawn.copies[a][0], b)] = a
        elif b in drawn.copies:
            to_copy[(a, drawn.copies[b][0])] = b
    arcs = []
    for t in net.transitions:
        if t.id not in pos:
            continue
        ranks = {"pre": 0, "read": 0, "post": 0}
        for a in (*net.pre[t.id], *net.post[t.id]):
            way = "post" if a.source == t.id else a.kind.value.replace("normal", "pre")
            k, ranks[way] = ranks[way], ranks[way] + 1
            place = a.target if way == "post" else a.source
            c = to_copy.get((a.source, a.target))
            if place not in pos and c is None:
                continue        # a place this view does not draw (the caller's)
            key = (a.source, a.target) if c is None else \
                ((c, a.target) if way != "post" else (a.source, c))
            arcs.append([tindex[t.id], way, k, -1 if c is None else number[c],
                         [v for point in drawn.bends.get(key, ()) for v in point]])
    return {
        "places": [[index[p.id], *pos[p.id], sizes.get(p.id, (PLACE_RADIUS,))[0],
                    *text(p.id, p.label)] for p in net.places if p.id in pos],
        "transitions": [[tindex[t.id], *pos[t.id],
                         *sizes.get(t.id, (HALF_WIDTH, HALF_HEIGHT)), text(t.id, t.label)[0]]
                        for t in net.transitions if t.id in pos],
        "copies": copies, "arcs": arcs,
        "groups": [[name, title, *rect] for name, (title, rect) in groups.items()],
        "boxes": [[name, *rect, names.get(name, name)] for name, rect in shut.items()],
        "boxArcs": [[list(shut).index(b), index[p], way, [v for pt in pts for v in pt]]
                    for b, p, way, pts in box_arcs],
        "frames": [list(rect) for rect in frames]}


def calls_json(net: Net, labels: Mapping[str, str]) -> dict[str, Any] | None:
    """A mission's calls as the page opens them one at a time (:mod:`mcl2pnml.view.calls`):
    its root, each call's name as MCL writes it, its callers and callees, what runs
    inside its box (:meth:`~mcl2pnml.view.calls.Calls.within`), and its view
    (:func:`view_json`); None where dot could not lay them out."""
    calls = mission_calls(net)
    laid = call_layouts(net, calls, labels)
    if laid is None or not calls.roots:
        return None
    views = {}
    for name, view in laid.items():
        views[name] = view_json(
            net, view.drawn, shut=view.shut, names=view.names,
            frames=list(view.frames.values()),
            box_arcs=view.box_arcs,
            groups={n: (short_label(labels.get(n, n)), r) for n, r in view.drawn.boxes.items()})
    return {"root": calls.roots[0], "labels": {n: labels.get(n, n) for n in calls.clusters},
            "callers": calls.callers, "callees": calls.callees,
            "within": {n: calls.within(n) for n in calls.clusters}, "views": views}


def _text(doc: Any) -> str | None:
    """A doc line as the page shows it: text (a payload's doc may be any JSON value)."""
    if doc is None or isinstance(doc, str):
        return doc
    return json.dumps(thaw(doc), ensure_ascii=False)


class _NotFinite(ValueError):
    """A run log's NaN, Infinity or number too large for a float."""

    def __init__(self, token: str):
        super().__init__(token)
        self.token = token


def _no_constant(token: str) -> Any:
    raise _NotFinite(token)


def _finite(token: str) -> float:
    x = float(token)
    if not math.isfinite(x):
        raise _NotFinite(token)
    return x


#: JSON strings (skipped) and the tokens a JSON line may spell a non-finite number with.
_TOKEN = re.compile(r'"(?:[^"\\]|\\.)*"|-?Infinity|NaN|-?\d+(?:\.\d+)?(?:[eE][+-]?\d+)?')


def _column(line: str, token: str) -> int:
    """Where ``token`` first stands outside a string in a JSON line, from 1."""
    for m in _TOKEN.finditer(line):
        if m.group() == token:
            return m.start() + 1
    return 1


#: A run log is read up to this many bytes (``show --run``, the page's file chooser, ``--live``).
MAX_RUN_LOG = 64 << 20


def run_log_schema() -> dict[str, Any]:
    """The JSON Schema of a run log's line (``runlog.schema.json`` beside this module): the
    types of the keys the page reads. :func:`run_line` checks each line with it, and the
    page's file chooser with the same schema, which the page carries in its data."""
    return json.loads(resources.files("mcl2pnml.view").joinpath("runlog.schema.json")
                      .read_text("utf-8"))


class RunEntries(list):
    """A run log's entries, and the line each stands at (``lines``)."""

    lines: list[int]


def read_run(path: str | Path) -> RunEntries:
    """The entries of a JSON-lines run log (``mcl2pnml run --log``); bad lines are errors.

    JSON has no NaN nor infinity, and the page's data holds none: ``NaN``,
    ``Infinity`` and numbers too large for a float (``1e999``), which
    Python's ``json`` would accept, are refused where they stand, as is a
    line whose keys do not have the types :func:`run_log_schema` gives them
    (a ``fire`` that is not a transition id, a string). A log of more than
    :data:`MAX_RUN_LOG` bytes is refused before it is read.
    """
    entries = RunEntries()
    entries.lines = []
    text = read_text(path, "run log", MAX_RUN_LOG)
    for n, line in enumerate(text.split("\n"), 1):
        entry = run_line(line, str(path), n)
        if entry is not None:
            entries.append(entry)
            entries.lines.append(n)
    return entries


def _dotted(path: Iterable[Any]) -> str:
    """A value's path in a line as the messages say it: ``ignored.event``, ``setpoint[1]``."""
    out = ""
    for key in path:
        out += f"[{key}]" if isinstance(key, int) else (f".{key}" if out else str(key))
    return out


def run_fault(entry: Any) -> tuple[tuple[Any, ...], str] | None:
    """The first fault of a line's value against :func:`run_log_schema`, in the schema's
    order (as the page finds it): where it stands (its path) and what the message says;
    None if there is none."""
    error = next(_validator().iter_errors(entry), None)
    if error is None:
        return None
    path = tuple(error.absolute_path)
    if not path and error.validator == "type":
        return path, "a run log's line is a JSON object"
    if error.validator == "required":
        missing = next(k for k in error.validator_value if k not in error.instance)
        return path, (f"a run log's '{_dotted(path + (missing,))}' is missing: "
                      f"{error.schema['description']}")
    return path, f"a run log's '{_dotted(path)}' is {error.schema['description']}"


@functools.lru_cache(maxsize=1)
def _validator() -> Any:
    """The schema's validator, made once."""
    # jsonschema, 47 ms (python -X importtime): only when a run log is checked, not for
    # every page this module makes
    from jsonschema import Draft202012Validator
    return Draft202012Validator(run_log_schema())


def run_line(line: str, path: str, n: int) -> dict[str, Any] | None:
    """Line ``n`` of a run log as :func:`read_run` reads it: None if blank, else its entry
    (an error if it is not a run log's JSON object)."""
    if not line.strip():
        return None
    try:
        entry = json.loads(line, parse_constant=_no_constant, parse_float=_finite)
    except json.JSONDecodeError as e:
        raise Mcl2PnmlError(f"not a JSON line: {e.msg}", Location(path, n, e.colno, line)) from None
    except _NotFinite as e:
        what = ("a number too large for a run log (it would be infinite)"
                if e.token[-1].isdigit() else "not a JSON value (JSON has no NaN or infinity)")
        raise Mcl2PnmlError(f"'{e.token}' is {what}",
                            Location(path, n, _column(line, e.token), line)) from None
    except (ValueError, RecursionError) as e:   # an integer of thousands of digits, deep nesting
        raise Mcl2PnmlError(f"not a run log's JSON line: {e}", Location(path, n, 1, line)) from None
    try:
        fault = run_fault(entry)
    except RecursionError:       # nested too deeply for the check (json read it)
        raise Mcl2PnmlError("not a run log's JSON line: nested too deeply",
                            Location(path, n, 1, line)) from None
    if fault is not None:
        where, message = fault
        column = offsets(line).get(where, 0) + 1
        raise Mcl2PnmlError(message, Location(path, n, column, line))
    return entry


def check_run(net: Net, entries: Iterable[dict[str, Any]], path: str) -> None:
    """Every transition a run log fires must be one of the net's (the message names its
    line where :func:`read_run` kept it)."""
    lines = getattr(entries, "lines", None)
    for n, entry in enumerate(entries):
        fired = entry.get("fire")
        if fired is not None and fired not in net.transition_index:
            raise Mcl2PnmlError(f"the run fires '{fired}', which is no transition of "
                                f"'{net.name}': a log of another mission?",
                                Location(path, lines[n]) if lines else Location(path))


# -- the page ------------------------------------------------------------------------------

#: The template's slots: ``__NAME__``, each filled once, all in one pass.
SLOTS = ("TITLE", "CSP", "DATA")
_SLOT = re.compile("__(" + "|".join(SLOTS) + ")__")
#: The page's own script and style, which the CSP names by their hashes.
_INLINE = re.compile(r"<(script|style)>(.*?)</\1>", re.S)
#: In JSON, these can only stand inside strings; as ``\u`` escapes they cannot
#: end the data's element (``</script``), open a comment (``<!--``) or, in the
#: script of an older browser, end a line (U+2028, U+2029).
_JSON_IN_HTML = str.maketrans({"<": "\\u003c", ">": "\\u003e", "&": "\\u0026",
                               "\u2028": "\\u2028", "\u2029": "\\u2029"})


def template() -> str:
    """The page's template, ``show_page.html``."""
    return resources.files("mcl2pnml.view").joinpath("show_page.html").read_text("utf-8")


def sha256_source(text: str) -> str:
    """A CSP hash source: ``'sha256-…'`` of an inline element's text, as browsers hash it."""
    digest = hashlib.sha256(text.encode("utf-8")).digest()
    return f"'sha256-{base64.b64encode(digest).decode('ascii')}'"


def csp(html: str, live: bool = False) -> str:
    """The Content-Security-Policy of the page made from the template ``html``: its one
    script and one style, by hash; nothing else. ``live``: the page served by
    :func:`serve_live`, which may also fetch from its own origin (the log's new lines)."""
    inline = {"script": [], "style": []}
    for m in _INLINE.finditer(html):
        inline[m.group(1)].append(m.group(2))
    if len(inline["script"]) != 1 or len(inline["style"]) != 1:
        raise AssertionError("the page's template has one script and one style")
    connect = "'self'" if live else "'none'"
    return ("default-src 'none'; "
            f"script-src {sha256_source(inline['script'][0])}; "
            f"style-src {sha256_source(inline['style'][0])}; "
            f"img-src 'none'; connect-src {connect}; font-src 'none'; "
            "frame-src 'none'; "
            "object-src 'none'; worker-src 'none'; manifest-src 'none'; "
            "form-action 'none'; base-uri 'none'; "
            "require-trusted-types-for 'script'; trusted-types 'none'")


def json_for_html(value: Any) -> str:
    """``value`` as JSON that may stand inside a ``<script>`` element: ASCII, no ``<``,
    ``>`` or ``&``, no NaN or infinity (a ``ValueError``)."""
    text = json.dumps(value, separators=(",", ":"), ensure_ascii=True, allow_nan=False)
    return text.translate(_JSON_IN_HTML)


def html_text(text: str) -> str:
    """Text as HTML character data (and attribute value): markup characters escaped,
    lone surrogates (an undecodable file name) replaced, so that it encodes as UTF-8."""
    text = re.sub("[\ud800-\udfff]", "\ufffd", text)
    return (text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
            .replace('"', "&quot;").replace("'", "&#39;"))


def fill(html: str, slots: dict[str, str]) -> str:
    """The template with its slots filled, in one pass: what a slot gets is not
    scanned again, so a value that spells a slot's name stays as it is."""
    return _SLOT.sub(lambda m: slots[m.group(1)], html)


def page(title: str, variants: list[dict[str, Any]],
         run: list[dict[str, Any]] | None = None,
         tree: Sequence[dict[str, Any]] = (), live: bool = False) -> str:
    """The HTML page: the template with the data inside it. ``live``: the page that
    :func:`serve_live` serves, which follows the run as its log is written."""
    try:
        data = json_for_html({"title": title, "variants": variants, "run": run,
                              "tree": list(tree), "live": live,
                              # the page's file chooser checks a log as read_run does
                              "runSchema": run_log_schema(), "runLogBytes": MAX_RUN_LOG})
    except ValueError as e:   # read_run and variant let no NaN through: a bug of ours
        raise Mcl2PnmlError(f"the page's data is not JSON: {e}") from None
    html = template()
    return fill(html, {"TITLE": html_text(title), "CSP": csp(html, live), "DATA": data})


def save_page(path: str | Path, title: str, variants: list[dict[str, Any]],
              run: list[dict[str, Any]] | None = None,
              tree: Sequence[dict[str, Any]] = ()) -> Path:
    """Write the page, whole or not at all."""
    atomic_write_text(path, page(title, variants, run, tree))
    return Path(path)


# -- following a run as it is written (show --live) -----------------------------------------

#: A live log's line may have this many bytes at most: a longer one is refused.
LIVE_LINE = 64 * 1024
#: One answer to the page carries this many entries at most (it asks again at once).
LIVE_ENTRIES = 500
#: A live log is followed up to this many bytes; past them, no further.
LIVE_BYTES = MAX_RUN_LOG
#: The server stops this long after it started, whatever the run does.
LIVE_MAX_SECONDS = 24 * 3600
#: Seconds a connection may stay silent (a socket time-out): then it is closed.
LIVE_IDLE = 10.0
#: Seconds a request may take to arrive whole, however its bytes trickle in (one deadline).
LIVE_REQUEST = 20.0
#: Seconds an answer may take to be written (a page that does not read it is dropped).
LIVE_SEND = 20.0
#: Connections served at once, each by a thread; one more is closed at once.
LIVE_CONNECTIONS = 16


class LiveLog:
    """A run log as it is written: its complete lines read as they come, each checked as
    :func:`read_run` and :func:`check_run` check a log, up to :data:`LIVE_BYTES`. A bad
    line ends the reading, and is what the page is told."""

    def __init__(self, net: Net, path: str | Path):
        self.net, self.path = net, Path(path)
        self.entries: list[dict[str, Any]] = []
        self.offset = 0          # bytes read, up to the end of the last complete line
        self.lines = 0
        self.error: str | None = None
        self.outcome = False     # the run's outcome line has been read
        self.fd: int | None = None   # the log followed, open from the first poll that finds it
        self._lock = threading.RLock()

    def _fail(self, message: str) -> None:
        self.error = message
        self.close()

    def close(self) -> None:
        """Let go of the log's file (its descriptor)."""
        with self._lock:
            if self.fd is not None:
                os.close(self.fd)
                self.fd = None

    def _same_file(self) -> os.stat_result | None:
        """The followed file's status, once it is checked to be still the file at the path:
        the same device and inode, not a symbolic link put in its place (which would
        have the page follow another file, and quote it). None: the reading is over."""
        try:
            st = os.fstat(self.fd)
            there = os.lstat(self.path)
        except OSError as e:
            return self._fail(f"{self.path}: the run log is gone while it was followed "
                              f"({e.strerror})")
        if stat.S_ISLNK(there.st_mode) or (there.st_dev, there.st_ino) != (st.st_dev, st.st_ino):
            return self._fail(f"{self.path}: the run log was replaced by another file while it "
                              "was followed (a symbolic link, or a new file): it is not "
                              "followed further")
        return st

    def _open(self) -> bool:
        """Open the log (not through a symbolic link, never blocking on a FIFO): False if it
        is not there yet, or cannot be followed (the error said)."""
        flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0) | \
            getattr(os, "O_CLOEXEC", 0)
        try:
            self.fd = os.open(self.path, flags)
        except FileNotFoundError:
            return False         # not written yet: the run has not started
        except OSError as e:
            if e.errno == errno.ELOOP:
                self._fail(f"{self.path}: the run log is a symbolic link; give the file it "
                           "points to")
            else:
                self._fail(f"{self.path}: cannot read the run log: {e.strerror}")
            return False
        if not stat.S_ISREG(os.fstat(self.fd).st_mode):
            self._fail(f"{self.path}: the run log is not a regular file")
            return False
        return True

    def poll(self) -> None:
        """Read the complete lines written since the last poll, from the file first opened,
        checked at every reading to be still the one at the path."""
        if self.error is not None or self.outcome:
            return
        if self.fd is None and not self._open():
            return
        st = self._same_file()
        if st is None:
            return
        if st.st_size < self.offset:
            return self._fail(f"{self.path}: the run log was cut short while it was followed")
        if self.offset >= LIVE_BYTES:
            return self._fail(f"{self.path}: the run log passed {LIVE_BYTES:,} bytes: it is "
                              f"not followed further")
        data = os.pread(self.fd, min(st.st_size, LIVE_BYTES) - self.offset, self.offset)
        end = data.rfind(b"\n") + 1
        if end == 0 and len(data) > LIVE_LINE:
            return self._fail(f"{self.path}:{self.lines + 1}: a run log's line of more than "
                              f"{LIVE_LINE:,} bytes")
        for raw in data[:end].split(b"\n")[:-1]:
            self.lines += 1
            self.offset += len(raw) + 1
            try:
                if len(raw) > LIVE_LINE:
                    raise Mcl2PnmlError(f"a run log's line of more than {LIVE_LINE:,} bytes",
                                        Location(str(self.path), self.lines))
                try:
                    line = raw.decode("utf-8")
                except UnicodeDecodeError as e:
                    raise Mcl2PnmlError(f"not UTF-8: {e.reason}",
                                        Location(str(self.path), self.lines)) from None
                entry = run_line(line, str(self.path), self.lines)
                if entry is None:
                    continue
                fired = entry.get("fire")
                if fired is not None and fired not in self.net.transition_index:
                    raise Mcl2PnmlError(f"the run fires '{fired}', which is no transition of "
                                        f"'{self.net.name}': a log of another mission?",
                                        Location(str(self.path), self.lines))
            except Mcl2PnmlError as e:
                return self._fail(str(e))
            self.entries.append(entry)
            if "outcome" in entry:
                self.outcome = True
                self.close()
                return

    def answer(self, start: int) -> tuple[dict[str, Any], bool]:
        """The page's answer from entry ``start`` on, and whether it carries the run's
        last entry (its outcome), or the error that ends the reading."""
        with self._lock:
            self.poll()
            start = max(0, min(start, len(self.entries)))
            entries = self.entries[start:start + LIVE_ENTRIES]
            end = start + len(entries)
            finished = end == len(self.entries) and (self.outcome or self.error is not None)
            return ({"entries": entries, "next": end, "done": finished,
                     "error": self.error}, finished)


class _RequestReader:
    """The raw reading of one connection's request, within one deadline: each ``recv`` is
    given what is left of it (a :class:`TimeoutError` once it has passed, which
    :mod:`http.server` answers by closing the connection), and at most ``idle`` seconds of
    silence, so a client that trickles its request a byte at a time cannot hold its
    thread longer than ``seconds``."""

    def __init__(self, sock: Any, seconds: float, idle: float):
        self.sock, self.clock, self.idle = sock, time.monotonic, idle
        self.deadline = self.clock() + seconds

    def reader(self) -> Any:
        """A buffered reader (``rfile``) over this deadline."""
        owner = self

        class Raw(io.RawIOBase):
            def readable(self) -> bool:
                return True

            def readinto(self, buffer: Any) -> int:
                left = owner.deadline - owner.clock()
                if left <= 0:
                    raise TimeoutError("the request took longer than its deadline")
                owner.sock.settimeout(min(left, owner.idle))
                return owner.sock.recv_into(buffer)
        return io.BufferedReader(Raw())


def _bounded_server(handler: Any, port: int, connections: int) -> Any:
    """A threading HTTP server on 127.0.0.1:``port`` that serves at most ``connections``
    connections at once (a thread each): one more is closed at once, unanswered."""
    from http.server import ThreadingHTTPServer   # 47 ms: as _live_handler says

    places = threading.BoundedSemaphore(connections)

    class Server(ThreadingHTTPServer):
        daemon_threads = True

        def process_request(self, request: Any, client_address: Any) -> None:
            if not places.acquire(blocking=False):
                self.shutdown_request(request)
                return
            try:
                super().process_request(request, client_address)
            except BaseException:
                places.release()
                raise

        def process_request_thread(self, request: Any, client_address: Any) -> None:
            try:
                super().process_request_thread(request, client_address)
            finally:
                places.release()

    return Server(("127.0.0.1", port), handler)


def _live_handler(body: bytes, token: str, log: LiveLog, idle: float, request: float,
                  finished_at: list[float]) -> type:
    """The request handler of :func:`serve_live`: the page ``body`` and the log's entries,
    to a request that holds ``token`` and names the loopback host; the time the run's
    outcome was first served appended to ``finished_at``."""
    # http.server (47 ms, python -X importtime): only when a page is served live, not for
    # every page or run log this module makes or checks
    from http.server import BaseHTTPRequestHandler
    policy = csp(template(), live=True)

    class Handler(BaseHTTPRequestHandler):
        server_version = "mcl2pnml"
        sys_version = ""
        timeout = idle           # the socket's time-out: a silent connection is closed

        def setup(self) -> None:
            super().setup()
            self.rfile.close()       # the reader made by setup, replaced by one with a deadline
            self.rfile = _RequestReader(self.connection, request, idle).reader()

        def log_message(self, format: str, *args: Any) -> None:   # quiet: the URL has the token
            pass

        def _send(self, status: int, ctype: str, data: bytes) -> None:
            self.connection.settimeout(LIVE_SEND)    # sendall's time-out is for all of it
            self.send_response(status)
            self.send_header("Content-Type", ctype)
            self.send_header("Content-Length", str(len(data)))
            self.send_header("Content-Security-Policy", policy)
            self.send_header("X-Content-Type-Options", "nosniff")
            self.send_header("Cache-Control", "no-store")
            self.send_header("Referrer-Policy", "no-referrer")
            self.send_header("Cross-Origin-Resource-Policy", "same-origin")
            self.end_headers()
            if self.command != "HEAD":
                self.wfile.write(data)

        def do_GET(self) -> None:
            url = urlsplit(self.path)
            host = self.headers.get("Host", "")
            bound = self.server.server_address[1]
            _, tok, rest = (url.path.split("/", 2) + ["", ""])[:3]
            if (host not in (f"127.0.0.1:{bound}", f"localhost:{bound}")
                    or not hmac.compare_digest(tok.encode(), token.encode())):
                self._send(403, "text/plain; charset=utf-8", b"forbidden\n")
            elif rest == "" and url.path.endswith("/"):
                self._send(200, "text/html; charset=utf-8", body)
            elif rest == "log":
                try:
                    start = max(0, int(parse_qs(url.query).get("from", ["0"])[0][:12]))
                except ValueError:
                    start = 0
                answer, finished = log.answer(start)
                if finished and not finished_at:
                    finished_at.append(time.monotonic())
                self._send(200, "application/json",
                           json.dumps(answer, allow_nan=False).encode("ascii"))
            else:
                self._send(404, "text/plain; charset=utf-8", b"not found\n")

        do_HEAD = do_GET

    return Handler


def serve_live(html: str, log: LiveLog, port: int = 0, linger: float = 10.0,
               ready: Any = print, max_seconds: float = LIVE_MAX_SECONDS,
               idle: float = LIVE_IDLE, request: float = LIVE_REQUEST,
               connections: int = LIVE_CONNECTIONS, stop: Any = None) -> None:
    """Serve the live page ``html`` (:func:`page` with ``live``) and the new entries of
    ``log`` on loopback (127.0.0.1) only, at ``port`` (0: one the system picks), under a
    random token: ``ready`` is given the page's URL, which holds it; a request without it
    (or naming another host: DNS rebinding) gets 403. Returns on Ctrl-C, ``linger``
    seconds after the page was handed the run's outcome (or the error that stops the
    reading), or after ``max_seconds``.

    Every connection is bounded: silent for ``idle`` seconds, or its request not all there
    ``request`` seconds after it connected, it is closed and its thread ends; an answer
    not written within :data:`LIVE_SEND` seconds is dropped; at most ``connections`` are
    served at once (HTTP/1.0: one request a connection). ``stop``, a
    :class:`threading.Event`, stops the server when set (the command stops on Ctrl-C)."""
    token = secrets.token_urlsafe(24)
    finished_at: list[float] = []
    handler = _live_handler(html.encode("utf-8"), token, log, idle, request, finished_at)
    server = _bounded_server(handler, port, connections)
    bound = server.server_address[1]
    started = time.monotonic()
    stop = stop or threading.Event()

    def watch() -> None:          # the run's end served, then linger (or told to): stop
        while True:
            told = stop.wait(0.1)
            now = time.monotonic()
            if told or (finished_at and now - finished_at[0] >= linger) or \
                    now - started >= max_seconds:
                server.shutdown()
                return

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    ready(f"http://127.0.0.1:{bound}/{token}/")
    try:
        server.serve_forever(poll_interval=0.1)
    except KeyboardInterrupt:
        pass
    finally:
        stop.set()
        server.server_close()
        log.close()
