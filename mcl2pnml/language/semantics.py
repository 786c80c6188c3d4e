"""The checker: names, arities, patterns, recursion; every error of a file at once.

It runs after the parser and before the compiler, and resolves what the
compiler needs: the value of every const, the template of every task's
pattern, the call graph of the functions in an order without cycles.

Each error names file, line and column, shows the line with a caret, and
says what would be valid ("unknown task or function 'Goo'; did you mean
'Go'? declared tasks and functions: Go, Stop").
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable

from mcl2pnml.language import ast
from mcl2pnml.core.bounds import MAX_SECONDS
from mcl2pnml.core.errors import (SHOWN_ERRORS, Location, Mcl2PnmlError, did_you_mean, raise_all,
                                  source_lines)
from mcl2pnml.core.timing import PER_SECOND, finer_than_a_microsecond
from mcl2pnml.core.vocabulary import counted
from mcl2pnml.language.library import Library, default_library
from mcl2pnml.language.declared_properties import property_errors
from mcl2pnml.language.template_parser import Template, TemplateKind

KIND = {ast.Const: "const", ast.Primitive: "primitive", ast.Task: "task",
        ast.Function: "function"}


@dataclass(frozen=True)
class Checked:
    """A program that passed every check, with what the compiler needs resolved."""

    program: ast.Program
    consts: dict[str, Any]                 # name -> value (numbers, strings, tuples)
    primitives: dict[str, ast.Primitive]
    tasks: dict[str, ast.Task]
    patterns: dict[str, Template]          # task name -> its pattern's template
    functions: dict[str, ast.Function]
    function_order: tuple[str, ...]        # callees before callers
    mission: ast.Mission

    def summary(self) -> str:
        """What the program declares, as ``mcl2pnml check`` reports it."""
        return ", ".join([counted(len(self.primitives), "primitive"),
                          counted(len(self.tasks), "task"),
                          counted(len(self.functions), "function"),
                          counted(len(self.consts), "const")])


class _Checker:
    def __init__(self, program: ast.Program, library: Library):
        self.p = program
        self.lib = library
        self.lines = source_lines(program.source)
        self.errors: list[Mcl2PnmlError] = []
        self.names: dict[str, Any] = {}
        self._of_kind: dict[type, list[str]] = {}
        self._users: dict[str, list[str]] | None = None

    def error(self, pos: ast.Pos, message: str) -> None:
        src = self.lines[pos.line - 1] if 0 < pos.line <= len(self.lines) else None
        self.errors.append(Mcl2PnmlError(message, Location(self.p.file, pos.line or None,
                                                           pos.column or None, src)))

    @property
    def said(self) -> bool:
        """Whether the next error is one of those shown (the first :data:`SHOWN_ERRORS`,
        which come first): only those are worth their hint ("did you mean", a cycle), whose
        search costs the size of the program, so that a file broken everywhere is not
        searched once per error."""
        return len(self.errors) < SHOWN_ERRORS

    def of_kind(self, kind) -> list[str]:
        """The names declared of ``kind``, sorted, found once (the declarations are all
        in): :func:`did_you_mean` sorts sorted lists in linear time."""
        if kind not in self._of_kind:
            self._of_kind[kind] = sorted(n for n, d in self.names.items() if isinstance(d, kind))
        return self._of_kind[kind]

    def suggest(self, name: str, valid, what: str) -> str:
        """:func:`did_you_mean` for an error that is shown, else nothing."""
        return did_you_mean(name, valid(), what) if self.said else ""

    # -- declarations ------------------------------------------------------------------

    def declare(self) -> None:
        missions = self.p.of(ast.Mission)
        for d in self.p.declarations:
            if isinstance(d, (ast.Mission, ast.Property)):   # properties: their own names
                continue
            first = self.names.get(d.name)
            if first is not None:
                self.error(d.pos, f"duplicate name '{d.name}': already declared as a "
                                  f"{KIND[type(first)]} on line {first.pos.line}")
                continue
            self.names[d.name] = d
            params = getattr(d, "params", ())
            seen: set[str] = set()
            for name in params:
                if name in seen:
                    self.error(d.pos, f"{KIND[type(d)]} '{d.name}' has two parameters named "
                                      f"'{name}'")
                seen.add(name)
        if not missions:
            line = max(1, len(self.lines))
            self.error(ast.Pos(line, 1), "no mission: a file needs one 'mission { ... }'")
        for extra in missions[1:]:
            self.error(extra.pos, f"a second mission (the first is on line {missions[0].pos.line});"
                                  " a file has exactly one")

    # -- values ------------------------------------------------------------------------

    def const_values(self) -> dict[str, Any]:
        """The value of every const, each const resolved once, in declaration order.

        A const may name another (``const A = B;``), in chains of any length:
        the chain is followed with an explicit stack of evaluations, not by
        recursion, each evaluation a generator that asks for the consts it
        names and is sent their values. A cycle is one error, at the const
        met again.
        """
        values: dict[str, Any] = {}
        visiting: list[str] = []
        on_path: set[str] = set()       # visiting's names: a chain of consts is not searched

        def evaluate(v: ast.Value, where: str):
            if isinstance(v, ast.Number):
                return v.value
            if isinstance(v, ast.String):
                return v.value
            if isinstance(v, ast.Tuple):   # nested at most MAX_NESTING deep (the parser)
                items = []
                for i in v.items:
                    items.append((yield from evaluate(i, where)))
                return tuple(items)
            target = self.names.get(v.name)
            if not isinstance(target, ast.Const):
                self.unknown_value(v, "const " + where, ())
                return None
            return (yield target)

        def resolve(root: ast.Const) -> None:
            stack: list[tuple[ast.Const, Any]] = []

            def enter(c: ast.Const) -> tuple[bool, Any]:
                """(known, its value), or (False, None) when its evaluation is pushed."""
                if c.name in values:
                    return True, values[c.name]
                if c.name in on_path:
                    cycle = visiting[visiting.index(c.name):] + [c.name]
                    self.error(c.pos, f"const '{c.name}' is defined in terms of itself: "
                                      + " -> ".join(cycle))
                    values[c.name] = None
                    return True, None
                visiting.append(c.name)
                on_path.add(c.name)
                stack.append((c, evaluate(c.value, c.name)))
                return False, None

            enter(root)
            sent: Any = None
            while stack:
                c, evaluation = stack[-1]
                try:
                    wanted = evaluation.send(sent)
                except StopIteration as done:
                    stack.pop()
                    on_path.discard(visiting.pop())
                    values[c.name] = sent = done.value
                    continue
                _, sent = enter(wanted)   # pushed: its evaluation starts with None

        for c in self.p.of(ast.Const):
            if self.names.get(c.name) is c:
                resolve(c)
        return values

    def unknown_value(self, v: ast.Ref, where: str, params: Iterable[str]) -> None:
        target = self.names.get(v.name)
        params = list(params)
        if target is not None:
            self.error(v.pos, f"'{v.name}' is a {KIND[type(target)]}, not a value; in {where} "
                              "a value is a const, a literal"
                              + (", or a parameter" if params else ""))
            return
        what = ("parameters and consts" if params else "consts")
        self.error(v.pos, f"undeclared name '{v.name}' in {where}"
                   + self.suggest(v.name, lambda: self.of_kind(ast.Const) + params, what))

    def check_args(self, args: Iterable[ast.Value], params: tuple[str, ...], where: str) -> None:
        for a in args:
            if isinstance(a, ast.Ref):
                if a.name not in params and not isinstance(self.names.get(a.name), ast.Const):
                    self.unknown_value(a, where, params)
            elif isinstance(a, ast.Tuple):
                self.check_args(a.items, params, where)

    def arity(self, pos, kind: str, name: str, params: tuple[str, ...], given: int) -> None:
        if len(params) != given:
            listing = f" ({', '.join(params)})" if params else ""
            self.error(pos, f"{kind} '{name}' takes {counted(len(params), 'argument')}"
                            f"{listing}, given {given}")

    # -- tasks ---------------------------------------------------------------------------

    def tasks(self) -> dict[str, Template]:
        # patterns by their own names (AchieveGoal), not by the CLI's aliases (task)
        patterns = {t.name: t for t in self.lib.unique() if t.kind is TemplateKind.PATTERN}
        out: dict[str, Template] = {}
        for task in self.p.of(ast.Task):
            where = f"task '{task.name}'"
            template = patterns.get(task.pattern)
            if template is None:
                self.error(task.pattern_pos, f"unknown task pattern '{task.pattern}'"
                           + self.suggest(task.pattern, lambda: patterns, "patterns"))
            else:
                out[task.name] = template
                slots = len(template.primitives)
                if slots != len(task.primitives):
                    self.error(task.pattern_pos,
                               f"pattern {task.pattern} takes {counted(slots, 'primitive')}, "
                               f"given {len(task.primitives)}")
            for call in task.primitives:
                prim = self.names.get(call.name)
                if not isinstance(prim, ast.Primitive):
                    if prim is None:
                        self.error(call.pos, f"undeclared primitive '{call.name}'" + self.suggest(
                            call.name, lambda: self.of_kind(ast.Primitive),
                            "declared primitives"))
                    else:
                        self.error(call.pos, f"'{call.name}' is a {KIND[type(prim)]}, not a "
                                             "primitive")
                    continue
                self.arity(call.pos, "primitive", call.name, prim.params, len(call.args))
                self.check_args(call.args, task.params, where)
            # a time-out the engines and the net's timing can all hold: finite (the
            # parser refuses 1e309), within MAX_SECONDS, and a whole number of the
            # microseconds the timed analysis and the TINA export count in
            if task.timeout is not None and not 0 < task.timeout.value <= MAX_SECONDS:
                self.error(task.timeout.pos, f"a timeout is a positive number of seconds, "
                                             f"at most {MAX_SECONDS:,}, not {task.timeout.text}")
            elif task.timeout is not None and finer_than_a_microsecond(task.timeout.value):
                self.error(task.timeout.pos, f"a timeout is a whole number of microseconds "
                                             f"({1 / PER_SECOND:f} s), not {task.timeout.text}")
        return out

    # -- statements ----------------------------------------------------------------------

    def statements(self, stmt: ast.Statement, params: tuple[str, ...], where: str,
                   calls: list[str]) -> None:
        if isinstance(stmt, ast.Call):
            target = self.names.get(stmt.name)
            if isinstance(target, (ast.Task, ast.Function)):
                self.arity(stmt.pos, KIND[type(target)], stmt.name, target.params, len(stmt.args))
                if isinstance(target, ast.Function):
                    calls.append(stmt.name)
            elif target is None:
                self.error(stmt.pos, f"unknown task or function '{stmt.name}'" + self.suggest(
                    stmt.name, lambda: self.of_kind(ast.Task) + self.of_kind(ast.Function),
                    "declared tasks and functions"))
            elif isinstance(target, ast.Primitive):
                users = self.users().get(stmt.name, [])
                hint = (f"; call a task that uses it: {', '.join(users)}" if users else
                        f"; declare a task that uses it, e.g. task Do{stmt.name}() = "
                        f"AchieveGoal({stmt.name}(...));")
                self.error(stmt.pos, f"'{stmt.name}' is a primitive, not a task or function"
                           + hint)
            else:
                self.error(stmt.pos, f"'{stmt.name}' is a {KIND[type(target)]}, not a task or "
                                     "function")
            self.check_args(stmt.args, params, where)
        elif isinstance(stmt, ast.Block):
            for s in stmt.body:
                self.statements(s, params, where, calls)
        elif isinstance(stmt, ast.Parallel):
            for s in stmt.items:
                self.statements(s, params, where, calls)
        elif isinstance(stmt, ast.Monitor):
            self.statements(stmt.watched, params, where, calls)
            self.statements(stmt.watcher, params, where, calls)
        elif isinstance(stmt, ast.If):
            self.statements(stmt.condition, params, where, calls)
            self.statements(stmt.then, params, where, calls)
            if stmt.otherwise is not None:
                self.statements(stmt.otherwise, params, where, calls)
        elif isinstance(stmt, ast.While):
            self.statements(stmt.condition, params, where, calls)
            self.statements(stmt.body, params, where, calls)

    def users(self) -> dict[str, list[str]]:
        """Each primitive's tasks, in declaration order, found once."""
        if self._users is None:
            self._users = {}
            for t in self.p.of(ast.Task):
                for name in dict.fromkeys(c.name for c in t.primitives):
                    self._users.setdefault(name, []).append(t.name)
        return self._users

    def functions(self) -> tuple[str, ...]:
        graph: dict[str, list[str]] = {}
        for f in self.p.of(ast.Function):
            calls: list[str] = []
            self.statements(f.body, f.params, f"function '{f.name}'", calls)
            graph[f.name] = calls
        for m in self.p.of(ast.Mission):
            self.statements(m.body, (), "the mission", [])
        # recursion, direct or not: a depth-first search for a cycle, with an explicit
        # stack (a chain of thousands of functions each calling the next is a
        # legitimate program, far deeper than Python's recursion limit)
        order: list[str] = []
        state: dict[str, int] = {}         # 1: on the current path, 2: done
        at: dict[str, int] = {}            # where each function on the path is in it
        # a cycle is found once per call that closes it (the call from the path's end): the
        # path from its callee is the same at each, so that the call names the cycle
        reported: set[tuple[str, str]] = set()
        for root in graph:
            if state.get(root) is not None:
                continue
            state[root] = 1
            path = [root]
            at[root] = 0
            stack = [iter(graph[root])]
            while stack:
                for callee in stack[-1]:
                    if state.get(callee) == 1:
                        key = (path[-1], callee)
                        if key not in reported:
                            reported.add(key)
                            # spelled out where it is shown: a cycle may be the whole program
                            cycle = (" calls ".join(path[at[callee]:] + [callee]) if self.said
                                     else f"{callee} calls itself through {path[-1]}")
                            self.error(self.names[callee].pos, "recursion: " + cycle
                                       + "; a mission must be finite, so functions may not "
                                         "call themselves, directly or not")
                    elif callee in graph and state.get(callee) is None:
                        state[callee] = 1
                        at[callee] = len(path)
                        path.append(callee)
                        stack.append(iter(graph[callee]))
                        break
                else:   # every callee done: this function comes after them
                    name = path.pop()
                    stack.pop()
                    state[name] = 2
                    order.append(name)
        return tuple(order)


def check_program(program: ast.Program, library: Library | None = None) -> Checked:
    """Check a parsed program; raise every error found, or return it resolved."""
    c = _Checker(program, library or default_library())
    c.declare()
    consts = c.const_values()
    patterns = c.tasks()
    order = c.functions()
    # the properties' errors after the rest: they name what the declarations declare
    raise_all(c.errors + property_errors(program, program.of(ast.Property)))
    return Checked(program, consts,
                   {d.name: d for d in program.of(ast.Primitive)},
                   {d.name: d for d in program.of(ast.Task)}, patterns,
                   {d.name: d for d in program.of(ast.Function)}, order,
                   program.of(ast.Mission)[0])
