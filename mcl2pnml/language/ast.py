"""The MCL abstract syntax tree: immutable data that keeps source positions.

One dataclass per construct of ``docs/mcl.md``. Every node has a
``pos`` (line, column), so that the checker and the compiler can point at
the source; positions take no part in equality, so two programs that say
the same thing are equal wherever they were written.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Union


@dataclass(frozen=True)
class Pos:
    line: int
    column: int


def _pos() -> Pos:
    return field(default=Pos(0, 0), compare=False, repr=False)


# -- values -------------------------------------------------------------------


@dataclass(frozen=True)
class Number:
    value: float | int
    text: str
    pos: Pos = _pos()


@dataclass(frozen=True)
class String:
    value: str
    pos: Pos = _pos()


@dataclass(frozen=True)
class Tuple:
    items: tuple["Value", ...]
    pos: Pos = _pos()


@dataclass(frozen=True)
class Ref:
    """A name used as a value: a const, or a parameter of the enclosing task or function."""

    name: str
    pos: Pos = _pos()


Value = Union[Number, String, Tuple, Ref]


# -- declarations -----------------------------------------------------------------


@dataclass(frozen=True)
class Const:
    name: str
    value: Value
    pos: Pos = _pos()


@dataclass(frozen=True)
class Primitive:
    name: str
    params: tuple[str, ...]
    pos: Pos = _pos()


@dataclass(frozen=True)
class PrimCall:
    """A primitive with its arguments, inside a task declaration."""

    name: str
    args: tuple[Value, ...]
    pos: Pos = _pos()


@dataclass(frozen=True)
class Task:
    """``task NAME(params) = PATTERN(PRIM(args), ...) [timeout SECONDS];``"""

    name: str
    params: tuple[str, ...]
    pattern: str
    primitives: tuple[PrimCall, ...]
    timeout: Number | None
    pos: Pos = _pos()
    pattern_pos: Pos = _pos()


# -- statements -----------------------------------------------------------------


@dataclass(frozen=True)
class Call:
    """``NAME(args);``: runs a task or a function."""

    name: str
    args: tuple[Value, ...]
    pos: Pos = _pos()


@dataclass(frozen=True)
class Block:
    """``{ ... }``: a sequence; empty, it is NULL."""

    body: tuple["Statement", ...]
    pos: Pos = _pos()


@dataclass(frozen=True)
class Parallel:
    items: tuple["Statement", ...]
    pos: Pos = _pos()


@dataclass(frozen=True)
class Monitor:
    watched: "Statement"
    watcher: "Statement"
    pos: Pos = _pos()


@dataclass(frozen=True)
class If:
    condition: "Statement"
    then: Block
    otherwise: Block | None
    pos: Pos = _pos()


@dataclass(frozen=True)
class While:
    condition: "Statement"
    body: Block
    pos: Pos = _pos()


Statement = Union[Call, Block, Parallel, Monitor, If, While]


@dataclass(frozen=True)
class Function:
    name: str
    params: tuple[str, ...]
    body: Block
    pos: Pos = _pos()


@dataclass(frozen=True)
class Mission:
    body: Block
    pos: Pos = _pos()


# -- properties (docs/properties.md) --------------------------------------------------


@dataclass(frozen=True)
class PropAtom:
    """``KIND(ARG[, ARG])``: ``enabled(KeepDepth)``, ``ended(Survey, ABORTED)``.

    The kind and its arguments are names here; the checker judges them
    (:func:`mcl2pnml.language.declared_properties.property_errors`), so that a
    misspelt kind is one message with the known ones, not a syntax error.
    """

    kind: str
    args: tuple[str, ...]
    pos: Pos = _pos()
    arg_pos: tuple[Pos, ...] = field(default=(), compare=False, repr=False)


@dataclass(frozen=True)
class PropTruth:
    value: bool
    pos: Pos = _pos()


@dataclass(frozen=True)
class PropNot:
    arg: "PropExpr"
    pos: Pos = _pos()


@dataclass(frozen=True)
class PropAnd:
    args: tuple["PropExpr", ...]
    pos: Pos = _pos()


@dataclass(frozen=True)
class PropOr:
    args: tuple["PropExpr", ...]
    pos: Pos = _pos()


PropExpr = Union[PropAtom, PropTruth, PropNot, PropAnd, PropOr]


@dataclass(frozen=True)
class Property:
    """``property NAME: PATTERN [SCOPE];`` (Dwyer, Avrunin and Corbett's patterns).

    ``pattern`` is how it was written (``never``, ``always``, ``eventually``,
    ``at most``, ``only after``, ``leads to``); ``p`` its first expression,
    ``s`` the second of ``only after`` and ``leads to``; ``bound`` the K of
    ``at most K times``. ``scope`` is ``globally``, ``before``, ``after``,
    ``between`` or ``after until``, opened by ``q`` and closed by ``r``.
    """

    name: str
    pattern: str
    p: PropExpr
    s: PropExpr | None = None
    bound: Number | None = None
    scope: str = "globally"
    q: PropExpr | None = None
    r: PropExpr | None = None
    pos: Pos = _pos()


Declaration = Union[Const, Primitive, Task, Function, Mission, Property]


@dataclass(frozen=True)
class Program:
    """A whole MCL file, declarations in source order."""

    declarations: tuple[Declaration, ...]
    file: str = field(default="<mcl>", compare=False)
    source: str = field(default="", compare=False, repr=False)

    def of(self, kind) -> list:
        return [d for d in self.declarations if isinstance(d, kind)]
