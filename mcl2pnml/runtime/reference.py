"""The reference engine: MCL run directly by the rules of ``docs/mcl.md``, no Petri net.

It exists to judge the executor (and to be judged by it): the same mission,
the same vehicle, and both engines must give the same outcome, time and
trace. It reads the checked program, not the compiled net, and keeps one
small state machine per running statement. Their lifecycle is one for all
(:class:`_Node`, its phases :class:`Phase`); what differs is what each does:

* a **call** waits until its task or function is free, and a task also
  until its primitives are (all at once), then runs it with the call's
  arguments; calls enter only when nothing else is left to do at the
  instant, the first in program order first; aborted while waiting it ends
  ABORTED without starting, aborted later it ends ABORTED once its callee
  has stopped;
* a **task** enables its primitives, starts its time-out when they are all
  on, and ends when its pattern says so, after it has disabled them and
  they are off (mcl.md, "Results");
* a **block** runs its statements in order, **parallel** all at once,
  **monitor** both with the rules of mcl.md, **if** and **while** their
  condition first; aborting any of them aborts what it is running.

Everything a stimulus causes at one instant is done through a first-in,
first-out queue of steps, in the order it was caused; this matches the
executor's rule that the transition enabled longest fires first.

The primitives are tracked as the vehicle primitive net of Fig. 1 is
(off or on; seeking, failed or achieved), so that an event the net would
not accept is ignored here too, with the same reason.
"""
from __future__ import annotations

import enum
import heapq
from abc import ABC, abstractmethod
from collections import deque
from typing import Any, Callable

from mcl2pnml.language import ast
from mcl2pnml.runtime.aal import Action, ActionKind, Event, EventKind
from mcl2pnml.runtime.engine import Engine, Outcome
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.language.semantics import Checked

# a statement ends in one of the outcomes of a whole mission (mcl.md, "Results")
OK, FAIL, ABORTED = Outcome.OK, Outcome.FAIL, Outcome.ABORTED
#: How each pattern ends: on the time-out, and when a primitive achieves its goal.
PATTERNS = {
    "AchieveGoal": {"timeout": FAIL, "achieved": OK},
    "KeepGoal": {"timeout": OK, "achieved": None},
    "KeepTwoGoals": {"timeout": OK, "achieved": None},
}
#: Steps allowed at one instant before the run is stopped as a zero-time loop.
ZENO_LIMIT = 1_000_000


class _Primitive:
    """The state of one vehicle primitive, as the primitive net of Fig. 1 has it."""

    def __init__(self, name: str):
        self.name = name
        self.on = False
        self.request: ActionKind | None = None    # E or D marked, not yet answered
        self.goal = "C"                            # C, S1 (failed), S2 (achieved)
        self.user: "_TaskRun | None" = None


