"""``mcl2pnml run MISSION``: a mission run against a vehicle (docs/running.md), its outcome
printed whatever signal comes at its end."""
from __future__ import annotations

import signal
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Iterator

from mcl2pnml import pipeline
from mcl2pnml.commands.common import MISSION_SIZE
from mcl2pnml.core.progress import Notes
from mcl2pnml.runtime import interrupts
from mcl2pnml.runtime.options import RunOptions


@dataclass(frozen=True)
class RunCommandOptions:
    """``run``'s settings: how to run (:class:`~mcl2pnml.runtime.options.RunOptions`, whose
    defaults the options take), and what the command reads and prints."""

    run: RunOptions = RunOptions()
    #: print only the outcome as JSON (no live log)
    as_json: bool = False
    #: also log the run here as JSON lines
    log_path: Path | None = None
    net_id: str | None = None
    lenient: bool = False
    max_mission_size: str = MISSION_SIZE


@dataclass(frozen=True)
class RunOutcome:
    """The run (:class:`mcl2pnml.runtime.engine.Run`): its outcome, time, trace and safe
    stop; the exit status is its outcome's."""

    run: Any

    @property
    def status(self) -> int:
        return self.run.exit_status

    def lines(self) -> list[str]:
        return list(self.run.report())

    def as_json(self) -> dict[str, Any]:
        return self.run.as_json()


def run(mission: Path, options: RunCommandOptions = RunCommandOptions(), *,
        live: IO[str] | None = None, notes: Notes | None = None) -> RunOutcome:
    """``mcl2pnml run`` with ``options``; the live log to ``live`` (None: none)."""
    o = options
    return RunOutcome(pipeline.run_mission(
        mission, o.run, text=live, log_path=o.log_path, net_id=o.net_id, lenient=o.lenient,
        max_mission_size=o.max_mission_size, note=Notes() if notes is None else notes))


@contextmanager
def printing() -> Iterator[None]:
    """The run's end: its outcome is printed whatever signal comes now (but a third)."""
    with interrupts.guard(interrupts.Phase.PRINTING):
        yield


def interrupted_status(cause: BaseException | None) -> int:
    """The exit status of a command a signal stopped (:func:`interrupts.exit_status`: 130
    SIGINT, 143 SIGTERM); Ctrl-C's where the cause does not say."""
    return interrupts.exit_status(getattr(cause, "signum", signal.SIGINT))
