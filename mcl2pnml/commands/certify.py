"""``mcl2pnml certify MISSION``: the mission proven from its parts and its certificate
written, or (``--check NET``) a certificate re-checked against a compiled net."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mcl2pnml import pipeline
from mcl2pnml.commands.common import CERTIFICATE_SIZE, MISSION_SIZE
from mcl2pnml.core.files import check_outputs
from mcl2pnml.core.net import Net
from mcl2pnml.core.progress import Notes
from mcl2pnml.core.settings import SettingError
from mcl2pnml.core.vocabulary import CERTIFIED, counted


@dataclass(frozen=True)
class CertifyOptions:
    """``certify``'s settings, by the names of its options (``--help`` says each)."""

    #: where the certificate goes (None: MISSION.cert.json)
    output: Path | None = None
    #: re-check the certificate MISSION against this net instead of certifying
    net_file: Path | None = None
    net_id: str | None = None
    #: certify the mission started with mission.A marked too
    abort_pending: bool = False
    max_cert: str = CERTIFICATE_SIZE
    max_mission_size: str = MISSION_SIZE


@dataclass(frozen=True)
class CertifyOutcome:
    """The certificate, the net it is of, and what the independent checker finds wrong with
    the pair (nothing: it holds; exit status 1 otherwise)."""

    net: Net
    certificate: dict[str, Any]
    problems: tuple[str, ...]

    @property
    def status(self) -> int:
        return 1 if self.problems else 0

    def lines(self) -> list[str]:
        """What ``certify`` prints: what does not hold, or what the certificate proves."""
        if self.problems:
            return [f"{self.net.name}: the certificate does not hold:",
                    *(f"  {p}" for p in self.problems)]
        cert = self.certificate
        instances = sum(len(t) for t in cert.get("trees", {}).values())
        return [f"{self.net.name}: certified from its parts ({counted(instances, 'instance')}, "
                f"{counted(len(cert['tasks']), 'task')}, "
                f"{counted(len(cert['functions']), 'function')}): {', '.join(CERTIFIED)}; "
                "every end one of " + ", ".join(cert["conclusion"]["ends"])]

    def as_json(self) -> dict[str, Any]:
        return {"net": self.net.name, "holds": not self.problems,
                "problems": list(self.problems), "certificate": self.certificate}


def certify(mission: Path, options: CertifyOptions = CertifyOptions(), *,
            notes: Notes | None = None) -> CertifyOutcome:
    """``mcl2pnml certify`` with ``options``: the mission certified and its certificate
    written (only if it holds), or with ``net_file`` a certificate re-checked against that
    net."""
    o, notes = options, Notes() if notes is None else notes
    if o.net_file is not None:
        if o.output is not None:
            raise SettingError("output", "--check writes nothing")
        cert = pipeline.load_certificate(mission, o.max_cert)
        net = pipeline.load_net(o.net_file, o.net_id, max_mission_size=o.max_mission_size)
        return CertifyOutcome(net, cert, tuple(pipeline.check_certificate(net, cert,
                                                                          shaped=True)))
    if o.net_id is not None:
        raise SettingError("net_id", "only --check reads a net file")
    if mission.suffix != ".mcl":
        raise SettingError("mission", f"'{mission}' is not a mission (.mcl); to re-check a "
                                      "certificate, add --check NET.pnml")
    output = o.output or pipeline.certificate_beside(mission)
    check_outputs([("output", output)], [("the mission", mission)])
    cert, net, problems = pipeline.certify_file(mission, o.abort_pending, o.max_mission_size)
    if not problems:
        pipeline.save_certificate(cert, output)
        notes(f"wrote {output}")
    return CertifyOutcome(net, cert, tuple(problems))
