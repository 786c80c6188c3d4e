"""The Petri-net core: places, transitions and arcs as plain immutable data.

A :class:`Net` is the structure of a place/transition net (Murata 1989) plus
the initial marking it is meant to start from (what PNML calls the places'
``initialMarking``). Run-time state lives apart, in :class:`Marking` values:
the net itself never changes while it is played or analysed.

Beyond a plain P/T net the core holds what the paper's nets need:

* **read (test) arcs** (:attr:`ArcKind.READ`): the transition needs tokens in
  the place but leaves them there. Kept as such, because they change which
  sets of places are siphons (see ``analysis``), and exported to P/T PNML as a
  self-loop, which has the same firing rule;
* **interface labels** on places: the fusion places of sections 2.2-2.5 of the
  paper (``B``, ``A``, ``MTX``, ``OK``, ``FAIL``, ``ABORTED``, ``E``, ``D``,
  ``OFF``, ``S1``, ``S2``), through which templates are composed;
* **timed transitions**: a delay or an interval ``[earliest, latest]``, as the
  time-out transition ``t03`` of the task net (section 2.3);
* an opaque, JSON-like **payload** per node, where the compiler puts vehicle
  bindings (which action a place triggers, with which arguments).

Everything is validated once, at construction, in time linear in the size of
the net, so that nets of 100,000 nodes build quickly.
"""
from __future__ import annotations

import enum
import math
import re
from dataclasses import dataclass, field
from functools import cached_property
from itertools import chain, compress
from operator import not_
from typing import Any, Iterable, Iterator, Mapping, NamedTuple

from mcl2pnml.core.errors import NetError
from mcl2pnml.core.vocabulary import counted

# --------------------------------------------------------------------------
# Frozen JSON-like payloads


class FrozenDict(Mapping[str, Any]):
    """A hashable, read-only mapping: the frozen form of a JSON object."""

    __slots__ = ("_data", "_hash")

    def __init__(self, data: Mapping[str, Any] = ()):  # type: ignore[assignment]
        self._data = dict(data)
        self._hash: int | None = None

    def __getitem__(self, key: str) -> Any:
        return self._data[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __hash__(self) -> int:
        if self._hash is None:
            self._hash = hash(frozenset(self._data.items()))
        return self._hash

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Mapping):
            return self._data == dict(other)
        return NotImplemented

    def __repr__(self) -> str:
        return f"FrozenDict({self._data!r})"


_SCALARS = frozenset({str, bool, int, type(None)})


def freeze(value: Any) -> Any:
    """Turn JSON-like data into hashable, immutable data (dicts, lists -> tuples)."""
    kind = type(value)
    # exact types first: an isinstance test against the Mapping ABC costs
    # microseconds, and the compiler freezes each call's bindings
    if kind in _SCALARS or kind is FrozenDict:
        return value
    if kind is dict:
        out = {}
        for key, item in value.items():
            if type(key) is not str:
                raise NetError(f"payload keys must be strings, not {key!r}")
            out[key] = freeze(item)
        return FrozenDict(out)
    if kind is list or kind is tuple:
        return tuple(freeze(item) for item in value)
    if isinstance(value, Mapping):
        out = {}
        for key, item in value.items():
            if not isinstance(key, str):
                raise NetError(f"payload keys must be strings, not {key!r}")
            out[key] = freeze(item)
        return FrozenDict(out)
    if isinstance(value, (list, tuple)):
        return tuple(freeze(item) for item in value)
    if value is None or isinstance(value, (str, bool, int)):
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            raise NetError(f"payload numbers must be finite, not {value!r}")
        return value
    raise NetError(f"payload must be JSON-like data, not {type(value).__name__}")


def thaw(value: Any) -> Any:
    """The inverse of :func:`freeze`: plain dicts and lists, ready for ``json``."""
    if isinstance(value, Mapping):
        return {key: thaw(item) for key, item in value.items()}
    if isinstance(value, tuple):
        return [thaw(item) for item in value]
    return value


# --------------------------------------------------------------------------
# Nodes and arcs


class ArcKind(enum.Enum):
    """How an arc takes part in firing."""

    NORMAL = "normal"
    """Place to transition: consumes ``weight`` tokens. Transition to place:
    produces them."""

    READ = "read"
    """Place to transition only: the transition needs ``weight`` tokens in the
    place to fire and leaves them there (a test arc)."""

    # Members are singletons, so identity hashing is exact, and it is done in
    # C: a net of a million arcs hashes each arc's kind when it is checked.
    __hash__ = object.__hash__


