"""The exact odds of a mission with a vehicle model: how likely each ending is, and when.

The mission runs as the engines run it (the Petri-net executor, section 2.1;
docs/time.md: the supervisor first, time-outs exactly their seconds after
they start, one stimulus at a time in the run loop's order). Its vehicle is a
:class:`~mcl2pnml.runtime.vehicle_model.ModelVehicle`, whose every choice
(which report, after how long) is enumerated with its probability instead of
drawn. A state of the chain is a settled *instant*: the executor's state
(marking and running time-outs) and what the vehicle will still do, both
relative to now; a step takes every stimulus of the next instant, and lasts
until it. The result is a discrete-time Markov chain with one step per
instant, solved by :mod:`mcl2pnml.analysis.markov` (probabilities of OK, FAIL, ABORTED
and of never ending; the expected end time, its spread and distribution).

Properties (docs/properties.md) are judged on the same runs: each firing's
marking is read by the property's observer (:mod:`mcl2pnml.analysis.checking.observers`, the
one the model checkers' verdicts use), whose state joins the chain's, so
that the chain is the product of the mission, its vehicle and the
observers. A run ends in an absorbing state (a finite run, judged on its
observer's last state) or loops in a bottom strongly connected component,
whose every state it then visits infinitely often with probability 1 (the
property fails on it when every state of the component owes something:
Baier and Katoen, *Principles of Model Checking*, 2008, section 10.3).

The same vehicle, drawing its choices, flies the simulated runs of
``run --vehicle model:FILE``: the tests hold the exact odds to thousands of
such runs on both engines, and to Storm's on the chain exported
(:func:`to_storm`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import Iterable, Sequence

import numpy as np
from scipy import sparse

from mcl2pnml.analysis.checking.observers import Watcher
from mcl2pnml.analysis.markov import (CYCLES, Chain, bottom_components, closed_classes,
                                      reaching, solve)
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import Net
from mcl2pnml.core.patterns import Property
from mcl2pnml.core.bounds import MAX_CHAIN_STATES
from mcl2pnml.runtime.aal import causal_order
from mcl2pnml.runtime.engine import Outcome
from mcl2pnml.runtime.executor import PetriEngine
from mcl2pnml.runtime.vehicle_model import Choice, ModelVehicle, Replay, VehicleModel

#: The labels of the chain's absorbing states: the mission's results, and a mission
#: that waits for ever (nothing pending: a primitive that never reports, no time-out).
ENDS = (Outcome.OK.value, Outcome.FAIL.value, Outcome.ABORTED.value)
WAITS = "waits"


class TooManyStates(Mcl2PnmlError):
    """The chain has more instants than the bound."""


@dataclass
class Instant:
    """A state of the chain: the engine and the vehicle settled at ``now``, and the
    properties' observers after every marking so far."""

    engine: PetriEngine
    vehicle: ModelVehicle
    now: float
    observed: tuple = ()

    def key(self) -> tuple:
        return self.engine.state(), self.vehicle.state(self.now), self.observed

    def next_time(self) -> float | None:
        te, timer = self.vehicle.earliest(), self.engine.next_timer()
        times = [x for x in (te, timer[0] if timer else None) if x is not None]
        return min(times) if times else None


def _deliver(vehicle: ModelVehicle, actions) -> None:
    for action in causal_order(actions):
        vehicle.act(action)


def _settle_instant(engine: PetriEngine, vehicle: ModelVehicle, t: float) -> None:
    """Every stimulus due at ``t``, in the run loop's order (:func:`~mcl2pnml.runtime
    .engine.run`: the vehicle's events before a time-out at one instant), and what
    each causes, until the mission has a result or nothing more is due at ``t``."""
    while engine.outcome is None:
        te, timer = vehicle.next_event_time(until=t), engine.next_timer()
        by_vehicle = te is not None and te <= t and (timer is None or te <= timer[0])
        if by_vehicle:
            _deliver(vehicle, engine.on_event(vehicle.take_event()))
        elif timer is not None and timer[0] <= t:
            _deliver(vehicle, engine.fire_timer(timer[0], timer[1]))
        else:
            return


def _branches(base: Instant | None, net: Net, model: VehicleModel, t: float,
              watcher: Watcher | None = None) -> list[tuple[Fraction, Instant]]:
    """Every way the instant ``t`` can go from ``base`` (None: the mission's start), each
    with its probability: the vehicle's choices tried in turn, each from a fresh copy.
    The ``watcher``'s observers read every marking the engine passes through."""
    out, todo = [], [((), Fraction(1))]
    while todo:
        made, p = todo.pop()
        chooser = Replay(made)
        if base is None:
            engine = PetriEngine(net)
            vehicle = ModelVehicle(model, chooser)
            seen = [watcher.start(engine.marking) if watcher else ()]
        else:
            engine, vehicle = base.engine.clone(), base.vehicle.copy(chooser)
            seen = [base.observed]
        if watcher is not None:
            def read(_t, _name, engine=engine, seen=seen):
                seen[0] = watcher.read(seen[0], engine.marking)
            engine.on_fire = read
        try:
            if base is None:
                _deliver(vehicle, engine.start(t))
            _settle_instant(engine, vehicle, t)
        except Choice as c:
            todo.extend(((*made, k), p * q) for k, (_, q) in enumerate(c.options))
            continue
        engine.on_fire = None
        vehicle.chooser = None      # settled: no choice is left to make before the next one
        out.append((p, Instant(engine, vehicle, t, seen[0])))
    return out


