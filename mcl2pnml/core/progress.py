"""What a long stage says on its way, as data: a progress line and notes, written to a stream.

A command's caller hands the stage the stream to write to (the CLI: standard error),
never a function of its own, so that nothing under the CLI calls up into it: the
explorer calls :class:`ProgressMeter` (its ``Progress``), the stages a :class:`Notes`,
both of this layer.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import IO


@dataclass(frozen=True)
class ProgressMeter:
    """The explorer's progress, rewritten in place on one line of ``stream``.

    Called as ``meter(states, frontier)`` (the explorers' ``Progress``); :meth:`end`
    ends the line, once the exploration is over.
    """

    stream: IO[str]

    def __call__(self, states: int, frontier: int) -> None:
        self.stream.write(f"\r  explored {states:,} markings, {frontier:,} to go...")
        self.stream.flush()

    def end(self) -> None:
        """The progress line ended: what follows starts on a line of its own."""
        self.stream.write("\n")
        self.stream.flush()


@dataclass(frozen=True)
class Notes:
    """What a command says on its way (a warning, a file written), in order.

    Each line is kept (:attr:`said`, for the outcome) and written to ``stream`` at
    once if there is one (the CLI's standard error), so that a long stage's note is
    read before the stage ends.
    """

    stream: IO[str] | None = None
    said: list[str] = field(default_factory=list, compare=False)

    def __call__(self, line: str) -> None:
        self.said.append(line)
        if self.stream is not None:
            self.stream.write(line + "\n")
            self.stream.flush()