class ReferenceEngine(Engine):
    """Runs a checked program statement by statement (see the module's documentation)."""

    def __init__(self, checked: Checked):
        super().__init__()
        self.c = checked
        for task in checked.tasks.values():
            if task.pattern not in PATTERNS:
                raise Mcl2PnmlError(
                    f"the reference engine runs the patterns {', '.join(PATTERNS)}; task "
                    f"'{task.name}' uses '{task.pattern}' (run it with --engine petri)")
        self.now = 0.0
        self.steps: deque[Callable[[], None]] = deque()
        #: results reported and not yet delivered to the parents (see :meth:`_Node.end`)
        self.reports: deque[tuple["_Node", Outcome]] = deque()
        self.actions: list[Action] = []
        self.prims = {name: _Primitive(name) for name in checked.primitives}
        self.busy: set[str] = set()                # tasks, functions and primitives in use
        self.waiting_calls: list["_Call"] = []
        self.timers: list[tuple[float, str, int]] = []
        self.timer_owner: dict[int, "_TaskRun"] = {}
        self.timer_ids = 0
        self.ordinals = self._call_ordinals()

    # -- program order of calls: who enters first when several wait -----------------

    def _call_ordinals(self) -> dict[int, int]:
        """Call statement (by id) -> its rank: functions' bodies (callees first), then the mission."""
        order: list[ast.Call] = []

        def walk(stmt: ast.Statement) -> None:
            stack = [stmt]
            while stack:
                s = stack.pop()
                if isinstance(s, ast.Call):
                    order.append(s)
                    continue
                if isinstance(s, ast.Block):
                    kids = list(s.body)
                elif isinstance(s, ast.Parallel):
                    kids = list(s.items)
                elif isinstance(s, ast.Monitor):
                    kids = [s.watched, s.watcher]
                elif isinstance(s, ast.If):
                    kids = [s.condition, s.then] + ([s.otherwise] if s.otherwise else [])
                else:
                    kids = [s.condition, s.body]
                stack.extend(reversed(kids))

        for name in self.c.function_order:
            walk(self.c.functions[name].body)
        walk(self.c.mission.body)
        return {id(call): rank for rank, call in enumerate(order)}

    # -- the step queue ------------------------------------------------------------------

    def later(self, step: Callable[[], None]) -> None:
        self.steps.append(step)

    def _settle(self) -> list[Action]:
        done = 0
        while self.outcome is None:
            if self.steps:
                self.steps.popleft()()
            elif not self.grant():
                break
            done += 1
            if done > ZENO_LIMIT:
                raise Mcl2PnmlError(
                    f"the mission fires for ever at t={self.now:g} s without time passing "
                    "(a while loop whose condition and body end at once?)")
        out, self.actions = self.actions, []
        return out

    def act(self, kind: ActionKind, prim: str, args: tuple = ()) -> None:
        self.actions.append(Action(self.now, kind, prim, args))

    # -- resources: one call inside a task or function, one task on a primitive --------

    def request(self, call: "_Call") -> None:
        self.waiting_calls.append(call)

    def release(self, names: list[str]) -> None:
        self.busy.difference_update(names)

    def grant(self) -> bool:
        """At quiescence: let the first waiting call (program order) that can enter in.

        As the executor fires call entries only when nothing else can fire,
        and the first in program order: whatever order the instant unfolded
        in, the call written first gets a free task.
        """
        for call in sorted(self.waiting_calls, key=lambda c: c.rank):
            if not (set(call.needs) & self.busy):
                # taking the callee and its primitives and entering are one
                # step, as the call site's enter transition is
                self.busy.update(call.needs)
                self.waiting_calls.remove(call)
                call.enter()
                return True
        return False

    # -- the engine interface ------------------------------------------------------------

    def start(self, t: float) -> list[Action]:
        self.now = t

        def finish(_: _Node, result: Outcome) -> None:
            self.outcome = result
        root = _statement(self, self.c.mission.body, {}, finish)
        self.later(root.start)
        return self._settle()

    def on_event(self, event: Event) -> list[Action]:
        self.now = event.t
        prim = self.prims.get(event.primitive)
        if prim is None or prim.name not in self._used():
            self.ignored.append((event, f"no primitive '{event.primitive}' in this mission"))
            return []
        reason = self._accept(prim, event.kind)
        if reason:
            self.ignored.append((event, reason))
            return []
        if prim.user is not None:
            user = prim.user
            self.later(lambda: user.primitive_changed(prim, event.kind))
        return self._settle()

    def _used(self) -> set[str]:
        return {p.name for t in self.c.tasks.values() for p in t.primitives}

    def waits_for(self, event: Event) -> bool:
        prim = self.prims.get(event.primitive)
        return prim is not None and prim.name in self._used() \
            and self._refusal(prim, event.kind) is None

    @staticmethod
    def _refusal(prim: _Primitive, kind: EventKind) -> str | None:
        """Why the primitive's net would not take the event now (None: it would)."""
        if kind is EventKind.ON:
            taken = prim.request is ActionKind.ENABLE and not prim.on
        elif kind is EventKind.OFF:
            taken = prim.request is ActionKind.DISABLE and prim.on
        else:
            taken = prim.on and prim.goal != ("S2" if kind is EventKind.ACHIEVED else "S1")
        return None if taken else f"nothing waits for '{kind.value}' from '{prim.name}' now"

    @classmethod
    def _accept(cls, prim: _Primitive, kind: EventKind) -> str | None:
        """Apply an event to the primitive as its net would; the reason if it would not."""
        reason = cls._refusal(prim, kind)
        if reason:
            return reason
        if kind is EventKind.ON:
            prim.on, prim.request = True, None
        elif kind is EventKind.OFF:
            prim.on, prim.request, prim.goal = False, None, "C"
        else:
            prim.goal = "S2" if kind is EventKind.ACHIEVED else "S1"
        return None

    def set_timer(self, task: "_TaskRun", seconds: float) -> int:
        self.timer_ids += 1
        heapq.heappush(self.timers, (self.now + seconds, task.task.name, self.timer_ids))
        self.timer_owner[self.timer_ids] = task
        return self.timer_ids

    def cancel_timer(self, ident: int | None) -> None:
        if ident is not None:
            self.timer_owner.pop(ident, None)

    def next_timer(self) -> tuple[float, str] | None:
        while self.timers and self.timers[0][2] not in self.timer_owner:
            heapq.heappop(self.timers)
        return (self.timers[0][0], self.timers[0][1]) if self.timers else None

    def fire_timer(self, t: float, name: str) -> list[Action]:
        _, _, ident = heapq.heappop(self.timers)
        self.now = t
        task = self.timer_owner.pop(ident)
        self.later(task.timed_out)
        return self._settle()

    def timeout_of(self, task: str) -> float | None:
        declared = self.c.tasks.get(task)
        return None if declared is None or declared.timeout is None \
            else float(declared.timeout.value)

    def primitives_used(self) -> set[str]:
        # the primitives of its tasks, whether or not a call reaches them
        return self._used()

    def waiting(self) -> list[str]:
        out = []
        for name in sorted(self.prims):
            p = self.prims[name]
            if p.user is not None:
                wanted = ("on" if p.request is ActionKind.ENABLE else
                          "off" if p.request is ActionKind.DISABLE else "achieved' or 'failed")
                out.append(f"{name}: waits for the vehicle's '{wanted}'")
        for due, task, ident in sorted(self.timers):
            if ident in self.timer_owner:
                out.append(f"{task}: its time-out at t={due:g} s")
        if self.waiting_calls:
            out.append("calls waiting to enter: " + ", ".join(c.call.name
                                                              for c in self.waiting_calls))
        return out


