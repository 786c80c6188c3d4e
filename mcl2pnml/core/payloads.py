"""What travels in a net's payloads: the contract between the compiler and its readers.

The compiler (section 2.4 of the paper, and docs/mcl.md, "Sharing")
leaves in the net everything the Mission Control System needs to run it
(section 2.1): which transitions send actions to the vehicle's primitives,
which ones the vehicle's events fire, with which arguments each call of a
shared task or function enters it, and the tasks' time-outs. The executor,
the token-game page and the TINA writer read them back, from a compiled net
or from its PNML alone.

A payload stays frozen JSON inside the :class:`~mcl2pnml.core.net.Net`:
PNML's toolspecific data round-trips it as it is, byte for byte. The typed
records below are what the stages write and read; :func:`read` and
:meth:`TransitionPayload.to_json` are the one place that maps them to and
from that JSON, key by key:

* ``doc``: a line for the reader of the net (:attr:`TransitionPayload.doc`,
  and a place's :func:`place_payload`);
* ``call``, ``scope``, ``bind``: a call site's entry (:class:`CallEntry`);
* ``actions``: enable and disable requests (:class:`ActionSpec`);
* ``event``, ``primitive``: the vehicle event that fires a primitive's
  transition (:class:`EventBinding`);
* ``timeout``: a task's time-out (:class:`TimeOut`).

Keys a template tags that none of these name are kept as they are
(:attr:`TransitionPayload.extra`), so a teacher's own tags reach PNML too.

It also names the mission's interface (:class:`MissionPlace`): the fusion
places of the root structure, which a run starts from and ends in.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass, replace
from typing import Any, Iterable, Mapping

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import Transition, freeze, thaw

# -- the vocabulary of the Architecture Abstraction Layer --------------------------------
#
# The kinds of actions and events are defined here, in core, and re-exported
# by runtime.aal: they are what a payload says, so the records hold them as
# enums (a payload with an unknown kind is refused when it is read, not when
# the vehicle first reports it), and one definition cannot drift from a
# second list of valid strings. Core may import nothing of ours, so the enums
# cannot stay in runtime.


class ActionKind(enum.Enum):
    """What the mission asks of a primitive (section 2.1: actions)."""

    ENABLE = "enable"
    """Start the primitive with these arguments (the task marked its E place)."""

    DISABLE = "disable"
    """Stop the primitive (the task marked its D place)."""


class EventKind(enum.Enum):
    """What a primitive reports back (section 2.1: events); each fires the
    primitive net's transition of that name."""

    ON = "on"
    """The primitive is running: the vehicle has processed the enable."""

    ACHIEVED = "achieved"
    """The goal is reached (or reached again)."""

    FAILED = "failed"
    """The goal cannot be reached, or was lost."""

    OFF = "off"
    """The primitive has stopped: the vehicle has processed the disable."""


# -- the mission's interface ----------------------------------------------------------------

#: The root structure's instance name, and the scope of the mission's own
#: arguments (the mission has no parameters: its arguments are all values).
MISSION = "mission"


class MissionPlace(enum.Enum):
    """The fusion places of the mission's root structure (the paper's Fp,
    section 2.5; docs/mcl.md, "Results"): a run starts by marking B
    and ends when one result place is marked."""

    B = "B"
    """Begin: marked in the initial marking, it starts the mission."""

    A = "A"
    """Abort: the operator's input. The analysis marks it with B to prove that
    an aborted mission ends and can be run again; the executor never sees it
    marked (a run stops by its safe stop, docs/faults.md)."""

    OK = "OK"
    """The mission ended OK."""

    FAIL = "FAIL"
    """The mission ended FAIL."""

    ABORTED = "ABORTED"
    """The mission ended ABORTED."""

    @property
    def id(self) -> str:
        """The place's id in a compiled net: ``mission.OK``."""
        return f"{MISSION}.{self.value}"


#: The places whose marking ends a run, each a result of docs/mcl.md.
RESULT_PLACES = (MissionPlace.OK, MissionPlace.FAIL, MissionPlace.ABORTED)

#: A call site's transition that enters the callee (it takes the callee's
#: gate and locks: docs/mcl.md, "Sharing"); its payload holds a
#: :class:`CallEntry`.
ENTER = "enter"


# -- the records ------------------------------------------------------------------------------


class PayloadError(Mcl2PnmlError):
    """A payload key this module knows holds data of the wrong shape."""


@dataclass(frozen=True)
class Param:
    """An argument that names a parameter of the scope it is evaluated in."""

    name: str

    def evaluate(self, scope: Mapping[str, Any]) -> Any:
        return _argument(scope[self.name])


