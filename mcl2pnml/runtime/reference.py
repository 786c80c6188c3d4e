"""The reference engine: MCL run directly by the rules of ``shared/spec/mcl.md``, no Petri net.

It exists to judge the executor (and to be judged by it): the same mission,
the same vehicle, and both engines must give the same outcome, time and
trace. It reads the checked program, not the compiled net, and keeps one
small state machine per running statement:

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

import heapq
from collections import deque
from typing import Any, Callable

from mcl2pnml.language import ast
from mcl2pnml.runtime.aal import Action, ActionKind, Event, EventKind
from mcl2pnml.runtime.engine import Engine, Outcome
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.language.checker import Checked

OK, FAIL, ABORTED = "OK", "FAIL", "ABORTED"
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
    def __init__(self, checked: Checked):
        self.c = checked
        for task in checked.tasks.values():
            if task.pattern not in PATTERNS:
                raise Mcl2PnmlError(
                    f"the reference engine runs the patterns {', '.join(PATTERNS)}; task "
                    f"'{task.name}' uses '{task.pattern}' (run it with --engine petri)")
        self.now = 0.0
        self.steps: deque[Callable[[], None]] = deque()
        self.actions: list[Action] = []
        self.outcome: Outcome | None = None
        self.ignored: list[tuple[Event, str]] = []
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

        def finish(result: str) -> None:
            self.outcome = Outcome(result)
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

    @staticmethod
    def _accept(prim: _Primitive, kind: EventKind) -> str | None:
        """Apply an event to the primitive as its net would; the reason if it would not."""
        nothing = f"nothing waits for '{kind.value}' from '{prim.name}' now"
        if kind is EventKind.ON:
            if prim.request is not ActionKind.ENABLE or prim.on:
                return nothing
            prim.on, prim.request = True, None
        elif kind is EventKind.OFF:
            if prim.request is not ActionKind.DISABLE or not prim.on:
                return nothing
            prim.on, prim.request, prim.goal = False, None, "C"
        elif kind is EventKind.ACHIEVED:
            if not prim.on or prim.goal == "S2":
                return nothing
            prim.goal = "S2"
        else:
            if not prim.on or prim.goal == "S1":
                return nothing
            prim.goal = "S1"
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

    def primitives_used(self) -> set[str]:
        """The primitives the mission enables (the vehicle must offer them)."""
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

Done = Callable[[str], None]


class _Node:
    """A running statement: started once, aborted at most once, reports one result."""

    def __init__(self, engine: ReferenceEngine, env: dict[str, Any], done: Done):
        self.e, self.env, self.done_cb = engine, env, done
        self.ended = False
        self.aborted = False

    def start(self) -> None:
        raise NotImplementedError

    def abort(self) -> None:
        raise NotImplementedError

    def done(self, result: str) -> None:
        if not self.ended:
            self.ended = True
            self.done_cb(result)


def _statement(engine: ReferenceEngine, stmt: ast.Statement, env: dict[str, Any],
               done: Done) -> _Node:
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
    """NULL, an empty block: ends OK at once (ABORTED if aborted before it started)."""

    def start(self) -> None:
        self.done(ABORTED if self.aborted else OK)

    def abort(self) -> None:
        self.aborted = True


class _Sequence(_Node):
    """A statement, then the rest of its block; the first result that is not OK ends it."""

    def __init__(self, engine, first, rest, env, done):
        super().__init__(engine, env, done)
        self.parts, self.i, self.child = [first, rest], 0, None

    def start(self) -> None:
        if self.aborted:
            return self.done(ABORTED)
        self.next()

    def next(self) -> None:
        if self.aborted:   # aborted between one statement's end and the next one's start
            return self.done(ABORTED)
        stmt = self.parts[self.i]
        self.i += 1
        self.child = _statement(self.e, stmt, self.env, self.child_done)
        self.e.later(self.child.start)

    def child_done(self, result: str) -> None:
        if self.aborted:
            return self.done(ABORTED)
        if result != OK:
            return self.done(result)
        if self.i == len(self.parts):
            return self.done(OK)
        self.e.later(self.next)

    def abort(self) -> None:
        if self.ended or self.aborted:
            return
        self.aborted = True
        if self.child is not None:
            child = self.child
            self.e.later(child.abort)
        # not yet started: start() sees it and ends ABORTED


class _Parallel(_Node):
    """All at once; ends when all have ended: OK if all OK, else FAIL."""

    def __init__(self, engine, items, env, done):
        super().__init__(engine, env, done)
        self.items, self.children, self.results = items, [], {}

    def start(self) -> None:
        if self.aborted:
            return self.done(ABORTED)
        for k, stmt in enumerate(self.items):
            child = _statement(self.e, stmt, self.env, lambda r, k=k: self.child_done(k, r))
            self.children.append(child)
            self.e.later(child.start)

    def child_done(self, k: int, result: str) -> None:
        self.results[k] = result
        if len(self.results) < len(self.items):
            return
        if self.aborted:
            return self.done(ABORTED)
        self.done(OK if all(r == OK for r in self.results.values()) else FAIL)

    def abort(self) -> None:
        if self.ended or self.aborted:
            return
        self.aborted = True
        for k, child in enumerate(self.children):
            if k not in self.results:
                self.e.later(child.abort)


class _Monitor(_Node):
    """Both at once; the first to end stops the other (mcl.md's rules for the result)."""

    def __init__(self, engine, stmt, env, done):
        super().__init__(engine, env, done)
        self.stmt, self.first, self.result = stmt, None, None
        self.children: list[_Node] = []
        self.stopped = 0

    def start(self) -> None:
        if self.aborted:
            return self.done(ABORTED)
        for k, stmt in enumerate((self.stmt.watched, self.stmt.watcher)):
            child = _statement(self.e, stmt, self.env, lambda r, k=k: self.child_done(k, r))
            self.children.append(child)
        for child in self.children:
            self.e.later(child.start)

    def child_done(self, k: int, result: str) -> None:
        self.stopped += 1
        if self.first is None and not self.aborted:
            self.first = k
            # the watched one first: FAIL; the watcher first: its result
            self.result = FAIL if k == 0 else (OK if result == OK else FAIL)
            other = self.children[1 - k]
            self.e.later(other.abort)
            return
        if self.stopped == 2:
            self.done(ABORTED if self.aborted and self.first is None else self.result)

    def abort(self) -> None:
        if self.ended or self.aborted:
            return
        if self.first is not None:
            return   # already stopping its other child: the result stands
        self.aborted = True
        for child in self.children:
            if not child.ended:
                self.e.later(child.abort)


class _If(_Node):
    """The condition, then the then-block (OK) or the else-block (FAIL; absent: OK)."""

    def __init__(self, engine, stmt, env, done):
        super().__init__(engine, env, done)
        self.stmt, self.child = stmt, None

    def start(self) -> None:
        if self.aborted:
            return self.done(ABORTED)
        self.child = _statement(self.e, self.stmt.condition, self.env, self.condition_done)
        self.e.later(self.child.start)

    def condition_done(self, result: str) -> None:
        if self.aborted:
            return self.done(ABORTED)
        branch = self.stmt.then if result == OK else (self.stmt.otherwise or ast.Block(()))
        self.child = _statement(self.e, branch, self.env, self.branch_done)
        self.e.later(self.child.start)

    def branch_done(self, result: str) -> None:
        self.done(ABORTED if self.aborted else result)

    def abort(self) -> None:
        if self.ended or self.aborted:
            return
        self.aborted = True
        if self.child is not None:
            child = self.child
            self.e.later(child.abort)


class _While(_Node):
    """The condition; FAIL ends the loop OK, OK runs the body; a failed body fails the loop."""

    def __init__(self, engine, stmt, env, done):
        super().__init__(engine, env, done)
        self.stmt, self.child = stmt, None

    def start(self) -> None:
        if self.aborted:
            return self.done(ABORTED)
        self.test()

    def test(self) -> None:
        if self.aborted:   # aborted between the body's end and the next test
            return self.done(ABORTED)
        self.child = _statement(self.e, self.stmt.condition, self.env, self.condition_done)
        self.e.later(self.child.start)

    def condition_done(self, result: str) -> None:
        if self.aborted:
            return self.done(ABORTED)
        if result != OK:
            return self.done(OK)
        self.child = _statement(self.e, self.stmt.body, self.env, self.body_done)
        self.e.later(self.child.start)

    def body_done(self, result: str) -> None:
        if self.aborted:
            return self.done(ABORTED)
        if result == OK:
            self.e.later(self.test)
        else:
            self.done(FAIL)

    def abort(self) -> None:
        if self.ended or self.aborted:
            return
        self.aborted = True
        if self.child is not None:
            child = self.child
            self.e.later(child.abort)


class _Call(_Node):
    """A call: wait for the callee (and a task's primitives), run it, pass an abort on."""

    def __init__(self, engine, call: ast.Call, env, done):
        super().__init__(engine, env, done)
        self.call = call
        self.rank = engine.ordinals[id(call)]
        self.task = engine.c.tasks.get(call.name)
        target = self.task or engine.c.functions[call.name]
        self.args = {p: _value(v, env, engine.c.consts) for p, v in zip(target.params, call.args)}
        prims = sorted({p.name for p in self.task.primitives}) if self.task else []
        self.needs = [call.name, *prims]
        self.inner: _Node | None = None
        self.state = "new"

    def start(self) -> None:
        if self.aborted:
            return self.done(ABORTED)
        self.state = "waiting"
        self.e.request(self)

    def enter(self) -> None:
        self.state = "inside"
        if self.task is not None:
            self.inner = _TaskRun(self.e, self.task, self.args, self.returned)
        else:
            body = self.e.c.functions[self.call.name].body
            self.inner = _statement(self.e, body, self.args, self.returned)
        self.e.later(self.inner.start)

    def returned(self, result: str) -> None:
        self.state = "done"
        self.e.release(self.needs)
        self.done(ABORTED if self.aborted else result)

    def abort(self) -> None:
        if self.ended or self.aborted:
            return
        self.aborted = True
        if self.state == "waiting":
            self.e.waiting_calls.remove(self)
            self.state = "done"
            self.done(ABORTED)    # it never started
        elif self.state == "inside":
            inner = self.inner
            self.e.later(inner.abort)


class _TaskRun(_Node):
    """A task inside: enable, wait for the goal (or the time-out or an abort), disable."""

    def __init__(self, engine, task: ast.Task, env, done):
        super().__init__(engine, env, done)
        self.task = task
        self.rules = PATTERNS[task.pattern]
        self.prims = [engine.prims[p.name] for p in task.primitives]
        self.state = "new"        # running, stopping
        self.result: str | None = None
        self.timer: int | None = None
        self.abort_pending = False

    def start(self) -> None:
        if self.abort_pending:       # aborted before it started (the net's t11)
            return self.done(ABORTED)
        self.state = "running"
        for call, prim in zip(self.task.primitives, self.prims):
            prim.user = self
            prim.request = ActionKind.ENABLE
            self.e.act(ActionKind.ENABLE, prim.name,
                       tuple(_value(v, self.env, self.e.c.consts) for v in call.args))

    def all_on(self) -> bool:
        return all(p.on for p in self.prims)

    def primitive_changed(self, prim: _Primitive, kind: EventKind) -> None:
        if self.state == "running":
            if kind is EventKind.ON and self.all_on():
                if self.task.timeout is not None:
                    self.timer = self.e.set_timer(self, float(self.task.timeout.value))
                if self.abort_pending:
                    return self.stop(ABORTED)
            if self.all_on() or kind is not EventKind.ON:
                self.check_goal()
        elif self.state == "stopping" and kind is EventKind.OFF:
            if not any(p.on for p in self.prims):
                for p in self.prims:
                    p.user = None
                self.done(self.result)

    def check_goal(self) -> None:
        if any(p.goal == "S1" for p in self.prims) and self.others_on():
            return self.stop(FAIL)
        if self.rules["achieved"] is not None and all(p.goal == "S2" for p in self.prims):
            return self.stop(self.rules["achieved"])

    def others_on(self) -> bool:
        # KeepTwoGoals' t04P needs Q on (and t04Q needs P on)
        return all(p.on for p in self.prims)

    def timed_out(self) -> None:
        if self.state == "running":
            self.timer = None
            self.stop(self.rules["timeout"])

    def stop(self, result: str) -> None:
        self.state = "stopping"
        self.result = result
        self.e.cancel_timer(self.timer)
        self.timer = None
        for prim in self.prims:
            prim.request = ActionKind.DISABLE
            self.e.act(ActionKind.DISABLE, prim.name)

    def abort(self) -> None:
        if self.state == "new":
            self.abort_pending = True
            return
        if self.state != "running":
            return    # stopping already: the result stands (the call reports ABORTED)
        if self.all_on():
            self.stop(ABORTED)
        else:
            self.abort_pending = True   # the net's t07 waits for the primitive to be on
