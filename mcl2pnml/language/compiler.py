"""Step 2 of the compiler: functional code to one composed P/T net, by place fusion.

The net is built the way section 2.5 says: templates joined through their
fusion places, with **one shared net per task and per function**, entered
from each call site with that call's parameters.

Components, each prefixed by its instance name (``AchieveDepth.MTX``):

(With ``reduced=True`` each task is the reduced model of Fig. 3 and there
are no primitives or locks: the mission's control flow alone.)

* one **primitive** net per vehicle primitive a task uses (``KeepDepth.ON``),
  with a lock ``KeepDepth.LOCK``: the analysis of the templates shows that
  OFF alone does not keep two tasks from enabling one primitive at once;
* one **task** net per task: its pattern's template, its slot places fused
  with its primitives' interface places, its time-out ``t03`` timed (or
  removed when the task has no timeout), and a gate ``T.GATE``;
* one **function** net per function: the structures of its body, the root
  one named after the function (``Survey.B``), and a gate ``Survey.GATE``;
* one **structure** instance per structure of a body (``sequence-1``,
  ``if-then-else-1`` ...), its slots T1, T2 ... fused with its children;
* one **call site** per call (``AchieveDepth-2``): a net with the control
  interface of the reduced task (B, A, MTX, OK, FAIL, ABORTED), which
  waits for the callee's gate and the locks of its primitives, takes them
  all at once, enters the shared net with its own arguments, passes an
  abort on, routes the result back and frees the gate. A call aborted while
  it waits ends ABORTED without starting. Taking the gate and every lock in
  one transition cannot deadlock: functions are not recursive, so gates
  are taken in a fixed nesting order, and locks by tasks only, which call
  nothing.

The root of the mission is named ``mission``: ``mission.B`` and
``mission.MTX`` are marked, and analysing the PNML alone covers the whole
mission (its interface: :class:`~mcl2pnml.core.payloads.MissionPlace`).

What the executor needs travels as payloads (and so as PNML toolspecific
data), written through the records of :mod:`mcl2pnml.core.payloads`: events
on the primitives' transitions, actions and their argument expressions on
the task transitions that mark E or D, bindings on each call site's entry,
delays on time-outs.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

from dataclasses import replace

from mcl2pnml.language import ast
from mcl2pnml.core import payloads
from mcl2pnml.core.compose import compose
from mcl2pnml.core.payloads import (ENTER, MISSION, ActionKind, ActionSpec, Arg, CallEntry,
                                    MissionPlace, Param, TimeOut, TransitionPayload, TupleOf,
                                    Value)
from mcl2pnml.language.functional import (FCall, FNode, NULL_KIND, function_expression,
                                          instances, mission_expression)
from mcl2pnml.core.gcpause import without_gc
from mcl2pnml.language.semantics import Checked
from mcl2pnml.core.net import Marking, Net, NetBuilder, Place, Timing, Transition, freeze
from mcl2pnml.language.library import Library, at_rest, default_library
from mcl2pnml.language.template_parser import CONTROL, slot_places

#: The doc of every gate: a task's or function's, taken by the call inside it.
GATE_DOC = "free: no call is inside"

STRUCTURE_TEMPLATE = {"sequence": "sequence", "parallel": "parallel", "if-then-else": "if-then-else",
                      "while": "while", "monitor": "monitor", NULL_KIND: "null"}


def _expr(value: ast.Value, params: tuple[str, ...], consts: dict[str, Any]) -> Arg:
    """An argument: a value for what is known now (consts resolved), else the
    parameter, or a tuple made at the call of what names parameters."""
    if isinstance(value, ast.Ref) and value.name in params:
        return Param(value.name)
    if isinstance(value, ast.Tuple) and _names_a_param(value, params):
        return TupleOf(tuple(_expr(item, params, consts) for item in value.items))
    return Value(_value(value, consts))


def _names_a_param(value: ast.Value, params: tuple[str, ...]) -> bool:
    if isinstance(value, ast.Tuple):
        return any(_names_a_param(item, params) for item in value.items)
    return isinstance(value, ast.Ref) and value.name in params


def _value(value: ast.Value, consts: dict[str, Any]) -> Any:
    if isinstance(value, ast.Number):
        return value.value
    if isinstance(value, ast.String):
        return value.value
    # tuples, as payloads hold them frozen
    if isinstance(value, ast.Tuple):
        return tuple(_value(i, consts) for i in value.items)
    return consts[value.name]


def _doc(text: str) -> dict[str, Any] | None:
    """A transition's payload that is a doc line alone."""
    return TransitionPayload(doc=text).to_json()