# ---------------------------------------------------------------------------
# running statements

class Phase(enum.Enum):
    """Where a running statement is in its life (mcl.md, "Results")."""

    NEW = enum.auto()
    """Made, its start step queued. An abort now is only noted: when its start
    step comes, the statement ends ABORTED without doing anything (mcl.md's
    abort rule: a call still waiting to enter never starts)."""

    RUNNING = enum.auto()
    """Started: it runs its children (a task, its primitives). An abort now is
    passed on to what it runs, and it ends ABORTED once that has stopped."""

    STOPPING = enum.auto()
    """Its result is decided; it waits for what still runs to stop (a
    monitor's other statement, a task's primitives going off). An abort now
    changes nothing: the result stands (the paper's equations 17 and 18)."""

    ENDED = enum.auto()
    """It has reported its one result to its parent; nothing changes it any more."""


#: What a statement calls with its result: its parent's :meth:`_Node.child_ended`.
Ended = Callable[["_Node", Outcome], None]


class _Node(ABC):
    """A running statement: started once, aborted at most once, reports one result.

    The lifecycle is the same for every statement (mcl.md, "Results", the
    abort rule) and is written here once: :meth:`start`, :meth:`abort`,
    :meth:`child_ended`, :meth:`end`. What a statement does is in three hooks:
    :meth:`begin` when it starts, :meth:`on_child_end` when one of its
    children ends (while it is neither aborted nor stopping), and
    :meth:`on_abort` when it is aborted while running.
    """

    def __init__(self, engine: ReferenceEngine, env: dict[str, Any], done: Ended):
        self.e, self.env, self.done_cb = engine, env, done
        self.phase = Phase.NEW
        self.aborted = False
        self.result: Outcome | None = None     # decided, while STOPPING
        self.running: list[_Node] = []          # children started and not ended, in order

    # -- the lifecycle -------------------------------------------------------------------

    def start(self) -> None:
        """Its start step: aborted before it, the statement ends ABORTED and does nothing."""
        if self.aborted:
            return self.end(ABORTED)
        self.phase = Phase.RUNNING
        self.begin()

    def abort(self) -> None:
        """Abort it: once, and only until its result is decided (mcl.md, "Results", abort)."""
        if self.aborted or self.phase in (Phase.STOPPING, Phase.ENDED):
            return
        self.aborted = True
        if self.phase is Phase.RUNNING:
            self.on_abort()

    def child_ended(self, child: _Node, result: Outcome) -> None:
        """A child's result. Aborted or stopping, the statement only drains: it ends
        when nothing it runs is left, ABORTED or with its decided result."""
        self.running.remove(child)
        if self.aborted or self.phase is Phase.STOPPING:
            if not self.running:
                self.end(ABORTED if self.aborted else self.result)
            return
        self.on_child_end(child, result)

    def end(self, result: Outcome) -> None:
        """Report the result to the parent; any later end is ignored: one result each.

        The report goes up the chain of callers without recursion: a chain of
        thousands of functions, each calling the next, ends as thousands of
        nested statements, far deeper than Python's stack. Every ``end`` is the
        last thing its caller does (a tail call), so a report made while
        another is being delivered can wait until that one returns: the order
        of effects is the one direct calls would give.
        """
        if self.phase is Phase.ENDED:
            return
        self.phase = Phase.ENDED
        pending = self.e.reports
        pending.append((self, result))
        if len(pending) > 1:
            return           # an outer end is delivering: this report is next
        try:
            while pending:
                node, outcome = pending[0]
                node.done_cb(node, outcome)
                pending.popleft()
        finally:
            pending.clear()

    # -- what the statements use ---------------------------------------------------------

    def run(self, stmt: ast.Statement, env: dict[str, Any] | None = None) -> _Node:
        """Run ``stmt`` as a child (in this statement's scope unless ``env`` is given)."""
        return self.adopt(_statement(self.e, stmt, self.env if env is None else env,
                                     self.child_ended))

    def adopt(self, child: _Node) -> _Node:
        # its start is a step of its own, after those already queued: the
        # order in which the net's transitions become enabled
        self.running.append(child)
        self.e.later(child.start)
        return child

    def after(self, step: Callable[[], None]) -> None:
        """Queue this statement's next step (a block's next statement, a loop's next test).

        Aborted between one step's end and the next one's start, with nothing
        running, the statement ends ABORTED instead of taking the step.
        """
        def go() -> None:
            if self.aborted:
                return self.end(ABORTED)
            step()
        self.e.later(go)

    def settle(self, result: Outcome) -> None:
        """The result is decided: stop what still runs; it is reported once that has ended."""
        self.phase = Phase.STOPPING
        self.result = result
        self.abort_children()

    def abort_children(self) -> None:
        for child in self.running:
            self.e.later(child.abort)

    # -- the hooks -----------------------------------------------------------------------

    @abstractmethod
    def begin(self) -> None:
        """What the statement does when it starts (not aborted before)."""

    def on_child_end(self, child: _Node, result: Outcome) -> None:
        """A child ended while the statement runs: by default its result is the statement's."""
        self.end(result)

    def on_abort(self) -> None:
        """Aborted while running: by default, abort every child still running."""
        self.abort_children()