@dataclass
class MarkovChain:
    """The chain of a mission's instants (module documentation)."""

    #: each state's successors, with their exact probabilities
    successors: list[list[tuple[int, Fraction]]] = field(default_factory=list)
    #: how long each state's step lasts (0 for an absorbing state, and the start's)
    duration: list[float] = field(default_factory=list)
    #: each absorbing state's label (ENDS, WAITS), "" for the others
    label: list[str] = field(default_factory=list)
    #: the properties watched (:class:`Watcher`), and for each state whether each one
    #: is owed something there (a run ending there, or staying in such states, fails it)
    properties: tuple[Property, ...] = ()
    pending: list[tuple[bool, ...]] = field(default_factory=list)

    @property
    def size(self) -> int:
        return len(self.label)

    def as_analysis(self):
        """The chain as :class:`mcl2pnml.analysis.markov.Chain` (floats, CSR)."""
        rows, cols, data = [], [], []
        for s, succ in enumerate(self.successors):
            if not succ:                        # absorbing: a self-loop
                rows.append(s), cols.append(s), data.append(1.0)
            for j, p in succ:
                rows.append(s), cols.append(j), data.append(float(p))
        P = sparse.csr_matrix((data, (rows, cols)), shape=(self.size, self.size))
        return Chain(P, np.array(self.duration, dtype=float), tuple(self.label))


def chain_of(net: Net, model: VehicleModel, max_states: int = MAX_CHAIN_STATES,
             properties: Sequence[Property] = ()) -> MarkovChain:
    """The chain of ``net`` run against ``model`` (the module's documentation), in
    product with the observers of ``properties``."""
    chain = MarkovChain(properties=tuple(properties))
    watcher = Watcher(properties, PetriEngine(net).places) if properties else None
    index: dict[tuple, int] = {}
    instants: list[Instant | None] = []     # None: the start, or explored

    def state(inst: Instant) -> int:
        key = inst.key()
        found = index.get(key)
        if found is None:
            if len(instants) >= max_states:
                raise TooManyStates(f"the odds need more than {max_states:,} states of the "
                                    "mission and its vehicle (raise --max-states)")
            found = index[key] = len(instants)
            instants.append(inst)
            chain.successors.append([]), chain.duration.append(0.0), chain.label.append("")
            chain.pending.append(watcher.pending(inst.observed) if watcher else ())
        return found

    # state 0: the mission before its start, whose first actions the vehicle may answer
    # in several ways (a step that takes no time)
    instants.append(None)
    chain.successors.append([]), chain.duration.append(0.0), chain.label.append("")
    chain.pending.append(tuple(False for _ in properties))
    first: dict[int, Fraction] = {}
    for p, inst in _branches(None, net, model, 0.0, watcher):
        j = state(inst)
        first[j] = first.get(j, Fraction(0)) + p
    chain.successors[0] = sorted(first.items())
    done = 1
    while done < len(instants):
        s, inst = done, instants[done]
        done += 1
        outcome = inst.engine.outcome
        if outcome is not None:
            chain.label[s] = outcome.value
            continue
        at = inst.next_time()
        if at is None:
            chain.label[s] = WAITS
            continue
        chain.duration[s] = at - inst.now
        merged: dict[int, Fraction] = {}
        for p, nxt in _branches(inst, net, model, at, watcher):
            j = state(nxt)
            merged[j] = merged.get(j, Fraction(0)) + p
        chain.successors[s] = sorted(merged.items())
        instants[s] = None      # explored: only its row is kept
    return chain


@dataclass(frozen=True)
class PropertyOdds:
    """The probability that a property holds on the mission's runs with the vehicle."""

    name: str
    text: str
    holds: float
    #: the same, exactly, for a chain small enough (None: too large)
    exact: Fraction | None = None

    def as_json(self) -> dict:
        return {"property": self.name, "text": self.text, "holds": self.holds,
                "fails": 1.0 - self.holds,
                **({"exact_holds": str(self.exact)} if self.exact is not None else {})}