@dataclass
class _Assembly:
    """Components (prefix, net) in union order, and the fusion groups between them."""

    parts: list[tuple[str, Net]] = field(default_factory=list)
    groups: list[list[str]] = field(default_factory=list)


class Compiler:
    def __init__(self, checked: Checked, library: Library | None = None,
                 reduced: bool = False):
        self.c = checked
        self.lib = library or default_library()
        self.a = _Assembly()
        #: every task as the paper's reduced model (Fig. 3), and no primitives
        self.reduced = reduced
        self.used_primitives = [] if reduced else sorted(
            {p.name for t in checked.tasks.values() for p in t.primitives})
        # One net per structure template and one call-site prototype per
        # callee, shared by every instance: a long mission repeats them
        # thousands of times, and nets are immutable.
        self._structures: dict[str, Net] = {}
        self._call_sites: dict[str, Net] = {}

    # -- shared nets ---------------------------------------------------------------------

    def primitive_net(self, name: str) -> Net:
        net = at_rest(self.lib.primitive.net)
        b = NetBuilder(name)
        for p in net.places:
            b.place(p.id, net.initial[p.id], name=p.name, interface=p.interface,
                    payload=p.payload)
        b.place("LOCK", 1, payload=payloads.place_payload("free: no task uses this primitive"))
        for t in net.transitions:
            payload = payloads.read_transition(t).of_primitive(name)
            b.transition(t.id, name=t.name, payload=payload.to_json())
        for a in net.arcs:
            b.arc(a.source, a.target, a.weight, a.kind)
        return b.build()

    def task_net(self, task: ast.Task) -> tuple[Net, list[list[str]]]:
        if self.reduced:
            net = at_rest(self.lib.reduced.net)
            gate = Place("GATE", payload=freeze(payloads.place_payload(GATE_DOC)))
            own = Net(task.name, (*net.places, gate), net.transitions, net.arcs,
                      Marking({**net.initial, "GATE": 1}))
            return own, []
        template = self.c.patterns[task.name]
        net = at_rest(template.net)
        interface = [p.id for p in self.lib.primitive.net.places if p.interface is not None]
        slot_of: dict[str, tuple[str, str]] = {}   # slot place -> (primitive name, interface)
        for slot, call in zip(template.primitives, task.primitives):
            for place, role in slot_places(slot, tuple(interface)).items():
                slot_of[place] = (call.name, role)
        calls = {slot: call for slot, call in zip(template.primitives, task.primitives)}
        transitions = []
        for t in net.transitions:
            payload = payloads.read_transition(t)
            actions = []
            for arc in net.post[t.id]:
                prim, role = slot_of.get(arc.target, (None, None))
                if role == "E":
                    call = next(c for s, c in calls.items()
                                if slot_places(s, tuple(interface)).get(arc.target) == "E")
                    # scope: the task whose parameters the arguments name
                    actions.append(ActionSpec(ActionKind.ENABLE, prim, task.name,
                                              tuple(_expr(v, task.params, self.c.consts)
                                                    for v in call.args)))
                elif role == "D":
                    actions.append(ActionSpec(ActionKind.DISABLE, prim))
            if actions:
                payload = replace(payload, actions=(*payload.actions, *actions))
            timing = None
            if payload.timeout is not None and payload.timeout.seconds is None:
                if task.timeout is None:
                    continue  # no time-out declared: the task waits for its primitive
                payload = replace(payload, timeout=TimeOut(task.timeout.value))
                timing = Timing.delay(float(task.timeout.value))
            transitions.append(Transition(t.id, t.name, timing, freeze(payload.to_json())))
        kept = {t.id for t in transitions}
        arcs = tuple(a for a in net.arcs if a.source in kept or a.target in kept)
        places = (*net.places, Place("GATE", payload=freeze(payloads.place_payload(GATE_DOC))))
        marking = dict(net.initial)
        marking["GATE"] = 1
        own = Net(task.name, places, tuple(transitions), arcs, Marking(marking))
        groups = [[f"{prim}.{role}", f"{task.name}.{place}"]
                  for place, (prim, role) in slot_of.items()]
        return own, groups

    # -- expressions ---------------------------------------------------------------------

    def instance(self, root: FNode, root_name: str, scope: str, params: tuple[str, ...]) -> None:
        """Add the nets of ``root`` (children first), its control places named ``root_name.*``.

        Depth-first with an explicit stack, not recursion: a block of n
        statements is n nested sequences, and missions of 10,000 calls are
        real (long surveys).
        """
        # the names of the instances: one rule, shared with the page's tree view
        names = {id(i.node): i.name for i in instances(root, root_name, scope)}
        # a frame: [node, its instance name, its template, next child, last child's name]
        stack: list[list[Any]] = [[root, root_name, None, 0, None]]
        while stack:
            frame = stack[-1]
            node, name, template, i, last = frame
            if isinstance(node, FCall):
                self.call(node, name, scope, params)
                stack.pop()
                continue
            if template is None:
                template = frame[2] = self.lib.get(STRUCTURE_TEMPLATE[node.kind])
            if i:   # child i-1 is complete: fuse it into its slot
                self.a.groups += [[f"{last}.{p}", f"{name}.{template.children[i - 1]}_{p}"]
                                  for p in CONTROL]
            if i < min(len(template.children), len(node.children)):
                child = node.children[i]
                child_name = names[id(child)]
                frame[3], frame[4] = i + 1, child_name
                stack.append([child, child_name, None, 0, None])
            else:
                net = self._structures.get(template.name)
                if net is None:
                    net = self._structures[template.name] = at_rest(template.net)
                self.a.parts.append((name, net))
                stack.pop()

    def call(self, node: FCall, name: str, scope: str, params: tuple[str, ...]) -> None:
        """A call site, fused with the callee's control places, gate and primitive locks."""
        target = self.c.tasks.get(node.name) or self.c.functions[node.name]
        binding = tuple((p, _expr(v, params, self.c.consts))
                        for p, v in zip(target.params, node.args))
        # the scope says where the arguments' parameters live: the function
        # whose body holds this call, or the mission (no parameters)
        enter = TransitionPayload(
            doc=f"the callee is free: enter {node.name} with these arguments",
            entry=CallEntry(node.name, scope or MISSION, binding))
        proto = self._call_sites.get(node.name)
        if proto is None:
            proto = self._call_sites[node.name] = self.call_site(node.name)
        self.a.parts.append((name, proto.with_payloads({ENTER: enter.to_json()})))
        self.a.groups += [[f"{node.name}.{p}", f"{name}.to.{p}"]
                          for p in ("GATE", *CONTROL) if p != "MTX"]
        for prim in self._locks(node.name):
            self.a.groups.append([f"{prim}.LOCK", f"{name}.lock.{prim}"])

    def _locks(self, callee: str) -> list[str]:
        """The primitives whose locks a call of ``callee`` takes (a task's, and none reduced)."""
        task = self.c.tasks.get(callee)
        return sorted({p.name for p in task.primitives}) if task and not self.reduced else []

    def call_site(self, callee: str) -> Net:
        """The call-site net of ``callee``; each call stamps its arguments on ``enter``."""
        return call_site_net(callee, self._locks(callee))

    # -- the whole mission -------------------------------------------------------------------

    def compile(self) -> Net:
        for prim in self.used_primitives:
            self.a.parts.append((prim, self.primitive_net(prim)))
        for task in self.c.tasks.values():
            own, groups = self.task_net(task)
            self.a.parts.append((task.name, own))
            self.a.groups += groups
        for fname in self.c.function_order:
            f = self.c.functions[fname]
            self.instance(function_expression(f), fname, fname, f.params)
            gate = NetBuilder("gate")
            gate.place("GATE", 1, payload=payloads.place_payload(GATE_DOC))
            self.a.parts.append((fname, gate.build()))
        self.instance(mission_expression(self.c.mission), MISSION, "", ())
        # the root is added last; its B is where the mission starts
        prefix, root = self.a.parts[-1]
        assert prefix == MISSION
        begin = MissionPlace.B.value
        self.a.parts[-1] = (prefix, root.with_initial({**root.initial, begin: 1}))
        return compose(self.a.parts, self.a.groups, name=self._name())

    def _name(self) -> str:
        stem = self.c.program.file.rsplit("/", 1)[-1]
        return stem[:-4] if stem.endswith(".mcl") else stem or "mission"