@dataclass(frozen=True)
class Timing:
    """When an enabled transition may fire, in seconds after it became enabled.

    A time-out of the paper's task net (``t03``, section 2.3) is the delay
    ``Timing(300, 300)``; ``latest=None`` means no upper bound.
    """

    earliest: float = 0.0
    latest: float | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.earliest) and self.earliest >= 0):
            raise NetError(f"timing must start at a finite time >= 0, not {self.earliest}")
        if self.latest is not None and not (
            math.isfinite(self.latest) and self.latest >= self.earliest
        ):
            raise NetError(
                f"timing interval [{self.earliest}, {self.latest}] is empty or not finite"
            )

    @classmethod
    def delay(cls, seconds: float) -> "Timing":
        """Fires exactly ``seconds`` after being enabled (a time-out)."""
        return cls(float(seconds), float(seconds))

    def __str__(self) -> str:
        hi = "inf" if self.latest is None else f"{self.latest:g}"
        return f"[{self.earliest:g}, {hi}]"


class _Named:
    """What places and transitions share: an id, and a name shown to people."""

    id: str
    name: str | None

    def __post_init__(self) -> None:
        # One canonical form keeps equality (and PNML round trips) exact:
        # surrounding white space is layout, and a blank name or one equal to
        # the id says nothing more.
        name = self.name.strip() if isinstance(self.name, str) else self.name
        if name == "" or name == self.id:
            name = None
        object.__setattr__(self, "name", name)

    @property
    def label(self) -> str:
        return self.name if self.name is not None else self.id

    def with_id(self, new_id: str):
        """The same node under another id (what composition does to every node).

        Built by copying the fields, without the dataclass machinery: they are
        valid already, and a compiled mission renames hundreds of thousands of
        nodes. Only the canonical name needs a look, since a name may equal
        the new id; the id itself is checked by the :class:`Net` it goes into.
        """
        clone = object.__new__(type(self))
        fields = clone.__dict__
        fields.update(self.__dict__)
        fields["id"] = new_id
        if fields["name"] == new_id:
            fields["name"] = None
        return clone


@dataclass(frozen=True)
class Place(_Named):
    """A place. ``interface`` names its role as a fusion place (``"B"``...)."""

    id: str
    name: str | None = None
    interface: str | None = None
    payload: Any = None
    position: tuple[float, float] | None = field(default=None, compare=False)



@dataclass(frozen=True)
class Transition(_Named):
    """A transition, optionally timed (``timing``) and bound (``payload``)."""

    id: str
    name: str | None = None
    timing: Timing | None = None
    payload: Any = None
    position: tuple[float, float] | None = field(default=None, compare=False)



class Arc(NamedTuple):
    """An arc between a place and a transition (in either direction).

    A named tuple rather than a dataclass: arcs are the bulk of a compiled
    mission (a million of them for 10,000 calls), and a tuple is built and
    hashed in C at half the cost.
    """

    source: str
    target: str
    weight: int = 1
    kind: ArcKind = ArcKind.NORMAL

    @property
    def key(self) -> tuple[str, str, ArcKind]:
        return (self.source, self.target, self.kind)


# --------------------------------------------------------------------------
# Markings


class Marking(Mapping[str, int]):
    """An immutable marking: place id -> token count, zero entries left out.

    Hashable, so that markings can be states of a reachability graph.
    """

    __slots__ = ("_tokens", "_hash")

    def __init__(self, tokens: Mapping[str, int] | Iterable[str] = ()):
        if isinstance(tokens, Mapping):
            items = tokens.items()
        else:  # an iterable of place ids, one token each
            counts: dict[str, int] = {}
            for place in tokens:
                counts[place] = counts.get(place, 0) + 1
            items = counts.items()
        data = {}
        for place, count in items:
            if not isinstance(count, int) or isinstance(count, bool):
                raise NetError(f"marking of place '{place}' must be an integer, not {count!r}")
            if count < 0:
                raise NetError(f"marking of place '{place}' is negative ({count})")
            if count:
                data[place] = count
        self._tokens = data
        self._hash: int | None = None

    def __getitem__(self, place: str) -> int:
        return self._tokens.get(place, 0)

    def __contains__(self, place: object) -> bool:
        return place in self._tokens

    def __iter__(self) -> Iterator[str]:
        return iter(self._tokens)

    def __len__(self) -> int:
        return len(self._tokens)

    def __hash__(self) -> int:
        if self._hash is None:
            self._hash = hash(frozenset(self._tokens.items()))
        return self._hash

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Marking):
            return self._tokens == other._tokens
        if isinstance(other, Mapping):
            return self._tokens == {k: v for k, v in other.items() if v}
        return NotImplemented

    def __repr__(self) -> str:
        return f"Marking({{{', '.join(self.format())}}})"

    def format(self) -> list[str]:
        """Sorted place names, ``P*2`` for counts above one (cli.md's notation)."""
        return [p if n == 1 else f"{p}*{n}" for p, n in sorted(self._tokens.items())]