@dataclass(frozen=True)
class Odds:
    """What ``mcl2pnml odds`` reports (docs/odds.md)."""

    #: the probability of each ending: OK, FAIL, ABORTED, and "never" (it waits or
    #: loops for ever)
    outcomes: dict[str, float]
    #: the end time, given that the mission ends: mean, standard deviation, quantiles
    mean: float | None
    spread: float | None
    quantiles: dict[str, float | None]
    #: (t, P(ended by t)) at each time the mission can end
    distribution: list[tuple[float, float]]
    #: the chain's size
    states: int
    transitions: int
    #: the probability still unresolved past the distribution's horizon
    beyond: float = 0.0
    #: the outcomes as exact fractions, for a chain small enough (None: too large)
    exact: dict[str, Fraction] | None = None
    #: the probability of each property watched (``odds --properties``)
    properties: tuple[PropertyOdds, ...] = ()

    def as_json(self) -> dict:
        exact = {"exact_outcomes": {k: str(v) for k, v in self.exact.items()}} \
            if self.exact is not None else {}
        props = {"properties": [p.as_json() for p in self.properties]} \
            if self.properties else {}
        return {"outcomes": self.outcomes, **exact, **props, "end_time": {
            "mean": self.mean, "std": self.spread, **self.quantiles},
            "distribution": [{"t": t, "ended": p} for t, p in self.distribution],
            "states": self.states, "transitions": self.transitions,
            **({"beyond_horizon": self.beyond} if self.beyond else {})}


QUANTILES = (0.05, 0.5, 0.95)
#: Chains of at most this many transient states get their outcomes as exact fractions too.
EXACT_STATES = 1_000


def exact_outcomes(chain: MarkovChain) -> dict[str, Fraction] | None:
    """The probability of each ending as an exact fraction (None: a chain of more than
    :data:`EXACT_STATES` transient states)."""
    label = list(chain.label)
    for s in closed_classes(chain.as_analysis()):
        label[s] = CYCLES
    found = _exact_reaching(chain, label)
    return None if found is None else _endings(found)


def _exact_reaching(chain: MarkovChain, label: list[str]) -> dict[str, Fraction] | None:
    """The probability of reaching each label's states first, from state 0, as exact
    fractions (every run reaching a labelled state): (I - Q) X = B solved over the
    rationals (FLINT's ``fmpq_mat``) from the model's exact probabilities. None for a
    chain of more than :data:`EXACT_STATES` transient states."""
    import flint   # python-flint: loaded only for the exact fractions of a small chain
    names = sorted({x for x in label if x})
    if label[0]:
        return {name: Fraction(int(label[0] == name)) for name in names}
    transient = [s for s, x in enumerate(label) if not x]
    if len(transient) > EXACT_STATES:
        return None
    index = {s: k for k, s in enumerate(transient)}
    column = {name: c for c, name in enumerate(names)}
    a = flint.fmpq_mat(len(transient), len(transient))
    b = flint.fmpq_mat(len(transient), len(names))
    for k, s in enumerate(transient):
        a[k, k] += 1
        for j, p in chain.successors[s]:
            q = flint.fmpq(p.numerator, p.denominator)
            if j in index:
                a[k, index[j]] -= q
            else:
                b[k, column[label[j]]] += q
    x = a.solve(b)
    row = index[0]
    return {name: Fraction(int(x[row, c].p), int(x[row, c].q))
            for c, name in enumerate(names)}


def fate_labels(chain: MarkovChain) -> list[str]:
    """Each bottom strongly connected component labelled with the properties that a run
    ending in it fails: "v" and one digit per property (1: fails), "" elsewhere. An
    absorbing state is a component of its own (a finite run, judged on its last
    observer states); a larger one, a loop, fails what every one of its states owes."""
    label = [""] * chain.size
    for component in bottom_components(chain.as_analysis()):
        fails = (all(chain.pending[s][k] for s in component)
                 for k in range(len(chain.properties)))
        fate = "v" + "".join("1" if f else "0" for f in fails)
        for s in component:
            label[s] = fate
    return label


def property_odds(chain: MarkovChain) -> list[PropertyOdds]:
    """The probability that each property the chain watched holds."""
    if not chain.properties:
        return []
    label = fate_labels(chain)
    reach = reaching(chain.as_analysis(), label)
    exact = _exact_reaching(chain, label)
    out = []
    for k, prop in enumerate(chain.properties):
        holds = sum(p for fate, p in reach.items() if fate[1 + k] == "0")
        sure = sum((p for fate, p in exact.items() if fate[1 + k] == "0"), Fraction(0)) \
            if exact is not None else None
        out.append(PropertyOdds(prop.name, prop.text, min(max(holds, 0.0), 1.0), sure))
    return out


def _endings(by_label: dict[str, Fraction]) -> dict[str, Fraction]:
    """The results, and "never" for waiting or cycling for ever."""
    out = {e: by_label.get(e, Fraction(0)) for e in ENDS}
    out["never"] = by_label.get(WAITS, Fraction(0)) + by_label.get("cycles", Fraction(0))
    return out