def _statement(engine: ReferenceEngine, stmt: ast.Statement, env: dict[str, Any],
               done: Ended) -> _Node:
    """The running form of a statement, nested as mcl.md's functional form nests it.

    A block of one statement is that statement, an empty one NULL, a longer
    one its first statement followed by the rest; ``parallel`` of three is
    ``parallel`` of one and the ``parallel`` of two. The same nesting as the
    compiled net's gives the same order of steps at one instant.
    """
    if isinstance(stmt, ast.Call):
        return _Call(engine, stmt, env, done)
    if isinstance(stmt, ast.Block):
        if not stmt.body:
            return _Null(engine, env, done)
        if len(stmt.body) == 1:
            return _statement(engine, stmt.body[0], env, done)
        return _Sequence(engine, stmt.body[0], ast.Block(stmt.body[1:], stmt.pos), env, done)
    if isinstance(stmt, ast.Parallel):
        rest = stmt.items[1] if len(stmt.items) == 2 else ast.Parallel(stmt.items[1:], stmt.pos)
        return _Parallel(engine, [stmt.items[0], rest], env, done)
    if isinstance(stmt, ast.Monitor):
        return _Monitor(engine, stmt, env, done)
    if isinstance(stmt, ast.If):
        return _If(engine, stmt, env, done)
    return _While(engine, stmt, env, done)


