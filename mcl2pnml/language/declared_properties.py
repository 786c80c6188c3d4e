"""A mission's ``property`` declarations: checked, and compiled to predicates on its net.

A property is one of Dwyer, Avrunin and Corbett's specification patterns in
one of their scopes ("Patterns in property specifications for finite-state
verification", ICSE 1999), written over the mission's own names; its typed
form, and what its patterns and scopes mean on a net's runs, is
:mod:`mcl2pnml.core.patterns`. Here each atom becomes a predicate on the
places of the net :mod:`mcl2pnml.language.compiler` builds (the paper's
section 2.4: one shared net per primitive, per task and per function, the
mission's fusion places of section 2.5), so that any Petri-net checker can
judge it. The syntax is docs/properties.md's.

=============================  =====================  ==========================================
atom                           places (marked: >= 1)  why
=============================  =====================  ==========================================
``enabled(P)``                 ``P.ON``               the primitive's shared net holds ON while the
                                                      vehicle runs it (Fig. 2, section 2.2)
``achieved(P)``                ``P.S2``               S2 is the primitive's goal state reached
``failed(P)``                  ``P.S1``               S1 is its goal state not (or no longer) held
``running(T)``                 not ``T.GATE``         a task's or function's GATE is free exactly
                                                      when no call is inside its shared net: taken
                                                      by the call site on entry, given back when the
                                                      result has been taken out
``ended(T, R)``                ``T.R``                the shared net's result place (R one of OK,
                                                      FAIL, ABORTED); marked only until the call
                                                      site takes the result out
``outcome(R)``                 ``mission.R``          the mission's result place: the run's end
``true``, ``false``            none                   constants
=============================  =====================  ==========================================

``P`` is a declared primitive, ``T`` a declared task or function. The
reduced model (``reduced=True``, the paper's Fig. 3) has no primitive nets:
an atom on a primitive there is an error at the atom. Every place a compiled
property names is checked to be in the net, so a change of the compiler's
place names is an error here, never a predicate that is silently false.
"""
from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

from mcl2pnml.core import patterns as typed
from mcl2pnml.core.bounds import MAX_PROPERTY_ATOMS, MAX_TOKENS, MAX_TOKENS_TEXT
from mcl2pnml.core.errors import (SHOWN_ERRORS, Location, Mcl2PnmlError, did_you_mean, raise_all,
                                  source_lines)
from mcl2pnml.core.net import Net
from mcl2pnml.core.payloads import MISSION
from mcl2pnml.language import ast

#: The results a task, a function or the mission ends with (docs/mcl.md, "Results").
RESULTS = ("OK", "FAIL", "ABORTED")

#: Each atom: what its arguments name ("primitive", "callable": a task or a function,
#: "result").
ATOMS: Mapping[str, tuple[str, ...]] = {
    "enabled": ("primitive",), "achieved": ("primitive",), "failed": ("primitive",),
    "running": ("callable",), "ended": ("callable", "result"), "outcome": ("result",),
}
#: The place of a primitive's net each primitive atom reads.
_PRIMITIVE_PLACE = {"enabled": "ON", "achieved": "S2", "failed": "S1"}

PATTERNS = {"never": typed.Pattern.ABSENCE, "always": typed.Pattern.UNIVERSALITY,
            "eventually": typed.Pattern.EXISTENCE, "at most": typed.Pattern.BOUNDED_EXISTENCE,
            "only after": typed.Pattern.PRECEDENCE, "leads to": typed.Pattern.RESPONSE}
SCOPES = {kind.value: kind for kind in typed.ScopeKind}


class _Errors:
    """Errors at positions of one file, each with its line and a caret."""

    def __init__(self, program: ast.Program):
        self.file = program.file
        self.lines = source_lines(program.source)
        self.errors: list[Mcl2PnmlError] = []

    def location(self, pos: ast.Pos) -> Location:
        src = self.lines[pos.line - 1] if 0 < pos.line <= len(self.lines) else None
        return Location(self.file, pos.line or None, pos.column or None, src)

    def add(self, pos: ast.Pos, message: str) -> None:
        self.errors.append(Mcl2PnmlError(message, self.location(pos)))


def _atoms(expr: ast.PropExpr | None):
    """Every atom of an expression (nested at most the parser's MAX_NESTING deep)."""
    return (e for e in _leaves(expr) if isinstance(e, ast.PropAtom))


def _leaves(expr: ast.PropExpr | None):
    """Every atom and constant of an expression, in the order written (none of None)."""
    stack = [expr]
    while stack:
        e = stack.pop()
        if isinstance(e, (ast.PropAtom, ast.PropTruth)):
            yield e
        elif isinstance(e, ast.PropNot):
            stack.append(e.arg)
        elif isinstance(e, (ast.PropAnd, ast.PropOr)):
            stack.extend(reversed(e.args))


