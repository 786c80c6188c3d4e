"""Warnings: valid MCL that does not do what it seems to say.

A pass over a checked program (:class:`~mcl2pnml.language.semantics.Checked`),
like lark's and sqlglot's: each trap found is a :class:`Warning`, a typed
value with a code, a message saying what really happens, a location (file,
line, column and the source line, rendered with a caret as errors are) and
a fix. ``mcl2pnml check`` and ``mcl2pnml compile`` print them on standard
error; ``--strict`` makes them errors (exit status 2). docs/warnings.md
explains each code with an example.

The rules follow the results of docs/mcl.md (and of the reference
engine, :mod:`mcl2pnml.runtime.reference`, which the net agrees with):

``W001`` a monitor whose FAIL stops what follows it.
    ``monitor(S1, S2)`` ends FAIL whenever S1 ends first, even when S1
    succeeded. Warned when the monitor is a statement of a sequence and its
    FAIL reaches a following statement: it is not the last of its block, or
    it is the last and the FAIL goes on up through blocks, branches of
    ``if``, bodies of ``while``, items of ``parallel`` and function calls to
    a block where something follows. Not warned in the condition of an
    ``if`` or a ``while`` (there FAIL is an answer) nor inside another
    monitor (that monitor is judged itself). Fix: ``if (monitor(S1, S2))
    then { ... }``.

``W002`` one task, function or primitive in two items of one ``parallel``.
    Every call of a task or function uses its one shared net, and tasks on
    one primitive share its lock: two items of a parallel that use the same
    one (calling it directly or through functions) run it one after the
    other, in an order the net picks, not at once. Warned at the later
    item's call.

``W003`` a wait nothing bounds.
    A call of a task of a built-in pattern with no ``timeout``: an
    AchieveGoal waits for its primitive's report, which may never come;
    KeepGoal and KeepTwoGoals end only on a failure. Warned when no
    enclosing monitor can stop it: a call inside one part of a monitor is
    bounded when the monitor's other part always ends by itself (its tasks
    all have time-outs, or a monitor in it is bounded so). A call inside a
    function is warned when one call of that function is unbounded. Only
    what the mission runs is judged.

``W004`` an ``if`` without ``else`` drops a failure.
    When the condition ends FAIL the missing else is NULL, so the ``if``
    ends OK and the mission goes on as if the condition had succeeded.
    Warned when the condition can fail, is not a monitor (whose FAIL is its
    answer: sauce.mcl's idiom), and something runs after the ``if``.

``W005`` one task, function or primitive in both parts of a monitor.
    The watched part takes it first, so the watcher waits for it until the
    watched part has ended, which ends the monitor FAIL and aborts the
    watcher before it ever started: it never watches.

A warning that is meant is acknowledged by a comment on its line or on the
line before it: ``// mcl: allow W004 because the leg is retried below``
(several codes: ``allow W002, W004 because ...``); the reason is required.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Iterator, Sequence

from mcl2pnml.core.errors import Location, shown as shown_errors, source_lines, visible
from mcl2pnml.core.gcpause import without_gc
from mcl2pnml.language import ast
from mcl2pnml.language.semantics import Checked
from mcl2pnml.language.functional import format_node, to_functional

#: Each code and what it is about (docs/warnings.md says more).
CODES = {
    "W001": "a monitor's FAIL stops the statements after it",
    "W002": "calls in one parallel share one net, so they do not run at once",
    "W003": "a wait nothing bounds (a task without timeout that nothing aborts)",
    "W004": "an if without else takes its condition's FAIL as OK",
    "W005": "the parts of a monitor share one net, so the watcher never watches",
}
#: The built-in patterns, and what one without a timeout waits for.
UNBOUNDED = {
    "AchieveGoal": "waits for its primitive to report, which it may never do",
    "KeepGoal": "ends only when its primitive fails or it is aborted",
    "KeepTwoGoals": "ends only when a primitive fails or it is aborted",
}
_ALLOW = re.compile(r"//\s*mcl:\s*allow\s+(W\d{3}(?:\s*,\s*W\d{3})*)\s+because\s+\S")


@dataclass(frozen=True)
class Warning:  # noqa: A001 (the name lark and sqlglot give it; this module's own)
    """A trap in a valid program: ``code`` (``W001``...), what happens, where, the fix."""

    code: str
    message: str
    location: Location
    fix: str

    def __str__(self) -> str:
        head = f"{self.location.prefix()}: warning: {visible(self.message)} [{self.code}]"
        excerpt = self.location.excerpt()
        return "\n".join([head] + ([excerpt] if excerpt else []) + [f"    fix: {self.fix}"])


@without_gc     # a record per statement, nothing cyclic: millions of them in a 16 MiB mission
def lint(checked: Checked) -> list[Warning]:
    """Every warning of a checked program, in source order, less those acknowledged."""
    found = _Lint(checked).run()
    allowed = _allowed(source_lines(checked.program.source))
    out = [w for w in found if w.code not in allowed.get(w.location.line or 0, ())]
    out.sort(key=lambda w: (w.location.line or 0, w.location.column or 0, w.code))
    unique: list[Warning] = []
    for w in out:
        if not unique or unique[-1] != w:
            unique.append(w)
    return unique


def _allowed(lines: list[str]) -> dict[int, set[str]]:
    """Line -> the codes acknowledged there: by a comment on it or on the line before."""
    out: dict[int, set[str]] = {}
    for n, text in enumerate(lines, 1):
        m = _ALLOW.search(text)
        if m:
            codes = {c.strip() for c in m.group(1).split(",")}
            for line in (n, n + 1):
                out.setdefault(line, set()).update(codes)
    return out


# -- the tree with its parents ----------------------------------------------------------------

@dataclass
class _Up:
    """Where a statement is: its parent, its role there, its index in a block."""

    parent: object          # a statement, or the body's owner (a Function or the Mission)
    role: str               # block, then, else, cond, body, item, watched, watcher, root
    index: int = 0


def _children(s) -> Iterator[tuple[object, str, int]]:
    if isinstance(s, ast.Block):
        for i, x in enumerate(s.body):
            yield x, "block", i
    elif isinstance(s, ast.Parallel):
        for i, x in enumerate(s.items):
            yield x, "item", i
    elif isinstance(s, ast.Monitor):
        yield s.watched, "watched", 0
        yield s.watcher, "watcher", 1
    elif isinstance(s, ast.If):
        yield s.condition, "cond", 0
        yield s.then, "then", 0
        if s.otherwise is not None:
            yield s.otherwise, "else", 0
    elif isinstance(s, ast.While):
        yield s.condition, "cond", 0
        yield s.body, "body", 0


def _walk(root) -> Iterator[object]:
    """Every statement under ``root`` (itself too), in source order; iterative."""
    stack = [root]
    while stack:
        s = stack.pop()
        yield s
        stack.extend(reversed([c for c, _, _ in _children(s)]))


class _Lint:
    def __init__(self, checked: Checked):
        self.c = checked
        self.p = checked.program
        self.lines = source_lines(self.p.source)
        self.up: dict[int, _Up] = {}
        self.sites: dict[str, list[ast.Call]] = {}   # function -> the calls of it
        # callers before callees: what a body's end leads to is known before its callees';
        # only what the mission runs (a function never called is not judged)
        self.callers_first: list[object] = []
        for owner in [checked.mission] + [checked.functions[n] for n in
                                          reversed(checked.function_order)]:
            if isinstance(owner, ast.Function) and owner.name not in self.sites:
                continue
            self.callers_first.append(owner)
            self.up[id(owner.body)] = _Up(owner, "root")
            for s in _walk(owner.body):
                for c, role, i in _children(s):
                    self.up[id(c)] = _Up(s, role, i)
                if isinstance(s, ast.Call) and s.name in checked.functions:
                    self.sites.setdefault(s.name, []).append(s)
        # what can be shared: a name used through two calls or more (:meth:`reaches`)
        edges: dict[str, int] = {}
        for owner in [checked.mission, *checked.functions.values()]:
            for s in _walk(owner.body):
                if isinstance(s, ast.Call):
                    edges[s.name] = edges.get(s.name, 0) + 1
        for task in checked.tasks.values():
            for prim in task.primitives:
                edges["primitive " + prim.name] = edges.get("primitive " + prim.name, 0) + 1
        self.shareable = {name for name, n in edges.items() if n > 1}
        self._reached: dict[str, tuple[str, ...]] = {}
        self._rank = {name: k for k, name in enumerate(checked.function_order)}
        self._ends: dict[str, bool] = {}
        self._ended: dict[int, bool] = {}
        self._fails: dict[str, bool] = {}
        for name in checked.function_order:          # callees first
            body = checked.functions[name].body
            self._ends[name] = self.ends(body)
            self._fails[name] = self.can_fail(body)
        self.warnings: list[Warning] = []

    def run(self) -> list[Warning]:
        self.monitors_that_stop()
        self.shared_at_once()
        self.unbounded_waits()
        self.ifs_without_else()
        return self.warnings

    # -- helpers -----------------------------------------------------------------------------

    def warn(self, code: str, pos: ast.Pos, message: str, fix: str) -> None:
        src = self.lines[pos.line - 1] if 0 < pos.line <= len(self.lines) else None
        self.warnings.append(Warning(code, message, Location(
            self.p.file, pos.line or None, pos.column or None, src), fix))

    def ends(self, s) -> bool:
        """Whether ``s`` always ends by itself (every wait in it bounded by a time-out)."""
        known = self._ended.get(id(s))
        if known is not None:
            return known
        if isinstance(s, ast.Call):
            task = self.c.tasks.get(s.name)
            if task is not None:
                known = task.timeout is not None or task.pattern not in UNBOUNDED
            else:
                known = self._ends.get(s.name, True)
        elif isinstance(s, ast.Monitor):       # the first part to end stops the other
            known = self.ends(s.watched) or self.ends(s.watcher)
        else:
            known = all(self.ends(c) for c, _, _ in _children(s))
        self._ended[id(s)] = known
        return known

    def can_fail(self, s) -> bool:
        """Whether ``s`` may end FAIL (run on its own)."""
        if isinstance(s, ast.Call):
            return s.name in self.c.tasks or self._fails.get(s.name, True)
        if isinstance(s, ast.Monitor):
            return True
        if isinstance(s, ast.If):
            return self.can_fail(s.then) or (s.otherwise is not None
                                             and self.can_fail(s.otherwise))
        if isinstance(s, ast.While):
            return self.can_fail(s.body)
        return any(self.can_fail(c) for c, _, _ in _children(s))

    def keyword(self, s) -> ast.Pos:
        """Where ``s`` is written: the parser gives a structure its first statement's
        position; this finds its keyword (``monitor``, ``if``...) before that."""
        chain = [s]
        while not isinstance(chain[-1], ast.Call):
            first = next(iter(_children(chain[-1])), None)
            if first is None:
                return s.pos
            chain.append(first[0])
        line, col = chain[-1].pos.line, chain[-1].pos.column
        if not 0 < line <= len(self.lines):
            return s.pos
        words = {ast.Monitor: "monitor", ast.Parallel: "parallel", ast.If: "if",
                 ast.While: "while"}
        for node in reversed(chain[:-1]):
            if isinstance(node, ast.Block):
                found = self._back(line, col, "{")
            else:
                found = self._back(line, col, "(")
                found = found and self._back(*found, words[type(node)])
            if found is None:
                return s.pos
            line, col = found
        return ast.Pos(line, col)

    def _back(self, line: int, col: int, token: str) -> tuple[int, int] | None:
        """The position of ``token`` just before (line, col), only blanks between."""
        while line > 0:
            text = self.lines[line - 1][:col - 1].rstrip()
            if text:
                if text.endswith(token) and (len(token) == 1 or not (
                        text[:-len(token)][-1:].isalnum() or text[:-len(token)][-1:] == "_")):
                    return line, len(text) - len(token) + 1
                return None
            line -= 1
            col = len(self.lines[line - 1]) + 1 if line > 0 else 1
        return None

    def leads_on(self, s, failed: bool, flags: dict[int, object]) -> object | None:
        """The statement that runs next when ``s`` ends FAIL (``failed``) or OK, by the
        results' rules, or None. ``flags`` holds, for each function already judged, what
        one of its calls leads to. Not past a monitor (the monitor is judged itself), nor
        past a failed condition (FAIL is then an answer)."""
        while True:
            up = self.up[id(s)]
            parent = up.parent
            if up.role == "root":
                return None if isinstance(parent, ast.Mission) else flags.get(id(parent))
            if up.role == "block" and up.index + 1 < len(parent.body):
                return parent.body[up.index + 1]
            if up.role in ("watched", "watcher") or (up.role == "cond" and failed):
                return None
            if up.role == "cond":
                nxt = parent.then if isinstance(parent, ast.If) else parent.body
                if nxt.body:
                    return nxt.body[0]
                if isinstance(parent, ast.While):
                    return parent.condition   # the loop tests again
            elif up.role == "body" and not failed:
                return parent.condition       # the loop tests again
            s = parent

    def leads(self, failed: bool) -> dict[int, object]:
        """Function (by id) -> a statement one of its calls leads to when it ends."""
        flags: dict[int, object] = {}
        for owner in self.callers_first:
            if isinstance(owner, ast.Function):
                for site in self.sites.get(owner.name, ()):
                    nxt = self.leads_on(site, failed, flags)
                    if nxt is not None:
                        flags[id(owner)] = nxt
                        break
        return flags

    def uses(self, s) -> dict[str, ast.Call]:
        """The tasks, functions and primitives ``s`` uses that two parts of a program can
        share (:meth:`reaches`), through functions too, each with the call in ``s`` that
        leads to it, in the order a depth-first walk of the calls meets them."""
        out: dict[str, ast.Call] = {}
        for x in _walk(s):
            if isinstance(x, ast.Call):
                for name in self.reaches(x.name):
                    out.setdefault(name, x)
        return out

    def reaches(self, name: str) -> tuple[str, ...]:
        """What a call of ``name`` uses, itself included, that can be shared, in the order a
        depth-first walk of the calls meets it; each function's found once, callees first.

        Only a name used by two calls or more (a task's use of a primitive counts as
        one) can be used by two parts: two walks that meet first meet at such a name,
        which is then the first shared one a walk finds. The rest is left out, so that
        what a function reaches is not walked again for each call, nor kept whole for
        each of a chain of functions: the rules stay linear in the program.
        """
        known = self._reached.get(name)
        if known is not None:
            return known
        if name not in self.c.functions:             # a task: itself, then its primitives
            task = self.c.tasks[name]
            found = dict.fromkeys(n for n in [name] + ["primitive " + p.name
                                                       for p in task.primitives]
                                  if n in self.shareable)
            self._reached[name] = tuple(found)
            return self._reached[name]
        pending, stack = set(), [name]              # the functions not yet known it reaches
        while stack:
            f = stack.pop()
            if f in pending or f in self._reached or f not in self.c.functions:
                continue
            pending.add(f)
            stack.extend(self._callees(f))
        for f in sorted(pending, key=self._rank.__getitem__):
            found = dict.fromkeys([f] if f in self.shareable else [])
            # the walk takes a body's calls last first (a stack), each as deep as it goes
            for callee in reversed(self._callees(f)):
                found.update(dict.fromkeys(self.reaches(callee)))
            self._reached[f] = tuple(found)
        return self._reached[name]

    def _callees(self, function: str) -> list[str]:
        """The calls of a function's body, in source order."""
        return [c.name for c in _walk(self.c.functions[function].body)
                if isinstance(c, ast.Call)]

    def statements(self) -> Iterator[object]:
        for owner in self.callers_first:
            yield from _walk(owner.body)

    def what(self, name: str) -> str:
        if name.startswith("primitive "):
            return name
        return ("task " if name in self.c.tasks else "function ") + f"'{name}'"

    # -- the rules ---------------------------------------------------------------------------

    def monitors_that_stop(self) -> None:
        flags = self.leads(failed=True)
        for s in self.statements():
            if isinstance(s, ast.Monitor):
                nxt = self.leads_on(s, True, flags)
                if nxt is None:
                    continue
                pos = self.keyword(s)
                self.warn("W001", pos,
                          "when the monitor's watched part (its first) ends before the watcher, "
                          "even with success, the monitor ends FAIL, and that FAIL stops the "
                          "sequence: "
                          f"{self._said(nxt)} never runs then",
                          "test it instead: `if (monitor(...)) then { ... }` (the "
                          "then-block runs when the watcher ended OK first), and put the "
                          "statements that must always run after the if")

    def _said(self, s) -> str:
        if isinstance(s, ast.Call):
            return f"{_text(s)} on line {s.pos.line}"
        kind = {ast.Monitor: "monitor", ast.Parallel: "parallel", ast.If: "if",
                ast.While: "while", ast.Block: "block"}[type(s)]
        line = self.keyword(s).line
        return f"the {kind} on line {line}" if line else f"the {kind} after it"

    def shared_at_once(self) -> None:
        for s in self.statements():
            if isinstance(s, ast.Parallel):
                seen: dict[str, ast.Call] = {}
                for item in s.items:
                    used = self.uses(item)
                    told: set[int] = set()
                    # a task or function before its primitives: the one shared said once
                    for name in sorted(used, key=lambda n: n.startswith("primitive ")):
                        call, first = used[name], seen.get(name)
                        if first is not None and id(call) not in told:
                            told.add(id(call))
                            self.warn("W002", call.pos,
                                      f"{self.what(name)} is used by two items of one parallel "
                                      f"(here, and by {_text(first)} at {first.pos.line}:"
                                      f"{first.pos.column}): {self._sharing(name)}, so they run "
                                      "one after the other, in an order the net picks, not "
                                      "at once",
                                      "run them in sequence, in the order meant; or declare a "
                                      "second task on its own primitive if the vehicle can "
                                      "really do both at once")
                    for name, call in used.items():
                        seen.setdefault(name, call)
            elif isinstance(s, ast.Monitor):
                watched = self.uses(s.watched)
                for name, call in self.uses(s.watcher).items():
                    if name in watched:
                        first = watched[name]
                        self.warn("W005", call.pos,
                                  f"the watcher uses {self.what(name)}, as the watched part "
                                  f"does ({_text(first)} at {first.pos.line}:{first.pos.column}): "
                                  f"{self._sharing(name)}, so the watcher waits until the "
                                  "watched part has ended, which ends the monitor FAIL and "
                                  "aborts the watcher before it starts: it never watches",
                                  "watch with a task on a primitive of its own")
                        break

    @staticmethod
    def _sharing(name: str) -> str:
        if name.startswith("primitive "):
            return "tasks on one primitive wait for its lock"
        return "every call of it uses its one shared net"

    def unbounded_waits(self) -> None:
        free: set[str] = set()              # functions called where nothing bounds them
        for owner in self.callers_first:
            if isinstance(owner, ast.Function) and owner.name not in free:
                continue
            body = owner.body
            for s in _walk(body):
                if not isinstance(s, ast.Call) or self.bounded(s):
                    continue
                if s.name in self.c.functions:
                    free.add(s.name)
                    continue
                task = self.c.tasks[s.name]
                if task.timeout is None and task.pattern in UNBOUNDED:
                    self.warn("W003", s.pos,
                              f"task '{s.name}' has no timeout and {UNBOUNDED[task.pattern]}; "
                              "nothing aborts this call, so the mission may wait for ever",
                              f"add `timeout SECONDS` to task '{s.name}', or run the call as "
                              "one part of a monitor whose other part always ends (e.g. "
                              "`monitor(Work(), " + f"{s.name}(...))`)")

    def bounded(self, s) -> bool:
        """Whether an enclosing monitor (in the same body) stops ``s`` in bounded time."""
        while True:
            up = self.up[id(s)]
            if up.role == "root":
                return False
            if up.role == "watched" and self.ends(up.parent.watcher):
                return True
            if up.role == "watcher" and self.ends(up.parent.watched):
                return True
            s = up.parent

    def ifs_without_else(self) -> None:
        flags = self.leads(failed=False)
        for s in self.statements():
            if not isinstance(s, ast.If) or s.otherwise is not None:
                continue
            cond = s.condition
            while isinstance(cond, ast.Block) and len(cond.body) == 1:
                cond = cond.body[0]
            if isinstance(cond, ast.Monitor) or not self.can_fail(cond):
                continue
            nxt = self.leads_on(s, False, flags)
            if nxt is None:
                continue
            self.warn("W004", self.keyword(s),
                      "this if has no else: when its condition ends FAIL, it runs nothing and "
                      "ends OK, so the failure is dropped and the mission goes on "
                      f"({self._said(nxt)}) as if the condition had succeeded",
                      "add `else { ... }` to handle the failure (e.g. surface); to stop on "
                      "it, write the condition as a statement before the block (a sequence "
                      "stops at a FAIL); if dropping it is meant, say so: "
                      "`// mcl: allow W004 because ...` on the line before")


def _text(call: ast.Call) -> str:
    """A call as written: ``Goto(WP1)``."""
    return format_node(to_functional(call))


def shown(warnings: Sequence[Warning]) -> list[str]:
    """The warnings as lines to print: the first ones, then how many more (as errors are)."""
    return shown_errors(warnings, "warnings")
