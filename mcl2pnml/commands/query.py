"""``mcl2pnml query NET [FORMULAS.xml...]``: the Model Checking Contest's formula files and
generic examinations answered on any net we read (docs/interop.md)."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Sequence

from mcl2pnml import pipeline
from mcl2pnml.commands.common import MISSION_SIZE
from mcl2pnml.core.bounds import MAX_STATES
from mcl2pnml.core.settings import SettingError, size_or_none

#: The contest's generic examinations ``query --examination`` answers.
EXAMINATIONS = ("ReachabilityDeadlock", "OneSafe", "StableMarking", "QuasiLiveness",
                "Liveness")


@dataclass(frozen=True)
class QueryOptions:
    """``query``'s settings, by the names of its options (``--help`` says each)."""

    #: generic examinations of :data:`EXAMINATIONS`, besides the formula files
    examinations: tuple[str, ...] = ()
    max_states: int = MAX_STATES
    max_memory: str | None = None
    #: search reachability on the fly under partial-order reduction, on a safe net
    stubborn: bool = False
    net_id: str | None = None
    lenient: bool = False
    max_mission_size: str = MISSION_SIZE


@dataclass(frozen=True)
class QueryOutcome:
    """What ``mcl2pnml query`` prints: one answer per formula and examination."""

    net: str
    answers: list[Any]

    @property
    def status(self) -> int:
        """0 when every question is answered, 3 when one is not."""
        return 3 if any(a.value is None for a in self.answers) else 0

    def lines(self) -> list[str]:
        return [a.line() for a in self.answers]

    def as_json(self) -> dict[str, Any]:
        return {"net": self.net, "answers": [
            {"id": a.id, "value": a.value, **({"technique": a.technique} if a.technique else {}),
             **({"reason": a.reason} if a.reason else {})} for a in self.answers]}


def query(net_path: Path, formulas: Sequence[Path], options: QueryOptions = QueryOptions()
          ) -> QueryOutcome:
    """``mcl2pnml query`` with ``options`` (:mod:`mcl2pnml.analysis.contest.answers`): every
    answer, the formulas' in the files' order, then the examinations'."""
    stream = query_as_found(net_path, formulas, options)
    got = {a.id: a for a in stream}
    return QueryOutcome(stream.net, [got[k] for k in stream.ids])


class QueryStream:
    """The answers of one ``query`` run, each as soon as it is settled (the order the
    techniques settle them in, as the contest's tools print them: a run cut short keeps
    what it printed); ``status`` as :attr:`QueryOutcome.status` once they are all out."""

    def __init__(self, net: str, ids: list[str], answers: Iterator[Any]):
        self.net, self.ids, self._answers = net, ids, answers
        self.unanswered = False

    def __iter__(self) -> Iterator[Any]:
        for a in self._answers:
            self.unanswered |= a.value is None
            yield a

    @property
    def status(self) -> int:
        return 3 if self.unanswered else 0


def query_as_found(net_path: Path, formulas: Sequence[Path],
                   options: QueryOptions = QueryOptions()) -> QueryStream:
    """The files and the net read and checked now (a bad one raises before any answer);
    the answers as they come, when iterated."""
    # the contest's answers and query reader: numpy 0.1 s and 25 ms; only query
    from mcl2pnml.analysis.contest import answers as mcc
    from mcl2pnml.io.mccquery import read_queries
    o = options
    if not formulas and not o.examinations:
        raise SettingError("formulas", "give a formula file of the contest, or --examination")
    queries = [x for path in formulas for x in read_queries(path)]
    net = pipeline.load_net(net_path, o.net_id, o.max_memory, o.lenient, o.max_mission_size)
    max_memory = size_or_none(o.max_memory, "max_memory")

    def answers() -> Iterator[Any]:
        if queries:
            yield from mcc.answers_as_found(net, queries, max_states=o.max_states,
                                            max_memory=max_memory, stubborn=o.stubborn)
        if o.examinations:
            from mcl2pnml.analysis.contest.generic import generic_as_found  # as mcc, above
            yield from generic_as_found(net, o.examinations, max_states=o.max_states,
                                        max_memory=max_memory)
    return QueryStream(net.name, [x.id for x in queries] + list(o.examinations), answers())