def check_atoms(sources: Sequence[ast.Program], limit: int = MAX_PROPERTY_ATOMS,
                option: str = "--max-atoms") -> None:
    """Refuse the properties of ``sources`` (the mission, then a side file) when they have
    more than ``limit`` atoms in all: one error at the first atom past the limit, before
    they are checked, compiled or judged
    (:data:`~mcl2pnml.core.bounds.MAX_PROPERTY_ATOMS`). Counting is one walk of the
    parsed expressions, without recursion."""
    count, first = 0, None
    for program in sources:
        for prop in program.of(ast.Property):
            for expr in _expressions(prop):
                for leaf in _leaves(expr):
                    count += 1
                    if count == limit + 1:
                        first = (program, leaf.pos)
    if first is None:
        return
    program, pos = first
    raise Mcl2PnmlError(f"the properties have {count:,} atoms in all, over the limit of "
                        f"{limit:,} ({option} to raise it); this is atom {limit + 1:,}",
                        _Errors(program).location(pos))


def _expressions(prop: ast.Property):
    # in the order they are written: the pattern, then the scope
    return tuple(e for e in (prop.p, prop.s, prop.q, prop.r) if e is not None)


def property_errors(program: ast.Program, props: Sequence[ast.Property],
                    declared: ast.Program | None = None) -> list[Mcl2PnmlError]:
    """Every error of ``props`` (written in ``program``), names resolved against
    ``declared`` (the mission; by default ``program`` itself): duplicate names, a bound
    that is not a positive integer, unknown atoms, wrong arities, undeclared names."""
    errors = _Errors(program)
    mission = declared or program
    names = {"primitive": {d.name for d in mission.of(ast.Primitive)},
             "callable": {d.name for d in (*mission.of(ast.Task), *mission.of(ast.Function))},
             "result": set(RESULTS)}
    what = {"primitive": "primitive", "callable": "task or function", "result": "result"}
    listing = {"primitive": "declared primitives", "callable": "declared tasks and functions",
               "result": "results"}
    seen: dict[str, ast.Property] = {}
    for prop in props:
        first = seen.setdefault(prop.name, prop)
        if first is not prop:
            errors.add(prop.pos, f"duplicate property '{prop.name}': already declared on line "
                                 f"{first.pos.line}")
        bound = prop.bound
        if bound is not None and (not isinstance(bound.value, int) or bound.value < 1):
            errors.add(bound.pos, f"'at most {bound.text} times': the bound is a positive "
                                  "integer (at most 3 times)")
        elif bound is not None and bound.value > MAX_TOKENS:
            errors.add(bound.pos, f"'at most {bound.text} times': the bound is at most "
                                  f"{MAX_TOKENS_TEXT}")
        for expr in _expressions(prop):
            for atom in _atoms(expr):
                kinds = ATOMS.get(atom.kind)
                if kinds is None:
                    errors.add(atom.pos, f"unknown atom '{atom.kind}'"
                               + did_you_mean(atom.kind, ATOMS, "atoms"))
                    continue
                if len(atom.args) != len(kinds):
                    shown = ", ".join(what[k].upper().replace(" ", "_") for k in kinds)
                    errors.add(atom.pos, f"'{atom.kind}' takes {len(kinds)} argument"
                                         f"{'s' * (len(kinds) != 1)}: {atom.kind}({shown})")
                    continue
                for kind, arg, pos in zip(kinds, atom.args, atom.arg_pos):
                    if arg not in names[kind]:
                        adjective = "unknown" if kind == "result" else "undeclared"
                        # results are upper case: "Ok" is offered "OK"
                        near = arg.upper() if kind == "result" else arg
                        # the hint searches every name: only for the errors shown
                        hint = did_you_mean(near, names[kind], listing[kind]) \
                            if len(errors.errors) < SHOWN_ERRORS else ""
                        errors.add(pos, f"{adjective} {what[kind]} '{arg}'" + hint)
    return errors.errors


def _atom(atom: ast.PropAtom, reduced: bool, errors: _Errors) -> typed.Predicate:
    if atom.kind in _PRIMITIVE_PLACE:
        if reduced:
            errors.add(atom.pos, f"'{atom.kind}({atom.args[0]})' reads a primitive's net, and "
                                 "the reduced model (Fig. 3) has none; check it on the full "
                                 "model")
            return typed.Const(False)
        return typed.Tokens((f"{atom.args[0]}.{_PRIMITIVE_PLACE[atom.kind]}",))
    if atom.kind == "running":
        return typed.Not(typed.Tokens((f"{atom.args[0]}.GATE",)))
    if atom.kind == "ended":
        return typed.Tokens((f"{atom.args[0]}.{atom.args[1]}",))
    return typed.Tokens((f"{MISSION}.{atom.args[0]}",))   # outcome


