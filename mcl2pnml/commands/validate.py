"""``mcl2pnml validate FILE``: a PNML file against our schema, the official grammar where it
is given, and the P/T net rules."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mcl2pnml import pipeline
from mcl2pnml.core.errors import shown, visible
from mcl2pnml.core.net import Net
from mcl2pnml.core.vocabulary import counted


@dataclass(frozen=True)
class ValidateOptions:
    """``validate``'s settings, by the names of its options (``--help`` says each)."""

    #: the folder of the official PNML grammar (None: $MCL2PNML_PNML_GRAMMAR's, or none)
    grammar: Path | None = None
    net_id: str | None = None


@dataclass(frozen=True)
class ValidateOutcome:
    """The verdict on ``file`` (:func:`mcl2pnml.io.pnml.grammar.validate`) and the net when
    it is valid; invalid: every problem on standard error, exit status 2."""

    file: Path
    verdict: Any
    net: Net | None

    @property
    def status(self) -> int:
        return 0 if self.verdict.valid else 2

    def problems(self) -> list[str]:
        """What an invalid file prints on standard error: each problem, then the count."""
        if self.verdict.valid:
            return []
        return [*shown(self.verdict.errors),
                f"{visible(str(self.file))}: invalid PNML "
                f"({counted(len(self.verdict.errors), 'problem')}; "
                f"{self.verdict.judges()})"]

    def lines(self) -> list[str]:
        """What a valid file prints: its judges and its size."""
        if not self.verdict.valid:
            return []
        net = self.net
        return [f"{visible(str(self.file))}: valid PNML P/T net ({self.verdict.judges()}): "
                f"{counted(len(net.places), 'place')}, "
                f"{counted(len(net.transitions), 'transition')}, {counted(len(net.arcs), 'arc')}"]

    def as_json(self) -> dict[str, Any]:
        return {"file": str(self.file), "valid": self.verdict.valid,
                "problems": [str(e) for e in self.verdict.errors]}


def validate(file: Path, options: ValidateOptions = ValidateOptions()) -> ValidateOutcome:
    """``mcl2pnml validate`` with ``options``."""
    verdict, net = pipeline.validate_pnml(file, options.grammar, options.net_id)
    return ValidateOutcome(file, verdict, net)
