"""``mcl2pnml odds MISSION --vehicle-model MODEL``: the exact odds of a mission with a vehicle
model (docs/odds.md), and the probability that each of its properties holds."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mcl2pnml.commands.common import MISSION_SIZE, PROPERTIES_SIZE, mission_net, \
    properties_file
from mcl2pnml.core.bounds import MAX_CHAIN_STATES, MAX_PROPERTY_ATOMS
from mcl2pnml.core.files import atomic_write_text, check_outputs
from mcl2pnml.core.progress import Notes
from mcl2pnml.core.settings import SettingError

if TYPE_CHECKING:
    from mcl2pnml.odds import Odds


@dataclass(frozen=True)
class OddsOptions:
    """``odds``' settings, by the names of its options (``--help`` says each)."""

    #: also P(OK) with each primitive always achieving, and never
    sensitivity: bool = False
    #: the chain in PRISM's language, to this file
    prism: Path | None = None
    properties: str | None = None
    max_props_size: str = PROPERTIES_SIZE
    max_atoms: int = MAX_PROPERTY_ATOMS
    max_states: int = MAX_CHAIN_STATES
    max_mission_size: str = MISSION_SIZE


@dataclass(frozen=True)
class OddsOutcome:
    """What ``mcl2pnml odds`` prints: the mission's odds with its vehicle model, and
    (asked for) each primitive's sway on P(OK)."""

    mission: str
    model: str
    odds: Odds
    sensitivity: list[dict[str, Any]] = field(default_factory=list)

    def as_json(self) -> dict[str, Any]:
        out = {"mission": self.mission, "vehicle_model": self.model, **self.odds.as_json()}
        if self.sensitivity:
            out["sensitivity"] = self.sensitivity
        return out

    def lines(self) -> list[str]:
        o = self.odds
        lines = [f"{self.mission} with the vehicle model {self.model} "
                 f"({o.states:,} states, {o.transitions:,} transitions; docs/odds.md):"]
        for name, p in o.outcomes.items():
            exact = o.exact.get(name) if o.exact is not None else None
            said = f" = {exact}" if exact is not None and exact.denominator > 1 and \
                len(str(exact)) <= 40 else ""
            lines.append(f"  P({name}) = {p:.6f}{said}")
        if o.mean is None:
            lines.append("  end time: the mission never ends")
        else:
            q = o.quantiles
            lines.append(f"  end time, if it ends: mean {o.mean:.2f} s, standard deviation "
                         f"{o.spread:.2f} s; 5% by {_s(q['p5'])}, half by {_s(q['p50'])}, "
                         f"95% by {_s(q['p95'])}")
        if o.beyond:
            lines.append(f"  (the distribution stops at its horizon with {o.beyond:.2e} of "
                         "the runs still going)")
        if o.properties:
            lines.append("  the properties (the probability that each holds):")
            width = max(len(p.name) for p in o.properties)
            for p in o.properties:
                said = f" = {p.exact}" if p.exact is not None and p.exact.denominator > 1 \
                    and len(str(p.exact)) <= 40 else ""
                lines.append(f"    {p.name:<{width}}  {p.holds:.6f}{said}")
        if self.sensitivity:
            lines.append("  P(OK) by primitive (as modelled; if it always achieved; if it never "
                         "did):")
            width = max(len(r["primitive"]) for r in self.sensitivity)
            for r in self.sensitivity:
                lines.append(f"    {r['primitive']:<{width}}  {r['ok']:.4f}  "
                             f"{r['ok_if_it_always_achieves']:.4f}  "
                             f"{r['ok_if_it_never_achieves']:.4f}  swing {r['swing']:.4f}")
        return lines


def _s(seconds: float | None) -> str:
    return "never" if seconds is None else f"{seconds:g} s"


def odds(mission: Path, model_path: Path, options: OddsOptions = OddsOptions(), *,
         notes: Notes | None = None) -> OddsOutcome:
    """``mcl2pnml odds`` with ``options``: the exact odds of a mission (MCL) with a vehicle
    model; with ``properties`` (``--properties [FILE]``) the probability that each of the
    mission's properties holds; the chain in PRISM's language to ``prism`` if asked (Storm
    and PRISM read it)."""
    # the chain's engine and vehicle model: the runtime, 40 ms at start-up; only odds
    from mcl2pnml import odds as exact
    from mcl2pnml.runtime.executor import PetriEngine
    from mcl2pnml.runtime.vehicle_model import VehicleModel
    o, notes = options, Notes() if notes is None else notes
    if mission.suffix != ".mcl":
        raise SettingError("mission", f"'{mission}' is not a mission (.mcl): the odds are a "
                                      "mission's, run as the engines run it")
    extra = None if o.properties is None else properties_file(mission, o.properties)
    check_outputs([("prism", o.prism)], [("the mission", mission),
                                            ("the vehicle model", model_path),
                                            ("the properties file (--properties)", extra)])
    model = VehicleModel.load(model_path)
    net, props = mission_net(mission, extra, o)
    used = PetriEngine(net).primitives_used()
    model.check_primitives(used)
    chain = exact.chain_of(net, model, o.max_states, props)
    odds = exact.odds_of(chain)
    if o.prism is not None:
        atomic_write_text(o.prism, exact.to_prism(chain, f"{mission.name} with "
                                                         f"{model_path.name}"))
        notes(f"wrote {o.prism}")
    table = exact.sensitivity(net, model, used, o.max_states, odds.outcomes["OK"]) \
        if o.sensitivity else []
    return OddsOutcome(mission.name, model_path.name, odds, table)
