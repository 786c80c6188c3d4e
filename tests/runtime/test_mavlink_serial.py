"""A mission flown over a serial line: ``--connect serial:DEVICE:BAUD``, pyserial's.

The fake autopilot of tests/support/fake_autopilot.py speaks on a pseudo-terminal
(tests/support/pty_autopilot.py) and the command line connects to the terminal's
device as it would to a USB autopilot: the ``mavlink`` extra brings
pyserial, so that the run flies the mission to its outcome, with its safe
state, instead of failing for a missing module.
"""
from __future__ import annotations

import json
import re

import pytest

# no skip for pyserial: where the mavlink extra is installed (pymavlink), it is too
pytest.importorskip("pymavlink")

from fake_autopilot import ARM_DISARM, GUIDED, SET_MODE  # noqa: E402
from pty_autopilot import PtyAutopilot  # noqa: E402

from helpers import ROOT, run_cli  # noqa: E402

SAUCE = ROOT / "examples" / "sauce.mcl"


@pytest.mark.timeout(120)
def test_a_mission_flies_over_a_serial_line_to_its_outcome(tmp_path):
    log = tmp_path / "run.jsonl"
    with PtyAutopilot() as fake:
        assert fake.address.startswith("serial:/dev/")
        out = run_cli("run", SAUCE, "--vehicle", "mavlink", "--connect", fake.address,
                      "--liveness", "5", "--json", "--log", log, timeout=90)
        fake.check()
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["outcome"] == "OK"
    # flown as over TCP: GUIDED and armed, then the safe state, disarmed at the end
    assert int(fake.commanded(SET_MODE)[0][1]) == GUIDED
    assert [p[0] for p in fake.commanded(ARM_DISARM)] == [1, 0]
    assert fake.flown and not fake.armed
    assert log.exists()


def test_the_mavlink_extra_brings_pyserial():
    import tomllib
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"]
    assert any(re.match(r"pyserial\b", requirement) for requirement in extras["mavlink"])
    import serial  # noqa: F401  (installed with it: make setup installs the extra)
