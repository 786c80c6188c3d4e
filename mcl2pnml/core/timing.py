"""Time in the verdicts: a net's timed semantics, and the one a compiled mission runs in.

docs/time.md is the prose of what this module states in types. A
:class:`TimedNet` is a P/T net read as a time Petri net with priorities
(Merlin and Farber's static intervals, as TINA reads them; Berthomieu,
Peres and Vernadat's priorities), with two additions a vehicle needs:

* every transition has a static interval ``[earliest, latest]`` in whole
  units of time: its clock starts when the transition becomes enabled (and
  again when it fires and stays enabled); it may fire once the clock has
  reached ``earliest`` and must fire (or be disabled) before it passes
  ``latest``. ``[0, None]`` is an untimed transition, ``[0, 0]`` an urgent
  one: time does not pass while it is enabled;
* ``priority``: transitions that, while one of them is enabled, are the only
  ones that may fire (the supervisor's steps: the engines take every step
  they can before anything else happens);
* ``eager``: transitions that come next, after the priority ones: while one
  is enabled (and no priority transition is), only they may fire (the
  vehicle's acknowledgements at once, taken before any other vehicle event of
  their instant, as the engines take a scripted vehicle's);
* ``gaps``: groups of transitions whose firings are at least a number of
  units apart (a primitive's reports: no vehicle reports infinitely often
  in one instant), the first one of a group at any time;
* ``fair``: groups of transitions of which one must eventually fire when
  one of them stays enabled (a primitive that is on eventually reports);
* ``shared``: groups of transitions with one clock between them, which
  starts when the first of them becomes enabled and runs while one of them
  is (a disable's acknowledgement is one of three transitions, ``off_C``,
  ``off_S1``, ``off_S2``, by the state of the goal: a report that moves the
  goal while the disable is pending does not restart the vehicle's delay).
  Members share their interval.

A transition newly enabled by a firing is one enabled after it and not
before it, or the fired transition itself (the executor's rule: a
transition that stays enabled keeps its timer).

:func:`mission_timing` reads a compiled mission's transitions by their
payloads (:mod:`mcl2pnml.core.payloads`) and gives each its interval under
the vehicle's :class:`Assumptions`. May import: the rest of the core.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from decimal import Decimal
from fractions import Fraction
from typing import Mapping

from mcl2pnml.core.bounds import MAX_ACK_WITHIN, MAX_REPORT_GAP
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import Net
from mcl2pnml.core.payloads import EventKind, read_transition
from mcl2pnml.core.settings import SettingError

#: The longest each assumption on the vehicle may be, in seconds, by its setting's name,
#: and why (docs/time.md, "The bounds on the assumptions").
LONGEST = {"ack_within": (MAX_ACK_WITHIN, "ten minutes: a vehicle slower to acknowledge "
                                          "has a broken link"),
           "report_gap": (MAX_REPORT_GAP, "a day")}
#: The finest time there is, in digits after the point of a second: the timed analysis
#: and the TINA export count in whole microseconds.
DIGITS = 6
#: How many of those units a second has.
PER_SECOND = 10 ** DIGITS
_MICROSECOND = Decimal(1).scaleb(-DIGITS)


def exact_seconds(x: int | float | Fraction) -> Fraction:
    """The number of seconds ``x`` stands for, exactly: a float (a time-out of MCL, a
    timing of PNML, both read from decimal text) as the decimal of at most 15 significant
    digits nearest it. Every such decimal is one double and back again, so that
    ``999999999.999999`` read as a double is that decimal, not its binary neighbour."""
    return Fraction(format(x, ".15g")) if isinstance(x, float) else Fraction(x)


def finer_than_a_microsecond(x: int | float | Fraction) -> bool:
    """Whether ``x`` seconds (as :func:`exact_seconds` reads them) are not a whole number
    of microseconds, the finest time the timed analysis counts."""
    return (exact_seconds(x) * PER_SECOND).denominator != 1


def seconds_text(x: Fraction | int) -> str:
    """``x`` seconds written exactly, as every printer of a time writes it: a decimal
    (``100000.5``, ``1000000000``, ``0.001``), never rounded nor with an exponent. A unit
    of time is a decimal fraction of a second, so that a time has a finite decimal; one
    that has none (a third, from a library call) is written as the fraction ``p/q``."""
    x = Fraction(x)
    rest, twos, fives = x.denominator, 0, 0
    while rest % 2 == 0:
        rest, twos = rest // 2, twos + 1
    while rest % 5 == 0:
        rest, fives = rest // 5, fives + 1
    if rest != 1:
        return f"{x.numerator}/{x.denominator}"
    places = max(twos, fives)
    whole, part = divmod(abs(x.numerator) * 10 ** places // x.denominator, 10 ** places)
    return ("-" if x < 0 else "") + str(whole) + (f".{part:0{places}d}" if places else "")


@dataclass(frozen=True)
class Assumptions:
    """What the vehicle is assumed to do, printed with every timed verdict (docs/time.md).

    ``ack_within``: the vehicle acknowledges an enable (``on``) or a disable
    (``off``) within this many seconds of the request (0: at once, as the
    scripted and simulated vehicles do). ``report_gap``: a primitive's reports
    (``achieved``, ``failed``) are at least this many seconds apart. ``fair``:
    a primitive that is on and has not reported since it was enabled reports
    eventually (without it, a vehicle may stay silent for ever). ``priority``:
    the supervisor's steps come before any vehicle event at their instant, as in
    the engines; False is the semantics of timed-arc tools (urgency only).
    """

    ack_within: Fraction = Fraction(0)
    report_gap: Fraction = Fraction(1)
    fair: bool = False
    priority: bool = True

    def words(self) -> str:
        """The assumptions in one line, as every timed verdict is printed with."""
        ack = "at once" if self.ack_within == 0 else f"within {seconds_text(self.ack_within)} s"
        return (f"acknowledgements {ack}; a primitive's reports at least "
                f"{seconds_text(self.report_gap)} s apart; "
                + ("an enabled primitive reports eventually" if self.fair
                   else "a primitive may never report")
                + ("" if self.priority else "; supervisor steps urgent, not first"))

    def as_json(self) -> dict:
        return {"ack_within": _num(self.ack_within), "report_gap": _num(self.report_gap),
                "fair": self.fair, "priority": self.priority}


def _num(x: Fraction) -> int | float:
    return x.numerator if x.denominator == 1 else float(x)


def seconds_setting(text: str, setting: str) -> Fraction:
    """A number of seconds as an assumption's setting writes it (``ack_within``,
    ``report_gap``): 0 or more, at most its :data:`LONGEST`, in whole microseconds; one
    that is not is a :class:`~mcl2pnml.core.settings.SettingError` of ``setting``."""
    longest, why = LONGEST[setting]
    try:
        # a decimal is read as a Decimal, which keeps its exponent: Fraction("1e999999999")
        # would build the power of ten, for hours; "p/q" is two whole numbers
        value = Fraction(text) if "/" in text else Decimal(text)
    except (ValueError, ZeroDivisionError, ArithmeticError):
        value = None
    if value is None or isinstance(value, Decimal) and not value.is_finite():
        raise SettingError(setting, f"'{text}' is not a number of seconds")
    if value < 0 or value > longest:
        raise SettingError(setting, f"'{text}' is not between 0 and {longest:,} seconds "
                                    f"({why})")
    if isinstance(value, Decimal):
        # its digits past the DIGITS-th after the point, read without arithmetic (which
        # would round 1e-999999999 to 0 within the context's exponents)
        _, digits, exponent = value.as_tuple()
        past = -DIGITS - int(exponent)
        finer = past > 0 and any(digits[-past:])
    else:
        finer = finer_than_a_microsecond(value)
    if finer:
        raise SettingError(setting, f"'{text}' is finer than a microsecond")
    # a Decimal within the bounds is at most 11 digits of microseconds: quantized exactly
    return Fraction(value.quantize(_MICROSECOND)) if isinstance(value, Decimal) else value


@dataclass(frozen=True)
class TimedNet:
    """A net with its timed semantics (see the module's documentation), in whole units.

    ``unit`` is the length of one unit in seconds: every time bound of the
    net and of the assumptions is a whole number of it.
    """

    net: Net
    intervals: Mapping[str, tuple[int, int | None]]
    priority: frozenset[str] = frozenset()
    gaps: tuple[tuple[frozenset[str], int], ...] = ()
    fair: tuple[frozenset[str], ...] = ()
    unit: Fraction = Fraction(1)
    names: Mapping[str, str] = field(default_factory=dict)
    """What each gap or fairness group stands for (a primitive's name), by its first member."""
    shared: tuple[frozenset[str], ...] = ()
    eager: frozenset[str] = frozenset()

    def seconds(self, units: int | float) -> Fraction | float:
        return units * self.unit if not isinstance(units, float) else units * float(self.unit)


def _unit(values: list[Fraction]) -> Fraction:
    """The largest unit 1/q (q a power of ten, up to :data:`PER_SECOND`) in which every
    value, a whole number of microseconds (:func:`_check_microseconds`), is whole."""
    q = 1
    while not all((v * q).denominator == 1 for v in values):
        q *= 10
    return Fraction(1, q)


def _check_microseconds(net: Net, assumptions: Assumptions) -> None:
    """Refuse a time bound finer than a microsecond. A mission's time-outs were refused
    at their place in the file by the checker: a bound here is one of a net read from a
    file (a PNML timing), or an assumption given by a library call."""
    for name in ("ack_within", "report_gap"):
        value = getattr(assumptions, name)
        if finer_than_a_microsecond(value):
            raise SettingError(name, f"{seconds_text(value)} s is finer than a microsecond")
    for t in net.transitions:
        if t.timing is None:
            continue
        what = "time-out" if t.timing.earliest == t.timing.latest else "time bound"
        for bound in (t.timing.earliest, t.timing.latest):
            if bound is not None and finer_than_a_microsecond(bound):
                raise Mcl2PnmlError(
                    f"net '{net.name}': the {what} of transition {t.id}, "
                    f"{seconds_text(exact_seconds(bound))} s, is finer than a microsecond, "
                    "the finest time the timed analysis counts")


def mission_timing(net: Net, assumptions: Assumptions = Assumptions()) -> TimedNet:
    """The timed semantics of a compiled mission under ``assumptions`` (docs/time.md).

    * a time-out (a timed transition, the task's ``t03``) fires exactly its
      seconds after it became enabled: after the task started and its
      primitives acknowledged ``on`` (the read arc on ``ON``), as both engines
      start its timer;
    * an acknowledgement (``on``, ``off``) within ``ack_within`` of its request
      (one clock for a primitive's three ``off`` transitions); at once, it comes
      before any report or time-out of its instant (``eager``);
    * a report (``achieved``, ``failed``) at any time, a primitive's at least
      ``report_gap`` apart; with ``fair``, the first report after an enabling
      (a transition out of the primitive's ``C``) eventually;
    * every other transition is a step of the supervisor: urgent, and first
      when ``priority``.
    """
    _check_microseconds(net, assumptions)
    values = [exact_seconds(assumptions.ack_within), exact_seconds(assumptions.report_gap)]
    for t in net.transitions:
        if t.timing is not None:
            values.append(exact_seconds(t.timing.earliest))
            if t.timing.latest is not None:
                values.append(exact_seconds(t.timing.latest))
    unit = _unit(values)

    def units(x) -> int:
        return int(exact_seconds(x) / unit)

    intervals: dict[str, tuple[int, int | None]] = {}
    priority, reports, first, offs, eager = set(), {}, {}, {}, set()
    pre = net.pre
    for t in net.transitions:
        event = read_transition(t).event
        if t.timing is not None:
            latest = None if t.timing.latest is None else units(t.timing.latest)
            intervals[t.id] = (units(t.timing.earliest), latest)
        elif event is None:
            intervals[t.id] = (0, 0)
            priority.add(t.id)
        elif event.kind in (EventKind.ON, EventKind.OFF):
            intervals[t.id] = (0, units(assumptions.ack_within))
            if assumptions.ack_within == 0:
                eager.add(t.id)
            if event.kind is EventKind.OFF:
                offs.setdefault(event.primitive or t.id.rsplit(".", 1)[0], []).append(t.id)
        else:
            intervals[t.id] = (0, None)
            prim = event.primitive or t.id.rsplit(".", 1)[0]
            reports.setdefault(prim, []).append(t.id)
            # the first report of an enabling leaves C, the primitive's "seeking" place
            if any(a.source.rsplit(".", 1)[-1] == "C" and a.kind.name != "READ"
                   for a in pre[t.id]):
                first.setdefault(prim, []).append(t.id)
    gap = units(assumptions.report_gap)
    gaps = tuple((frozenset(ts), gap) for _, ts in sorted(reports.items())) if gap else ()
    fair = tuple(frozenset(ts) for _, ts in sorted(first.items())) if assumptions.fair else ()
    names = {min(ts): p for p, ts in list(reports.items()) + list(first.items())}
    shared = tuple(frozenset(ts) for _, ts in sorted(offs.items()) if len(ts) > 1)
    first_ = assumptions.priority
    return TimedNet(net, intervals, frozenset(priority) if first_ else frozenset(),
                    gaps, fair, unit, names, shared, frozenset(eager) if first_ else frozenset())