@dataclass(frozen=True)
class Value:
    """An argument known at compile time: a number, a string, or a tuple of them
    (a const resolved). Held frozen (tuples); JSON writes tuples as lists."""

    value: Any

    def evaluate(self, scope: Mapping[str, Any]) -> Any:
        return _argument(thaw(self.value))


@dataclass(frozen=True)
class TupleOf:
    """A tuple made when the call is made, because some of its items name
    parameters: ``Leg((a, 0.0, 2.0))`` inside ``function Row(a)``. A tuple
    of constants alone is a :class:`Value`."""

    items: tuple["Arg", ...]

    def evaluate(self, scope: Mapping[str, Any]) -> Any:
        return tuple(item.evaluate(scope) for item in self.items)


Arg = Param | Value | TupleOf
#: How deep tuples of arguments may nest in a payload (MCL's parser allows less).
MAX_ARG_NESTING = 64


def _argument(value: Any) -> Any:
    """An argument as the vehicle receives it: an MCL tuple is a Python tuple."""
    return tuple(value) if isinstance(value, list) else value


@dataclass(frozen=True)
class CallEntry:
    """A call site's entry, as the compiler writes it (section 2.4): the callee
    it enters and the values of the callee's parameters, evaluated in
    ``scope`` when the entry fires. One shared net per task and function,
    entered with each call's own arguments (docs/mcl.md, "Sharing")."""

    callee: str
    scope: str
    """The function whose body holds the call, or ``MISSION``: where the
    arguments' parameters live."""
    bindings: tuple[tuple[str, Arg], ...]
    """(callee's parameter, argument), in the callee's parameter order."""


@dataclass(frozen=True)
class ActionSpec:
    """An action a task transition sends when it marks a primitive's E or D
    place (section 2.1; Fig. 2): enable with arguments, or disable."""

    kind: ActionKind
    primitive: str
    scope: str | None = None
    """The task whose parameters the arguments name (an enable only)."""
    args: tuple[Arg, ...] = ()


@dataclass(frozen=True)
class EventBinding:
    """The vehicle event that fires a primitive's transition (section 2.1)."""

    kind: EventKind
    primitive: str | None = None
    """None in the primitive template: the compiler names each instance's."""


@dataclass(frozen=True)
class TimeOut:
    """A task's time-out (``t03``; docs/mcl.md, "Tasks, patterns and time-outs")."""

    seconds: int | float | None = None
    """None in a pattern template (the transition *is* the time-out); the
    task's declared seconds once compiled."""


@dataclass(frozen=True)
class TransitionPayload:
    """Everything one transition carries; an empty record is no payload."""

    doc: str | None = None
    entry: CallEntry | None = None
    event: EventBinding | None = None
    actions: tuple[ActionSpec, ...] = ()
    timeout: TimeOut | None = None
    extra: tuple[tuple[str, Any], ...] = ()
    """Keys none of the records name (a template's own tags), frozen, in order."""

    def of_primitive(self, primitive: str) -> "TransitionPayload":
        """This transition of the primitive template, in the net of ``primitive``."""
        if self.event is not None:
            return replace(self, event=EventBinding(self.event.kind, primitive))
        # a transition no event fires still says whose net it is in
        return replace(self, extra=(*self.extra, ("primitive", primitive)))

    def to_json(self) -> dict[str, Any] | None:
        """The payload as JSON-like data (None when empty), the inverse of :func:`read`."""
        out: dict[str, Any] = {}
        if self.entry is not None:
            e = self.entry
            out["call"] = e.callee
            out["scope"] = e.scope
            out["bind"] = {name: _arg_json(arg) for name, arg in e.bindings}
        if self.doc is not None:
            out["doc"] = self.doc
        if self.event is not None:
            out["event"] = self.event.kind.value
            if self.event.primitive is not None:
                out["primitive"] = self.event.primitive
        if self.timeout is not None:
            out["timeout"] = True if self.timeout.seconds is None else self.timeout.seconds
        if self.actions:
            out["actions"] = [_action_json(a) for a in self.actions]
        for key, value in self.extra:
            out[key] = value
        return out or None


def _arg_json(arg: Arg) -> dict[str, Any]:
    if isinstance(arg, TupleOf):
        return {"tuple": [_arg_json(item) for item in arg.items]}
    return {"param": arg.name} if isinstance(arg, Param) else {"value": arg.value}


def _action_json(a: ActionSpec) -> dict[str, Any]:
    out: dict[str, Any] = {"action": a.kind.value, "primitive": a.primitive}
    if a.scope is not None:
        out["scope"] = a.scope
    if a.kind is ActionKind.ENABLE:   # a disable has no arguments (section 2.1)
        out["args"] = [_arg_json(x) for x in a.args]
    return out


