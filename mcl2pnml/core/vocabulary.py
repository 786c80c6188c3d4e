"""The words the answers say: each property of a mission named once (docs/glossary.md).

The explorer's report, a certificate, the timed verdicts, the queries written for other
tools and the commands all speak of the same few properties. Each is named here, once,
so that one property reads the same in every answer, and two properties never share a
name: "a proper end is always reachable" (from every marking some run can still end,
``AG EF end``: what the explorer and a certificate decide, time aside) is not "every run
ends" (``AF end`` on the runs in time: what ``analyze --timed`` decides; a vehicle that
never reports makes a mission whose end is always reachable run for ever).
"""
from __future__ import annotations

#: No reachable marking puts two tokens in a place (the paper's section 2.2).
SAFE = "1-safe"
#: Every dead marking is a proper end (the paper's "free of deadlocks"); the textbook's
#: "deadlock-free" (no dead marking at all) is named where it is printed.
NO_DEADLOCK = "no deadlock (ours: every dead marking is a proper end)"
#: From every reachable marking a proper end can be reached: ``AG EF end``, time aside.
CAN_END = "a proper end is always reachable"
#: Bounded, no deadlock, and a proper end always reachable: the net can run again.
REUSABLE = "reusable"
#: What a certificate proves of a mission, in the order it is said.
CERTIFIED = (SAFE, CAN_END, REUSABLE)
#: Every run in time reaches a result: ``AF end`` on the time-divergent runs (docs/time.md).
ENDS = "every run ends"
#: A run that never ends because it goes round a loop.
CYCLE = "a cycle repeats for ever"
#: A run that never ends because nothing is left to happen and no result is marked.
STALL = "a state with nothing left to happen and no result"


def counted(n: int, noun: str, plural: str | None = None) -> str:
    """``n`` things in words: ``1 primitive``, ``2 primitives``, ``1,000 tasks``;
    ``plural`` where adding an s is not the plural."""
    return f"{n:,} {noun if n == 1 else plural or noun + 's'}"