def _value(v: ast.Value, env: dict[str, Any], consts: dict[str, Any]) -> Any:
    if isinstance(v, (ast.Number, ast.String)):
        return v.value
    if isinstance(v, ast.Tuple):
        return tuple(_value(i, env, consts) for i in v.items)
    return env[v.name] if v.name in env else consts[v.name]


class _Null(_Node):
    """NULL, an empty block: ends OK at once (mcl.md, "Statements and structures")."""

    def begin(self) -> None:
        self.end(OK)


class _Sequence(_Node):
    """A statement, then the rest of its block: the first result that is not OK ends it
    (mcl.md, "Results", sequence)."""

    def __init__(self, engine, first, rest, env, done):
        super().__init__(engine, env, done)
        self.first, self.rest = first, rest

    def begin(self) -> None:
        self.run(self.first)

    def on_child_end(self, child: _Node, result: Outcome) -> None:
        if result is not OK or self.rest is None:
            return self.end(result)
        rest, self.rest = self.rest, None
        self.after(lambda: self.run(rest))


class _Parallel(_Node):
    """All at once; ends when all have ended: OK if all OK, else FAIL
    (mcl.md, "Results", parallel)."""

    def __init__(self, engine, items, env, done):
        super().__init__(engine, env, done)
        self.items, self.failed = items, False

    def begin(self) -> None:
        for stmt in self.items:
            self.run(stmt)

    def on_child_end(self, child: _Node, result: Outcome) -> None:
        self.failed |= result is not OK
        if not self.running:
            self.end(FAIL if self.failed else OK)


class _Monitor(_Node):
    """Both at once; the first to end decides the result and stops the other
    (mcl.md, "Results", monitor)."""

    def __init__(self, engine, stmt, env, done):
        super().__init__(engine, env, done)
        self.stmt = stmt
        self.watched: _Node | None = None

    def begin(self) -> None:
        self.watched = self.run(self.stmt.watched)
        self.run(self.stmt.watcher)

    def on_child_end(self, child: _Node, result: Outcome) -> None:
        # the watched one first: FAIL; the watcher first: OK only if it ended OK
        self.settle(FAIL if child is self.watched or result is not OK else OK)


class _If(_Node):
    """The condition, then the then-block (OK) or the else-block (FAIL; absent: OK)
    (mcl.md, "Results", if)."""

    def __init__(self, engine, stmt, env, done):
        super().__init__(engine, env, done)
        self.stmt = stmt
        self.condition: _Node | None = None

    def begin(self) -> None:
        self.condition = self.run(self.stmt.condition)

    def on_child_end(self, child: _Node, result: Outcome) -> None:
        if child is not self.condition:
            return self.end(result)     # the branch's result is the if's
        self.run(self.stmt.then if result is OK else (self.stmt.otherwise or ast.Block(())))


class _While(_Node):
    """The condition; FAIL ends the loop OK, OK runs the body; a failed body fails the loop
    (mcl.md, "Results", while)."""

    def __init__(self, engine, stmt, env, done):
        super().__init__(engine, env, done)
        self.stmt = stmt
        self.condition: _Node | None = None

    def begin(self) -> None:
        self.test()

    def test(self) -> None:
        self.condition = self.run(self.stmt.condition)

    def on_child_end(self, child: _Node, result: Outcome) -> None:
        if child is self.condition:
            if result is not OK:
                return self.end(OK)
            self.run(self.stmt.body)
        elif result is OK:
            self.after(self.test)
        else:
            self.end(FAIL)


