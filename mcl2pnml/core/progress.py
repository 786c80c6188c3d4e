"""What a long stage says on its way, as data: a progress line and notes, written to a stream.

A command's caller hands the stage the stream to write to (the CLI: standard error),
never a function of its own, so that nothing under the CLI calls up into it: the
explorer calls :class:`ProgressMeter` (its ``Progress``), the stages a :class:`Notes`, a
live page its :class:`Announcement`, a campaign its :class:`RunsBar`: all of this layer.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import IO, Any


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


@dataclass(frozen=True)
class Announcement:
    """A line said once a value is known (the URL a live page is served on): ``before``,
    the value, ``after``, to ``notes``."""

    notes: Notes
    before: str
    after: str = ""

    def __call__(self, value: str) -> None:
        self.notes(f"{self.before}{value}{self.after}")


class RunsBar:
    """A bar of the runs done, their rate and the time left, on ``stream`` if ``shown``;
    what is said meanwhile (:attr:`notes`) printed above it, not through it.

    Called as a campaign's ``progress`` (the runs done, the runs asked); a context
    manager: the bar is closed however the campaign ends.
    """

    def __init__(self, runs: int, shown: bool, stream: IO[str]):
        from tqdm import tqdm   # 90 ms at start-up: only a campaign's bar
        self.bar = tqdm(total=runs, unit=" runs", file=stream, disable=not shown,
                        dynamic_ncols=True)
        self.notes = Notes(_AboveBar(tqdm, stream) if shown else stream)

    def __call__(self, done: int, runs: int) -> None:
        self.bar.update(done - self.bar.n)

    def __enter__(self) -> "RunsBar":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.bar.close()


class _AboveBar:
    """A stream whose lines tqdm writes above its bar."""

    def __init__(self, tqdm: Any, stream: IO[str]):
        self.tqdm, self.stream = tqdm, stream

    def write(self, text: str) -> None:
        self.tqdm.write(text.removesuffix("\n"), file=self.stream)

    def flush(self) -> None:
        self.stream.flush()