# --------------------------------------------------------------------------
# The net

_ID = re.compile(r"\S(?:.*\S)?\Z", re.S)


def _valid_text(text: object) -> bool:
    return isinstance(text, str) and not _NOT_XML.search(text)


def is_valid_id(text: object) -> bool:
    """A node id: a non-empty string without leading or trailing white space."""
    return isinstance(text, str) and _ID.match(text) is not None

# characters XML 1.0 cannot carry at all: names and labels must avoid them
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


_KINDS = frozenset(ArcKind)
#: How many marked places :meth:`Net.summary` names before it counts the rest.
SUMMARY_MARKED = 12


@dataclass(frozen=True, eq=False)
class Net:
    """A marked place/transition net. Build it once; it never changes.

    Construction checks, in linear time: ids are non-empty and unique across
    places and transitions; every arc joins a place and a transition (read
    arcs from a place to a transition); weights are positive; no two arcs have
    the same ends and kind; no transition both reads and consumes one place;
    the initial marking names existing places only.

    Equality ignores order and drawing positions: two nets are equal when
    they have the same places, transitions, arcs and initial marking.
    """

    name: str
    places: tuple[Place, ...]
    transitions: tuple[Transition, ...]
    arcs: tuple[Arc, ...]
    initial: Marking = field(default_factory=Marking)

    def __post_init__(self) -> None:
        object.__setattr__(self, "places", tuple(self.places))
        object.__setattr__(self, "transitions", tuple(self.transitions))
        object.__setattr__(self, "arcs", tuple(self.arcs))
        if not isinstance(self.initial, Marking):
            object.__setattr__(self, "initial", Marking(self.initial))
        self._check()

    def _check(self) -> None:
        """Validate in a few passes that run in C; explain the first fault if any.

        Each condition is a set operation over all ids or all arcs, so that a
        net of a million arcs checks in a fraction of a second; only when one
        fails does :meth:`_explain` walk the net to say where.
        """
        try:
            ok = self._valid()
        except (TypeError, AttributeError):  # an unhashable id, weight or kind; a stray object
            ok = False
        if not ok:
            self._explain()
            raise NetError(f"net '{self.name}' is malformed")  # _explain always raises first

    def _valid(self) -> bool:
        places, transitions, arcs = self.places, self.transitions, self.arcs
        pids = {p.id for p in places}
        tids = {t.id for t in transitions}
        texts = ({p.name for p in places} | {p.interface for p in places}
                 | {t.name for t in transitions})
        texts.discard(None)
        if not (_valid_text(self.name)
                and len(pids) == len(places) and len(tids) == len(transitions)
                and pids.isdisjoint(tids)
                and all(map(_ID.match, chain(pids, tids)))
                and all(map(_valid_text, texts))
                and pids.issuperset(self.initial)):
            return False
        if not arcs:
            return True
        sources, targets, weights, kinds = zip(*arcs)
        from_place = list(map(pids.__contains__, sources))
        from_transition = list(map(not_, from_place))
        return (tids.issuperset(compress(targets, from_place))
                and tids.issuperset(compress(sources, from_transition))
                and pids.issuperset(compress(targets, from_transition))
                and set(kinds) <= _KINDS
                and ArcKind.READ not in set(compress(kinds, from_transition))
                and all(isinstance(w, int) and not isinstance(w, bool) and w >= 1
                        for w in set(weights))
                # one arc per ordered pair: no duplicates, and no transition
                # that both reads and consumes a place
                and len(set(zip(sources, targets))) == len(arcs))

    def _explain(self) -> None:
        """Walk the net node by node and arc by arc; raise on the first fault."""
        if not _valid_text(self.name):
            raise NetError(f"net name must be text without control characters, "
                           f"not {self.name!r}")
        kinds: dict[str, str] = {}
        for node_kind, nodes in (("place", self.places), ("transition", self.transitions)):
            for node in nodes:
                if not isinstance(node.id, str) or not _ID.match(node.id):
                    raise NetError(f"{node_kind} id {node.id!r} must be a non-empty string "
                                   "without leading or trailing white space")
                if node.id in kinds:
                    raise NetError(
                        f"duplicate id '{node.id}' (a {kinds[node.id]} and a {node_kind}); "
                        "ids must be unique across places and transitions")
                kinds[node.id] = node_kind
                for what in ("name", "interface"):
                    text = getattr(node, what, None)
                    if text is not None and (not isinstance(text, str) or _NOT_XML.search(text)):
                        raise NetError(f"{what} of {node_kind} '{node.id}' must be text "
                                       f"without control characters, not {text!r}")
        seen: set[tuple[str, str, ArcKind]] = set()
        inputs: set[tuple[str, str]] = set()
        reads: set[tuple[str, str]] = set()
        for arc in self.arcs:
            where = f"arc {arc.source} -> {arc.target}"
            if not isinstance(arc.kind, ArcKind):
                raise NetError(f"{where}: kind must be one of "
                               f"{', '.join(k.name for k in ArcKind)}, not {arc.kind!r}")
            for end in (arc.source, arc.target):
                if end not in kinds:
                    raise NetError(f"{where}: no place or transition '{end}'")
            ends = (kinds[arc.source], kinds[arc.target])
            if ends[0] == ends[1]:
                raise NetError(f"{where} joins two {ends[0]}s; an arc joins a place "
                               "and a transition")
            if arc.kind is ArcKind.READ and ends[0] != "place":
                raise NetError(f"{where}: a read arc goes from a place to a transition")
            if not isinstance(arc.weight, int) or isinstance(arc.weight, bool) or arc.weight < 1:
                raise NetError(f"{where}: weight must be a positive integer, not {arc.weight!r}")
            if arc.key in seen:
                raise NetError(f"{where}: two {arc.kind.value} arcs with the same ends")
            seen.add(arc.key)
            if ends[0] == "place":
                (reads if arc.kind is ArcKind.READ else inputs).add((arc.source, arc.target))
        both = inputs & reads
        if both:
            place, transition = sorted(both)[0]
            raise NetError(f"transition '{transition}' both reads and consumes place "
                           f"'{place}'; use one arc")
        for place in self.initial:
            if kinds.get(place) != "place":
                raise NetError(f"initial marking names '{place}', which is not a place")

    # -- lookups (computed once, on first use) ---------------------------------

    @cached_property
    def place_index(self) -> Mapping[str, Place]:
        return {p.id: p for p in self.places}

    @cached_property
    def transition_index(self) -> Mapping[str, Transition]:
        return {t.id: t for t in self.transitions}

    @cached_property
    def pre(self) -> Mapping[str, tuple[Arc, ...]]:
        """Transition id -> its input arcs (normal and read)."""
        return self._group(lambda a: a.target, self.transition_index)

    @cached_property
    def post(self) -> Mapping[str, tuple[Arc, ...]]:
        """Transition id -> its output arcs."""
        return self._group(lambda a: a.source, self.transition_index)

    def _group(self, key, nodes) -> Mapping[str, tuple[Arc, ...]]:
        groups: dict[str, list[Arc]] = {n: [] for n in nodes}
        for arc in self.arcs:
            k = key(arc)
            if k in groups:
                groups[k].append(arc)
        return {k: tuple(v) for k, v in groups.items()}

    def by_interface(self) -> Mapping[str, tuple[str, ...]]:
        """Interface label -> the ids of the places that carry it."""
        out: dict[str, list[str]] = {}
        for p in self.places:
            if p.interface is not None:
                out.setdefault(p.interface, []).append(p.id)
        return {k: tuple(v) for k, v in out.items()}

    # -- equality --------------------------------------------------------------

    def _content(self):
        return (self.name, frozenset(self.places), frozenset(self.transitions),
                frozenset(self.arcs), self.initial)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Net):
            return NotImplemented
        return self._content() == other._content()

    def __hash__(self) -> int:
        return hash(self._content())

    def __repr__(self) -> str:
        return (f"Net({self.name!r}: {len(self.places)} places, "
                f"{len(self.transitions)} transitions, {len(self.arcs)} arcs)")

    # -- small conveniences ----------------------------------------------------

    @classmethod
    def _trusted(cls, name: str, places: tuple[Place, ...], transitions: tuple[Transition, ...],
                 arcs: tuple[Arc, ...], initial: Marking,
                 columns: tuple[tuple, tuple, tuple, tuple] | None = None) -> "Net":
        """A net whose validity its builder has proved (see :func:`~mcl2pnml.core.compose.compose`).

        A builder that made the arcs from columns hands those over too, as
        :attr:`columns`, which then need not be taken apart again.
        """
        net = object.__new__(cls)
        for f, value in (("name", name), ("places", places), ("transitions", transitions),
                         ("arcs", arcs), ("initial", initial)):
            object.__setattr__(net, f, value)
        if columns is not None and arcs:
            net.__dict__["columns"] = columns
        return net

    @cached_property
    def columns(self) -> tuple[tuple, tuple, tuple, tuple]:
        """The arcs as four columns: sources, targets, weights, kinds."""
        if not self.arcs:
            return ((), (), (), ())
        return tuple(zip(*self.arcs))  # type: ignore[return-value]

    def _derived(self, **changes: Any) -> "Net":
        """A copy with fields changed in ways that cannot break what was checked."""
        return Net._trusted(*(changes.get(f, getattr(self, f))
                              for f in ("name", "places", "transitions", "arcs", "initial")))

    def with_initial(self, marking: Mapping[str, int] | Iterable[str]) -> "Net":
        """The same net started from another marking (only the marking is checked)."""
        marking = marking if isinstance(marking, Marking) else Marking(marking)
        for place in marking:
            if place not in self.place_index:
                raise NetError(f"initial marking names '{place}', which is not a place")
        return self._derived(initial=marking)

    def with_payloads(self, payloads: Mapping[str, Any]) -> "Net":
        """The same net with other payloads on some transitions (id -> JSON-like data).

        The structure is untouched, so nothing is checked again: this is how
        the compiler stamps each call site's arguments on a shared prototype.
        """
        unknown = set(payloads) - set(self.transition_index)
        if unknown:
            raise NetError(f"no transition '{sorted(unknown)[0]}' in net '{self.name}'")
        transitions = tuple(
            Transition(t.id, t.name, t.timing, freeze(payloads[t.id]), t.position)
            if t.id in payloads else t for t in self.transitions)
        return self._derived(transitions=transitions)

    def renamed(self, name: str) -> "Net":
        if not _valid_text(name):
            raise NetError(f"net name must be text without control characters, not {name!r}")
        return self._derived(name=name)

    def summary(self) -> str:
        timed = sum(1 for t in self.transitions if t.timing is not None)
        reads = sum(1 for a in self.arcs if a.kind is ArcKind.READ)
        marked = self.initial.format()
        if len(marked) > SUMMARY_MARKED:  # a long mission marks every call site's MTX
            marked = [*marked[:SUMMARY_MARKED], f"... {len(marked) - SUMMARY_MARKED:,} more"]
        return (f"{self.name}: {counted(len(self.places), 'place')}, "
                f"{counted(len(self.transitions), 'transition')} ({timed:,} timed), "
                f"{counted(len(self.arcs), 'arc')} ({reads:,} read), "
                f"initial marking {{{', '.join(marked)}}}")


