"""TAPAAL's own file format (``.tapn``, and ``.xml`` files saved by TAPAAL), read as a P/T net.

TAPAAL saves timed-arc Petri nets in the namespace of the old HU-Berlin
PNML (``http://www.informatik.hu-berlin.de/top/pnml/ptNetb``), with the
net type ``P/T net`` and everything as attributes: a place's tokens in
``initialMarking="2"`` and its age invariant in ``invariant="< inf"``, an
arc's weight in ``weight``, its time interval in ``inscription="[0,inf)"``
and its kind in ``type`` (``timed`` input, ``normal`` output,
``tapnInhibitor``, ``transport``; older files have ``inputArc``,
``outputArc``, ``inhibitorArc`` and ``transportArc`` elements instead, and
often no namespace). Read as a standard PNML file, every marking would
silently be 0.

A file whose time cannot matter (every invariant ``< inf``, every interval
``[0,inf)``) is the P/T net it draws, and is read with its markings and
weights. Everything else is refused with its place in the file: time that
matters, inhibitor and transport arcs, colours, and a model of several
components, which TAPAAL composes through shared places and transitions
(pick one with ``--net``, knowingly, or export the composed net as PNML from
TAPAAL).
"""
from __future__ import annotations

from mcl2pnml.core.errors import PnmlError, raise_all
from mcl2pnml.core.bounds import MAX_TOKENS, MAX_TOKENS_TEXT, natural_at_most
from mcl2pnml.core.net import Arc, Marking, Net, Place, Transition

NAMESPACE = "http://www.informatik.hu-berlin.de/top/pnml/ptNetb"
#: An age invariant and an interval under which time cannot matter.
UNTIMED_INVARIANT = {"<inf", "<=inf"}
UNTIMED_INTERVAL = {"[0,inf)", "[0,inf]"}
#: Arc elements of older files, and the ``type`` each stands for.
OLD_ARCS = {"inputArc": "timed", "outputArc": "normal", "inhibitorArc": "tapninhibitor",
            "transportArc": "transport"}


#: Arc kinds refused whatever they join (an old transport arc names three nodes).
REFUSED = {"tapninhibitor", "inhibitor", "transport"}
#: Arc types only TAPAAL's own format has.
TAPAAL_TYPES = {"timed", "transport", "tapninhibitor"}


def is_tapaal(root) -> bool:
    """Whether a document is in TAPAAL's own format.

    Its root's namespace says so, but older files (and TAPAAL's own test
    models) have none: then a place with its marking in an attribute, an arc
    element of the old kinds, or an arc of a type only TAPAAL has.
    """
    if isinstance(root.tag, str) and root.tag.startswith("{" + NAMESPACE + "}"):
        return True
    for el in root.iter("{*}place", *(f"{{*}}{name}" for name in OLD_ARCS), "{*}arc"):
        name = _local(el)
        if (name in OLD_ARCS or (name == "place" and el.get("initialMarking") is not None)
                or (name == "arc" and (el.get("type") or "").lower() in TAPAAL_TYPES)):
            return True
    return False


def _local(el) -> str:
    return el.tag.rsplit("}", 1)[-1] if isinstance(el.tag, str) else ""