def tagged(doc: str | None, tags: Iterable[tuple[str, Any]]) -> TransitionPayload:
    """A template transition's payload: its doc line and its ``KEY=VALUE`` tags
    (``timeout`` alone is ``("timeout", True)``), a later one winning."""
    data: dict[str, Any] = {} if doc is None else {"doc": doc}
    data.update(tags)
    return read(data)


def place_payload(doc: str | None) -> dict[str, Any] | None:
    """A place's payload: its doc line, if any."""
    return {"doc": doc} if doc else None


def doc_of(payload: Any) -> Any:
    """The doc line of any node's payload (None if it has none, or is not a mapping)."""
    return payload.get("doc") if isinstance(payload, Mapping) else None


# -- reading ------------------------------------------------------------------------------

_KNOWN = frozenset({"doc", "call", "scope", "bind", "event", "primitive", "timeout", "actions"})


def read(payload: Any) -> TransitionPayload:
    """The record of a transition's payload (frozen or plain JSON).

    A payload that is not a mapping (another tool's) reads as empty; a key
    this module knows that holds the wrong shape is a :class:`PayloadError`.
    """
    if not isinstance(payload, Mapping):
        return TransitionPayload()
    entry = None
    if "call" in payload:
        bind = payload.get("bind", {})
        if not isinstance(bind, Mapping):
            raise PayloadError(f"'bind' is a mapping of parameters, not {thaw(bind)!r}")
        entry = CallEntry(_str(payload, "call"), _str(payload, "scope", MISSION),
                          tuple((name, _arg(x)) for name, x in bind.items()))
    event = None
    if "event" in payload:
        event = EventBinding(_enum(EventKind, payload["event"], "event"),
                             _str(payload, "primitive", None))
    timeout = None
    if "timeout" in payload:
        seconds = payload["timeout"]
        if seconds is not True and (isinstance(seconds, bool)
                                    or not isinstance(seconds, (int, float))):
            raise PayloadError(f"'timeout' is true or seconds, not {thaw(seconds)!r}")
        timeout = TimeOut(None if seconds is True else seconds)
    actions = tuple(_action(a) for a in _items(payload.get("actions", ()), "actions"))
    extra = tuple((k, freeze(v)) for k, v in payload.items()
                  if k not in _KNOWN or (k == "primitive" and event is None)
                  or (k in ("scope", "bind") and entry is None))
    return TransitionPayload(payload.get("doc"), entry, event, actions, timeout, extra)


def read_transition(t: Transition) -> TransitionPayload:
    """:func:`read` of ``t``'s payload; an error names the transition."""
    try:
        return read(t.payload)
    except PayloadError as e:
        raise PayloadError(f"transition '{t.id}': {e.message}") from None


def _str(payload: Mapping, key: str, default: Any = ...) -> Any:
    if key not in payload and default is not ...:
        return default
    value = payload.get(key)
    if not isinstance(value, str):
        raise PayloadError(f"'{key}' is a name, not {thaw(value)!r}")
    return value


def _enum(kind: type[enum.Enum], value: Any, key: str) -> Any:
    try:
        return kind(value)
    except (ValueError, TypeError):
        valid = ", ".join(k.value for k in kind)
        raise PayloadError(f"'{key}' is one of {valid}, not {thaw(value)!r}") from None


def _items(value: Any, key: str) -> tuple:
    if isinstance(value, (tuple, list)):
        return tuple(value)
    raise PayloadError(f"'{key}' is a list, not {thaw(value)!r}")


def _arg(expr: Any, depth: int = 0) -> Arg:
    if isinstance(expr, Mapping) and "param" in expr:
        return Param(_str(expr, "param"))
    if isinstance(expr, Mapping) and "value" in expr:
        return Value(freeze(expr["value"]))
    if isinstance(expr, Mapping) and "tuple" in expr:
        if depth >= MAX_ARG_NESTING:
            raise PayloadError(f"tuples of arguments nest at most {MAX_ARG_NESTING} deep")
        return TupleOf(tuple(_arg(x, depth + 1) for x in _items(expr["tuple"], "tuple")))
    raise PayloadError(f"an argument is {{\"param\": name}}, {{\"value\": v}} or "
                       f"{{\"tuple\": [argument, ...]}}, not {thaw(expr)!r}")


def _action(a: Any) -> ActionSpec:
    if not isinstance(a, Mapping):
        raise PayloadError(f"an action is a mapping, not {thaw(a)!r}")
    return ActionSpec(_enum(ActionKind, a.get("action"), "action"), _str(a, "primitive"),
                      _str(a, "scope", None),
                      tuple(_arg(x) for x in _items(a.get("args", ()), "args")))
