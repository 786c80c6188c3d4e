"""``mcl2pnml check MISSION`` and ``mcl2pnml functional MISSION``: a mission read and checked,
printed as its verdict (with its properties compiled, if asked) or as its functional form
(the paper's Algorithm 2). One module: both read a mission and print it checked, without
compiling it to a net but for its properties."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mcl2pnml import pipeline
from mcl2pnml.commands.common import MISSION_SIZE, PROPERTIES_SIZE, properties_file, warned
from mcl2pnml.core.bounds import MAX_PROPERTY_ATOMS
from mcl2pnml.core.errors import raise_all, visible
from mcl2pnml.core.patterns import describe
from mcl2pnml.core.progress import Notes


@dataclass(frozen=True)
class CheckOptions:
    """``check``'s settings, by the names of its options (``--help`` says each)."""

    #: also print each property compiled to place formulas (None: not asked)
    properties: str | None = None
    max_props_size: str = PROPERTIES_SIZE
    max_atoms: int = MAX_PROPERTY_ATOMS
    #: the warnings are errors
    strict: bool = False
    max_mission_size: str = MISSION_SIZE
    #: the vehicle that must offer every primitive, as ``run --vehicle`` names it (None: any)
    vehicle: str | None = None
    #: files of simulated primitives the simulator offers besides its own
    sim_primitives: tuple[Path, ...] = ()


@dataclass(frozen=True)
class CheckOutcome:
    """A mission checked: its name as given, the checked program, its warnings, and the
    vehicle it was checked against (None: none)."""

    mission: Path
    checked: Any
    warnings: tuple = ()
    vehicle: str | None = None

    def lines(self) -> list[str]:
        """What ``check`` prints first: ok, and what the mission holds."""
        flown = "" if self.vehicle is None else \
            f"; --vehicle {visible(self.vehicle)} offers every primitive it uses"
        return [f"{visible(str(self.mission))}: ok ({self.checked.summary()}){flown}"]

    def as_json(self) -> dict[str, Any]:
        return {"mission": str(self.mission), "ok": True, "summary": self.checked.summary(),
                "warnings": len(self.warnings), "vehicle": self.vehicle}


@dataclass(frozen=True)
class PropertiesOutcome:
    """A checked mission's properties compiled to predicates on its net's places."""

    properties: tuple

    def lines(self) -> list[str]:
        """What ``check --properties`` prints after ok: each property's place formulas."""
        return properties_lines(self.properties)

    def as_json(self) -> dict[str, Any]:
        return {"properties": [{"name": p.name, "text": p.text} for p in self.properties]}


def check(mission: Path, options: CheckOptions = CheckOptions(), *,
          notes: Notes | None = None) -> CheckOutcome:
    """``mcl2pnml check`` with ``options``: every error of the file at once (raised), then
    every primitive ``vehicle`` does not offer (raised), then the warnings, said to
    ``notes``. Its properties are :func:`properties`' (the mission is ok before they are
    compiled, and said to be so first)."""
    o, notes = options, Notes() if notes is None else notes
    checked = pipeline.check_file(mission, o.max_mission_size)
    if o.vehicle is not None:
        raise_all(pipeline.unflown(checked, o.vehicle, o.sim_primitives))
    return CheckOutcome(mission, checked, tuple(warned(mission, checked, o.strict, notes)),
                        o.vehicle)


def properties(checked: CheckOutcome, options: CheckOptions = CheckOptions()
               ) -> PropertiesOutcome:
    """``check --properties``: the mission's properties, then those of the side file,
    compiled on its net."""
    o, mission = options, checked.mission
    _, compiled = pipeline.properties_of(
        mission, extra=properties_file(mission, o.properties or ""), max_size=o.max_props_size,
        max_atoms=o.max_atoms, checked=checked.checked)
    return PropertiesOutcome(tuple(compiled))


def properties_lines(compiled) -> list[str]:
    """``check --properties``: each property compiled to place formulas, its pattern's
    (P, S, the bound) then its scope's (Q, R)."""
    out = []
    for prop in compiled:
        scope = prop.scope
        q = f": Q = {describe(scope.q)}" if scope.q is not None else ""
        r = "" if scope.r is None else f"{'; ' if q else ': '}R = {describe(scope.r)}"
        out += [f"property {prop.name} ({prop.location.prefix()}): {prop.text}",
                f"  {prop.pattern.value}: P = {describe(prop.p)}"
                + (f"; S = {describe(prop.s)}" if prop.s is not None else "")
                + (f"; at most {prop.bound} times" if prop.bound is not None else ""),
                f"  {scope.kind.value}{q}{r}"]
    return out or ["no properties"]


@dataclass(frozen=True)
class FunctionalOptions:
    """``functional``'s settings, by the names of its options (``--help`` says each)."""

    #: also each function's body in functional form
    functions: bool = False
    max_mission_size: str = MISSION_SIZE


@dataclass(frozen=True)
class FunctionalOutcome:
    """The functional form: each function's body if asked, then the mission's."""

    form: tuple[str, ...]

    def lines(self) -> list[str]:
        return list(self.form)

    def as_json(self) -> dict[str, Any]:
        return {"functional": list(self.form)}


def functional(mission: Path, options: FunctionalOptions = FunctionalOptions()
               ) -> FunctionalOutcome:
    """``mcl2pnml functional`` with ``options`` (the paper's Algorithm 2)."""
    checked = pipeline.check_file(mission, options.max_mission_size)
    return FunctionalOutcome(tuple(pipeline.functional_form(checked,
                                                            functions=options.functions)))