def odds_of(chain: MarkovChain) -> Odds:
    a = solve(chain.as_analysis(), ENDS)
    outcomes = {e: a.probability.get(e, 0.0) for e in ENDS}
    outcomes["never"] = a.probability.get(WAITS, 0.0) + a.probability.get(CYCLES, 0.0)
    quantiles = {f"p{round(q * 100)}": a.quantile(q) for q in QUANTILES}
    return Odds(outcomes, a.mean, a.spread, quantiles,
                [(float(t), float(p)) for t, p in zip(a.times, a.cdf)], chain.size,
                sum(len(s) for s in chain.successors), a.beyond, exact_outcomes(chain),
                tuple(property_odds(chain)))


def odds(net: Net, model: VehicleModel, max_states: int = MAX_CHAIN_STATES) -> Odds:
    """The exact odds of the compiled mission ``net`` with the vehicle ``model``."""
    model.check_primitives(PetriEngine(net).primitives_used())
    return odds_of(chain_of(net, model, max_states))


def sensitivity(net: Net, model: VehicleModel, primitives: Iterable[str],
                max_states: int = MAX_CHAIN_STATES, base: float | None = None) -> list[dict]:
    """For each primitive, P(OK) as modelled (``base``, when the caller has it), if it
    always achieved, and if it never did (its failures taking the place of its
    successes): which primitive's reliability moves the mission's odds most."""
    if base is None:
        base = odds(net, model, max_states).outcomes["OK"]
    rows = []
    for name in sorted(primitives):
        m = model.of(name)
        perfect = odds(net, model.replaced(name, achieve=Fraction(1), fail=Fraction(0)),
                       max_states).outcomes["OK"]
        broken = odds(net, model.replaced(name, achieve=Fraction(0), fail=m.achieve + m.fail),
                      max_states).outcomes["OK"]
        rows.append({"primitive": name, "achieve": float(m.achieve), "ok": base,
                     "ok_if_it_always_achieves": perfect, "ok_if_it_never_achieves": broken,
                     "swing": perfect - broken})
    return sorted(rows, key=lambda r: -r["swing"])


def owes_labels(properties: Sequence[Property]) -> list[str]:
    """The PRISM label of each property's owing states: ``owes_NAME`` (``owes_NAME_2``
    for a second property of that name, from another file)."""
    out: list[str] = []
    for prop in properties:
        label, k = f"owes_{prop.name}", 1
        while label in out:
            k += 1
            label = f"owes_{prop.name}_{k}"
        out.append(label)
    return out


def to_prism(chain: MarkovChain, title: str) -> str:
    """The chain in PRISM's language (a ``dtmc`` of one variable, its state), which PRISM
    and Storm read: the exact probabilities as fractions, a label per ending ("OK",
    "FAIL", "ABORTED", "waits", and "ended" for the three results), one per property
    watched ("owes_NAME", the states where it is owed something) and a reward "time",
    each state's duration, so that ``R{"time"}=? [F "ended"]`` is the expected end time
    of a mission that surely ends."""
    n = chain.size
    lines = [f"// {title}: the exact odds' chain (mcl2pnml odds, docs/odds.md)",
             "// one state per instant; each state's reward \"time\" is how long it lasts",
             "dtmc", "", "module mission", f"  s : [0..{max(n - 1, 0)}] init 0;"]
    for s, successors in enumerate(chain.successors):
        if not successors:
            lines.append(f"  [] s={s} -> true;")
            continue
        lines.append(f"  [] s={s} -> " + " + ".join(f"{p.numerator}/{p.denominator} : (s'={j})"
                                                    for j, p in successors) + ";")
    lines += ["endmodule", ""]
    groups = {name: [s for s, x in enumerate(chain.label) if x == name]
              for name in (*ENDS, WAITS)}
    groups["ended"] = [s for s, x in enumerate(chain.label) if x in ENDS]
    for k, name in enumerate(owes_labels(chain.properties)):
        # where the property is owed something: a run that ends there, or stays in such
        # states for ever, fails it (P=? [F G "owes_NAME"] is its probability of failing)
        groups[name] = [s for s, owed in enumerate(chain.pending) if owed and owed[k]]
    for name, states in groups.items():
        body = " | ".join(f"s={s}" for s in states) if states else "false"
        lines.append(f'label "{name}" = {body};')
    lines += ["", 'rewards "time"']
    lasting = [f"  s={s} : {Fraction(d).limit_denominator(10**6)};"
               for s, d in enumerate(chain.duration) if d]
    lines += lasting or ["  true : 0;"]     # a mission that takes no time: PRISM needs one
    lines += ["endrewards", ""]
    return "\n".join(lines)