def predicate(expr: ast.PropExpr, *, reduced: bool = False,
              errors: _Errors | None = None) -> typed.Predicate:
    """The predicate on the compiled net of a checked expression (the module's table)."""
    errors = errors or _Errors(ast.Program(()))
    if isinstance(expr, ast.PropAtom):
        return _atom(expr, reduced, errors)
    if isinstance(expr, ast.PropTruth):
        return typed.Const(expr.value)
    if isinstance(expr, ast.PropNot):
        return typed.Not(predicate(expr.arg, reduced=reduced, errors=errors))
    args = tuple(predicate(a, reduced=reduced, errors=errors) for a in expr.args)
    if len(args) == 1:
        return args[0]
    return typed.And(args) if isinstance(expr, ast.PropAnd) else typed.Or(args)


def text_of(prop: ast.Property) -> str:
    """The property's pattern and scope as written (spacing and parentheses made canonical)."""
    p, s = expression_text(prop.p), prop.s and expression_text(prop.s)
    pattern = {"never": f"never {p}", "always": f"always {p}", "eventually": f"eventually {p}",
               "at most": f"at most {prop.bound.text if prop.bound else '?'} times {p}",
               "only after": f"{p} only after {s}", "leads to": f"{p} leads to {s}"}[prop.pattern]
    q, r = prop.q and expression_text(prop.q), prop.r and expression_text(prop.r)
    scope = {"globally": "globally", "before": f"before {r}", "after": f"after {q}",
             "between": f"between {_term(prop.q)} and {r}",
             "after until": f"after {q} until {r}"}[prop.scope]
    return f"{pattern} {scope}"


def _term(expr: ast.PropExpr | None) -> str:
    text = expression_text(expr) if expr is not None else ""
    return f"({text})" if isinstance(expr, (ast.PropAnd, ast.PropOr)) and len(expr.args) > 1 \
        else text


def expression_text(expr: ast.PropExpr) -> str:
    """An expression written back: ``enabled(KeepDepth) and not (outcome(OK) or ...)``."""
    if isinstance(expr, ast.PropAtom):
        return f"{expr.kind}({', '.join(expr.args)})"
    if isinstance(expr, ast.PropTruth):
        return "true" if expr.value else "false"
    if isinstance(expr, ast.PropNot):
        inner = expression_text(expr.arg)
        return f"not ({inner})" if isinstance(expr.arg, (ast.PropAnd, ast.PropOr)) \
            and len(expr.arg.args) > 1 else f"not {inner}"
    parts = [expression_text(a) for a in expr.args]
    if isinstance(expr, ast.PropAnd):
        parts = [f"({t})" if isinstance(a, ast.PropOr) and len(a.args) > 1 else t
                 for a, t in zip(expr.args, parts)]
        return " and ".join(parts)
    return " or ".join(parts)


def compile_properties(net: Net, sources: Sequence[ast.Program], *,
                       reduced: bool = False) -> tuple[typed.Property, ...]:
    """Each ``property`` of ``sources`` (the mission, then any side file; all checked)
    as its typed form over ``net``'s places, with its file, line and column.

    Names unique across the sources; every error of every source at once.
    """
    found: list[Mcl2PnmlError] = []
    compiled: list[typed.Property] = []
    seen: dict[str, str] = {}
    for program in sources:
        errors = _Errors(program)
        for prop in program.of(ast.Property):
            if prop.name in seen and seen[prop.name] != program.file:
                errors.add(prop.pos, f"duplicate property '{prop.name}': already declared in "
                                     f"{seen[prop.name]}")
            seen.setdefault(prop.name, program.file)
            def pred(e):
                return None if e is None else predicate(e, reduced=reduced, errors=errors)
            result = typed.Property(
                prop.name, PATTERNS[prop.pattern], pred(prop.p), pred(prop.s),
                prop.bound.value if prop.bound is not None else None,
                typed.Scope(SCOPES[prop.scope], pred(prop.q), pred(prop.r)),
                text_of(prop), errors.location(prop.pos))
            missing = sorted(_places(result) - set(net.place_index))
            if missing:   # the compiler and the table above disagree: say so, never guess
                errors.add(prop.pos, f"property '{prop.name}' reads places the net lacks: "
                                     f"{', '.join(missing)}")
            compiled.append(result)
        found += errors.errors
    raise_all(found)
    return tuple(compiled)


def _places(prop: typed.Property) -> frozenset[str]:
    preds = (prop.p, prop.s, prop.scope.q, prop.scope.r)
    return frozenset().union(*(typed.places_of(p) for p in preds if p is not None))


def check_side_file(program: ast.Program, mission: ast.Program) -> ast.Program:
    """A side file of properties (``MISSION.props``), checked against ``mission``: only
    ``property`` declarations, every error at once."""
    errors = _Errors(program)
    for d in program.declarations:
        if not isinstance(d, ast.Property):
            errors.add(d.pos, "a properties file holds only 'property' declarations; "
                              "declare the rest in the mission")
    raise_all(errors.errors + property_errors(program, program.of(ast.Property), mission))
    return program


def side_file_of(mission: Path) -> Path:
    """Where a mission's side file of properties is looked for: ``MISSION.props``."""
    return mission.with_suffix(".props")