def call_site_net(callee: str, locks: Sequence[str]) -> Net:
    """The call-site net of ``callee`` taking the locks of the primitives ``locks``: it
    waits for the callee's gate and the locks, takes them all at once, enters the shared
    net, passes an abort on, routes the result back and gives everything back (see the
    module's documentation)."""
    b = NetBuilder(callee)
    for p in CONTROL:
        b.place(p, 1 if p == "MTX" else 0, interface=p)
    b.place("IN", payload=payloads.place_payload(f"inside {callee}"))
    b.place("ABT", payload=payloads.place_payload(f"abort passed on to {callee}"))
    for p in ("GATE", *CONTROL):
        if p != "MTX":
            b.place(f"to.{p}", interface=f"{callee}.{p}")
    for prim in locks:
        b.place(f"lock.{prim}", interface=f"{prim}.LOCK")
    enter = b.transition(ENTER)
    for p in ("B", "MTX", "to.GATE", *(f"lock.{x}" for x in locks)):
        b.arc(p, enter)
    b.arc(enter, "to.B")
    b.arc(enter, "IN")
    t = b.transition("pending_abort", payload=_doc("aborted before it started"))
    b.arc("B", t)
    b.arc("A", t)
    b.arc(t, "ABORTED")
    t = b.transition("abort", payload=_doc(f"pass the abort on to {callee}"))
    b.arc("IN", t)
    b.arc("A", t)
    b.arc(t, "to.A")
    b.arc(t, "ABT")

    def leave(tid: str, inputs: list[str], result: str, doc: str) -> None:
        t = b.transition(tid, payload=_doc(doc))
        for p in inputs:
            b.arc(p, t)
        for p in (result, "MTX", "to.GATE", *(f"lock.{x}" for x in locks)):
            b.arc(t, p)

    for r in ("OK", "FAIL"):
        leave(f"return_{r}", ["IN", f"to.{r}"], r, f"{callee} ended {r}")
    leave("return_ABORTED", ["ABT", "to.ABORTED"], "ABORTED", f"{callee} aborted")
    for r in ("OK", "FAIL"):
        leave(f"drain_{r}", ["ABT", f"to.{r}", "to.A"], "ABORTED",
              f"{callee} ended {r} before the abort reached it: drain its A")
    return b.build()


@without_gc
def compile_checked(checked: Checked, library: Library | None = None, *,
                    reduced: bool = False) -> Net:
    """One composed P/T net for a checked MCL program (from ``mission.B``, ``mission.MTX``).

    ``reduced``: every task is the paper's reduced model (Fig. 3, section
    2.3: started by B, ends in OK, FAIL or ABORTED, no primitive), the way
    the paper analyses structures; the mission's control flow alone, for
    teaching and for a smaller state space. It cannot be run on a vehicle.
    """
    return Compiler(checked, library, reduced).compile()
