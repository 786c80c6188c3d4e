"""How to run a mission, as typed values: ``mcl2pnml run``'s options, each default written here once.

Plain data of its own module, which imports nothing of the runtime's machinery: the
command line reads its defaults when it starts, and the link and the vehicles it
configures (:mod:`mcl2pnml.runtime.session`) cost a tenth of a second to import.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from mcl2pnml.core.bounds import MAX_RUN_TIME
from mcl2pnml.core.timing import Assumptions, seconds_setting
from mcl2pnml.runtime.limits import HEARTBEAT, LIVENESS, MAX_LINE, SEND_TIMEOUT


@dataclass(frozen=True)
class RunOptions:
    """How to run a mission: ``mcl2pnml run``'s options, as typed values."""

    #: petri: the executor plays the compiled net; reference: MCL interpreted directly
    engine: str = "petri"
    #: a kind of :data:`mcl2pnml.runtime.vehicles.VEHICLES`, with what follows its name
    vehicle: str = "sim"
    connect: str | None = None
    world: Path | None = None
    #: Python files of simulated primitives the simulator offers besides its own
    #: (:mod:`mcl2pnml.runtime.simprims`)
    sim_primitives: tuple[Path, ...] = ()
    #: faults injected into a simulated vehicle's events (:mod:`mcl2pnml.runtime.faults`)
    faults: Path | None = None
    max_time: float = MAX_RUN_TIME
    #: the assumptions on the vehicle the timed verdicts were proven under (docs/time.md),
    #: as written (``analyze --timed``'s): watched on every event, each breach said
    ack_within: str = str(Assumptions.ack_within)
    report_gap: str = str(Assumptions.report_gap)
    #: stop the run safely at the first breach (outcome BREACH)
    stop_on_breach: bool = False
    #: show fired transitions in the live log
    transitions: bool = False
    journal: Path | None = None
    resume: Path | None = None
    #: the live link to a real vehicle (mcl2pnml.runtime.link): its shared
    #: secret, TLS files, heartbeat period, liveness and send time-outs (s),
    #: and longest line (bytes)
    secret: Path | None = None
    tls_ca: Path | None = None
    tls_cert: Path | None = None
    tls_key: Path | None = None
    heartbeat: float = HEARTBEAT
    liveness: float = LIVENESS
    send_timeout: float = SEND_TIMEOUT
    max_line: int = MAX_LINE
    #: the options the user gave (a resumed run must not contradict its journal on them)
    explicit: frozenset[str] = field(default_factory=frozenset)

    def assumptions(self) -> Assumptions:
        """The assumptions watched, read as ``analyze`` reads them (one message, naming
        the option, for a bad one)."""
        return Assumptions(seconds_setting(self.ack_within, "ack_within"),
                           seconds_setting(self.report_gap, "report_gap"))