class NetBuilder:
    """Collects nodes and arcs, then builds one immutable :class:`Net`.

    Arcs added twice between the same ends add up their weights, which is what
    drawing the same arc twice means in a P/T net.
    """

    def __init__(self, name: str):
        self.name = name
        self._places: dict[str, Place] = {}
        self._transitions: dict[str, Transition] = {}
        self._arcs: dict[tuple[str, str, ArcKind], int] = {}
        self._marking: dict[str, int] = {}

    def place(self, id: str, tokens: int = 0, *, name: str | None = None,
              interface: str | None = None, payload: Any = None,
              position: tuple[float, float] | None = None) -> str:
        if id in self._places or id in self._transitions:
            raise NetError(f"duplicate id '{id}'")
        self._places[id] = Place(id, name, interface, freeze(payload), position)
        if tokens:
            self._marking[id] = tokens
        return id

    def transition(self, id: str, *, name: str | None = None, timing: Timing | None = None,
                   payload: Any = None, position: tuple[float, float] | None = None) -> str:
        if id in self._places or id in self._transitions:
            raise NetError(f"duplicate id '{id}'")
        self._transitions[id] = Transition(id, name, timing, freeze(payload), position)
        return id

    def arc(self, source: str, target: str, weight: int = 1,
            kind: ArcKind = ArcKind.NORMAL) -> None:
        key = (source, target, kind)
        self._arcs[key] = self._arcs.get(key, 0) + weight

    def read(self, place: str, transition: str, weight: int = 1) -> None:
        self.arc(place, transition, weight, ArcKind.READ)

    def build(self) -> Net:
        arcs = tuple(Arc(s, t, w, k) for (s, t, k), w in self._arcs.items())
        return Net(self.name, tuple(self._places.values()),
                   tuple(self._transitions.values()), arcs, Marking(self._marking))