class _Tapaal:
    def __init__(self, src):
        self.src = src
        self.errors: list[PnmlError] = []
        self.timed = False   # time that matters is said once: the whole net is timed

    def timed_error(self, el, message: str) -> None:
        if not self.timed:
            self.timed = True
            self.error(el, message + ": a timed-arc net, in which time changes what can "
                                     "fire; mcl2pnml reads untimed P/T nets")

    def error(self, el, message: str) -> None:
        self.errors.append(PnmlError(message, self.src.locate(el)))

    def natural(self, el, attr: str, default: int, minimum: int) -> int:
        text = el.get(attr)
        if text is None:
            return default
        digits = text.strip()
        if digits.isdigit() and digits.isascii() and natural_at_most(digits, MAX_TOKENS) is None:
            shown = digits if len(digits) <= 30 else f"(a number of {len(digits):,} digits)"
            self.error(el, f"{_local(el)} '{el.get('id')}': {attr} {shown} is too large: "
                           f"markings and weights go up to {MAX_TOKENS_TEXT}")
            return default
        try:
            n = int(digits) if len(digits) <= 30 else -1
        except ValueError:
            n = -1
        if n < minimum:
            kind = "a natural number" if minimum == 0 else "a positive integer"
            self.error(el, f"{_local(el)} '{el.get('id')}': {attr} must be {kind}, "
                           f"not '{text}'")
            return default
        return n

    def net(self, net_el) -> Net:
        places: dict[str, Place] = {}
        transitions: dict[str, Transition] = {}
        marking: dict[str, int] = {}
        arcs: dict[tuple[str, str], int] = {}
        arc_els = []
        for el in net_el:
            name = _local(el)
            if name in ("place", "transition"):
                if not (el.get("id") or "").strip():
                    self.error(el, f"a {name} without an id")
                    continue
                if el.get("id") in places or el.get("id") in transitions:
                    self.error(el, f"duplicate id '{el.get('id')}'")
                    continue
            if name == "place":
                pid = el.get("id")
                invariant = (el.get("invariant") or "< inf").replace(" ", "")
                if invariant not in UNTIMED_INVARIANT:
                    self.timed_error(el, f"place '{pid}' has the age invariant "
                                         f"'{el.get('invariant')}'")
                places[pid] = Place(pid, el.get("name"))
                tokens = self.natural(el, "initialMarking", 0, 0)
                if tokens:
                    marking[pid] = tokens
            elif name == "transition":
                transitions[el.get("id")] = Transition(el.get("id"), el.get("name"))
            elif name == "arc" or name in OLD_ARCS:
                arc_els.append((el, name))
        for el, name in arc_els:   # every node first: arcs may come before their ends
            src, dst = el.get("source"), el.get("target")
            kind = (el.get("type") or OLD_ARCS.get(name, "")).lower()
            if kind in REFUSED:   # said for what it is, whatever its ends
                self.arc(el, name, arcs)
                continue
            ends = places.keys() | transitions.keys()
            if (src in places) == (dst in places) or not {src, dst} <= ends:
                self.error(el, f"arc from '{src}' to '{dst}' does not join a place and a "
                               "transition of this net")
                continue
            self.arc(el, name, arcs)
        raise_all(self.errors)
        return Net(net_el.get("id") or "net", tuple(places.values()),
                   tuple(transitions.values()),
                   tuple(Arc(s, d, w) for (s, d), w in arcs.items()), Marking(marking))

    def arc(self, el, name: str, arcs: dict) -> None:
        kind = (el.get("type") or OLD_ARCS.get(name, "normal")).lower()
        aid = el.get("id") or f"{el.get('source')} to {el.get('target')}"
        if kind in ("tapninhibitor", "inhibitor"):
            self.error(el, f"arc '{aid}' is an inhibitor arc (it enables its transition only "
                           "while the place holds fewer tokens than its weight): a P/T net has "
                           "none; remove it, or analyse the net with TAPAAL")
            return
        if kind == "transport":
            # it moves a token with its age; even where ages cannot matter, TAPAAL's
            # engines and its two spellings of it do not agree on what it does
            self.error(el, f"arc '{aid}' is a transport arc of a timed-arc net; mcl2pnml reads "
                           "P/T nets: replace it by an input and an output arc in TAPAAL")
            return
        inscription = (el.get("inscription") or "").replace(" ", "")
        if kind == "timed" and (inscription or "[0,inf)") not in UNTIMED_INTERVAL:
            self.timed_error(el, f"arc '{aid}' has the time interval '{el.get('inscription')}'")
            return
        if kind not in ("timed", "normal"):
            self.error(el, f"arc '{aid}' has type '{el.get('type')}', which mcl2pnml does not "
                           "know; known: timed, normal")
            return
        if el.get("weight") is None and kind == "normal" and inscription.isdigit():
            weight = self.natural(el, "inscription", 1, 1)   # older files: the weight
        else:
            weight = self.natural(el, "weight", 1, 1)
        key = (el.get("source"), el.get("target"))
        arcs[key] = arcs.get(key, 0) + weight


def parse_tapaal(root, src, net_id: str | None = None) -> Net:
    """The one untimed P/T net of a TAPAAL file (``net_id``: one component of several)."""
    reader = _Tapaal(src)
    for el in root.iter(f"{{{NAMESPACE}}}feature"):
        if el.get("isColored") == "true":
            reader.error(el, "this TAPAAL model is coloured (isColored=\"true\"); unfold it to a "
                             "P/T net first (TAPAAL's unfolding, or export as PNML)")
    for el in root.iter(f"{{{NAMESPACE}}}declaration"):
        reader.error(el, "this TAPAAL model declares colour types; unfold it to a P/T net first")
    raise_all(reader.errors)
    nets = [n for n in root if _local(n) == "net"]
    if net_id is not None:
        chosen = [n for n in nets if n.get("id") == net_id]
        if not chosen:
            raise PnmlError(f"no component with id '{net_id}'; components in this file: "
                            + ", ".join(str(n.get("id")) for n in nets), src.locate(root))
        return reader.net(chosen[0])
    active = [n for n in nets if n.get("active", "true") != "false"]
    if not active:
        raise PnmlError("no active component in this TAPAAL model", src.locate(root))
    if len(active) > 1:
        raise PnmlError(f"this TAPAAL model has {len(active)} components "
                        f"({', '.join(str(n.get('id')) for n in active)}), which TAPAAL composes "
                        "through shared places and transitions; export the composed net as "
                        "PNML from TAPAAL, or read one component alone with --net ID",
                        src.locate(active[1]))
    return reader.net(active[0])
