"""What the paper says: equations 1 to 26, the oracle the analysis is compared with.

Transcribed from ``shared/paper/equations.md`` (the cleaned reading of the
scan), with the reading chosen where the scan is garbled. Nothing here is
computed; everything in :mod:`paper_repro.checks` is, from the templates.
"""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Equation:
    number: int
    kind: str                      # "invariant", "siphon", "marking", "final"
    net: str                       # the template the paper analyses
    text: str                      # as the paper writes it
    # invariant: coefficients and right-hand side; siphon / marking / final: places
    coefficients: dict[str, int] = field(default_factory=dict)
    value: int = 0
    places: tuple[str, ...] = ()
    start: tuple[str, ...] = ()    # for final markings: the M0 they are reached from
    group: tuple[int, ...] = ()    # final markings reached together from that M0
    reading: str = ""              # how a garbled scan was read, and why


def inv(n, net, text, coefficients, value, reading=""):
    return Equation(n, "invariant", net, text, coefficients, value, reading=reading)


def siphon(n, net, places):
    return Equation(n, "siphon", net, "{" + ", ".join(places) + "}", places=tuple(places))


def final(n, net, places, start, group):
    return Equation(n, "final", net, "{" + ", ".join(places) + "}", places=tuple(places),
                    start=tuple(start), group=tuple(group))


TASK_M0 = ("B", "A", "MTX", "OFF", "C")
TASK_M0_NO_ABORT = ("B", "MTX", "OFF", "C")
REDUCED_M0 = ("B", "A", "MTX")
REDUCED_M0_NO_ABORT = ("B", "MTX")
PRIMITIVE_ENABLED_DISABLED = ("OFF", "C", "E", "D")

EQUATIONS: tuple[Equation, ...] = (
    # the vehicle primitive (Fig. 1), section 2.2
    inv(1, "primitive", "ON + OFF = 1", {"ON": 1, "OFF": 1}, 1),
    inv(2, "primitive", "C + S1 + S2 = 1", {"C": 1, "S1": 1, "S2": 1}, 1),
    inv(3, "primitive", "-OFF - D + E = -1", {"OFF": -1, "D": -1, "E": 1}, -1),
    siphon(4, "primitive", ["ON", "OFF"]),
    siphon(5, "primitive", ["C", "S1", "S2"]),
    Equation(6, "marking", "primitive", "M0 = {OFF, C}", places=("OFF", "C")),
    final(7, "primitive", ["OFF", "C"], PRIMITIVE_ENABLED_DISABLED, (7,)),
    # the task fused with the primitive (Fig. 2), section 2.3: "six place invariants"
    inv(8, "task", "ON + OFF = 1", {"ON": 1, "OFF": 1}, 1),
    inv(9, "task", "C + S1 + S2 = 1", {"C": 1, "S1": 1, "S2": 1}, 1),
    inv(10, "task", "OFF + D - E + EXE + E_OK + E_FAIL = 1",
        {"OFF": 1, "D": 1, "E": -1, "EXE": 1, "E_OK": 1, "E_FAIL": 1}, 1,
        "printed twice in the scan"),
    inv(11, "task", "ABORTED + OK - MTX + FAIL + B = 0",
        {"ABORTED": 1, "OK": 1, "MTX": -1, "FAIL": 1, "B": 1}, 0,
        "the scan's leading '-' is a list bullet: read as a minus, the equation fails "
        "at the paper's own markings"),
    inv(12, "task", "ABORTED + A + W_A = 1", {"ABORTED": 1, "A": 1, "W_A": 1}, 1,
        "the scan prints 'ABORTED + A WA = 1' and numbers it 11 again"),
    inv(13, "task", "-ABORTED - OFF + MTX - D + E - A + W_OK + W_FAIL = -1",
        {"ABORTED": -1, "OFF": -1, "MTX": 1, "D": -1, "E": 1, "A": -1, "W_OK": 1,
         "W_FAIL": 1}, -1),
    siphon(14, "task", ["ON", "OFF"]),
    siphon(15, "task", ["C", "S1", "S2"]),
    siphon(16, "task", ["MTX", "EXE", "E_OK", "E_FAIL", "W_OK", "W_FAIL", "W_A"]),
    final(17, "task", ["A", "FAIL", "MTX", "OFF", "C"], TASK_M0, (17, 18, 19)),
    final(18, "task", ["A", "OK", "MTX", "OFF", "C"], TASK_M0, (17, 18, 19)),
    final(19, "task", ["ABORTED", "MTX", "OFF", "C"], TASK_M0, (17, 18, 19)),
    final(20, "task", ["FAIL", "MTX", "OFF", "C"], TASK_M0_NO_ABORT, (20, 21)),
    final(21, "task", ["OK", "MTX", "OFF", "C"], TASK_M0_NO_ABORT, (20, 21)),
    # the reduced task (Fig. 3), end of section 2.3
    final(22, "task-reduced", ["A", "FAIL", "MTX"], REDUCED_M0, (22, 23, 24)),
    final(23, "task-reduced", ["A", "OK", "MTX"], REDUCED_M0, (22, 23, 24)),
    final(24, "task-reduced", ["ABORTED", "MTX"], REDUCED_M0, (22, 23, 24)),
    final(25, "task-reduced", ["FAIL", "MTX"], REDUCED_M0_NO_ABORT, (25, 26)),
    final(26, "task-reduced", ["OK", "MTX"], REDUCED_M0_NO_ABORT, (25, 26)),
)

#: Section 2.3: "the resulting Petri net has six place invariants"; section 2.2: three.
INVARIANT_COUNT = {"primitive": 3, "task": 6}

#: Section 2.3: siphon 16 is "controlled by invariants 8, 9 and 10+12+13".
SIPHON_16_CONTROL = (10, 12, 13)

#: Section 2.5: the sequence's fusion groups (equations 27-29).
SEQUENCE_FUSION = {
    27: ("T1_B", "T1_A", "T1_MTX", "T1_OK", "T1_FAIL", "T1_ABORTED"),
    28: ("T2_B", "T2_A", "T2_MTX", "T2_OK", "T2_FAIL", "T2_ABORTED"),
    29: ("B", "A", "MTX", "OK", "FAIL", "ABORTED"),
}