class _Call(_Node):
    """A call: wait for the callee (and a task's primitives), run it, pass an abort on
    (mcl.md, "Sharing", and "Results", abort)."""

    def __init__(self, engine, call: ast.Call, env, done):
        super().__init__(engine, env, done)
        self.call = call
        self.rank = engine.ordinals[id(call)]
        self.task = engine.c.tasks.get(call.name)
        target = self.task or engine.c.functions[call.name]
        self.args = {p: _value(v, env, engine.c.consts) for p, v in zip(target.params, call.args)}
        prims = sorted({p.name for p in self.task.primitives}) if self.task else []
        self.needs = [call.name, *prims]
        self.inner: _Node | None = None     # None: still waiting to enter

    def begin(self) -> None:
        self.e.request(self)

    def enter(self) -> None:
        """The engine's :meth:`~ReferenceEngine.grant`: the callee is ours, run it."""
        if self.task is not None:
            self.inner = self.adopt(_TaskRun(self.e, self.task, self.args, self.child_ended))
        else:
            self.inner = self.run(self.e.c.functions[self.call.name].body, self.args)

    def child_ended(self, child: _Node, result: Outcome) -> None:
        self.e.release(self.needs)     # the callee is free again, whatever its result
        super().child_ended(child, result)

    def on_abort(self) -> None:
        if self.inner is None:         # still waiting: it never starts
            self.e.waiting_calls.remove(self)
            return self.end(ABORTED)
        super().on_abort()


class _TaskRun(_Node):
    """A task inside: enable, wait for the goal (or the time-out or an abort), disable
    (mcl.md, "Results", task; the pattern's template net)."""

    def __init__(self, engine, task: ast.Task, env, done):
        super().__init__(engine, env, done)
        self.task = task
        self.rules = PATTERNS[task.pattern]
        self.prims = [engine.prims[p.name] for p in task.primitives]
        self.timer: int | None = None

    def begin(self) -> None:
        for call, prim in zip(self.task.primitives, self.prims):
            prim.user = self
            prim.request = ActionKind.ENABLE
            self.e.act(ActionKind.ENABLE, prim.name,
                       tuple(_value(v, self.env, self.e.c.consts) for v in call.args))

    def all_on(self) -> bool:
        return all(p.on for p in self.prims)

    def primitive_changed(self, prim: _Primitive, kind: EventKind) -> None:
        if self.phase is Phase.RUNNING:
            if kind is EventKind.ON and self.all_on():
                if self.task.timeout is not None:
                    self.timer = self.e.set_timer(self, float(self.task.timeout.value))
                if self.aborted:
                    return self.stop(ABORTED)
            if self.all_on() or kind is not EventKind.ON:
                self.check_goal()
        elif self.phase is Phase.STOPPING and kind is EventKind.OFF:
            if not any(p.on for p in self.prims):
                for p in self.prims:
                    p.user = None
                self.end(self.result)

    def check_goal(self) -> None:
        if any(p.goal == "S1" for p in self.prims) and self.others_on():
            return self.stop(FAIL)
        if self.rules["achieved"] is not None and all(p.goal == "S2" for p in self.prims):
            return self.stop(self.rules["achieved"])

    def others_on(self) -> bool:
        # KeepTwoGoals' t04P needs Q on (and t04Q needs P on)
        return all(p.on for p in self.prims)

    def timed_out(self) -> None:
        if self.phase is Phase.RUNNING:
            self.timer = None
            self.stop(self.rules["timeout"])

    def stop(self, result: Outcome) -> None:
        self.settle(result)
        self.e.cancel_timer(self.timer)
        self.timer = None
        for prim in self.prims:
            prim.request = ActionKind.DISABLE
            self.e.act(ActionKind.DISABLE, prim.name)

    def on_abort(self) -> None:
        if self.all_on():
            self.stop(ABORTED)
        # else the net's t07 waits for the primitives to be on: primitive_changed sees the abort
