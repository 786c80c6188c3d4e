"""A time the timed analysis cannot count is refused where it is written (docs/time.md).

A time-out finer than a microsecond is one message of the checker, at the constant's line
and column, whichever command reads the mission; a net read from a file with such a time
bound is refused by the timed analysis, naming the net, the transition and the value.
The golden messages of the checker are tests/data/mcl/invalid/timeout_finer_*.

An assumption on the vehicle past its bound (``--ack-within`` past ten minutes, the
autopilot bridge's own bound; ``--report-gap`` past a day) is one message naming the
option, the value and the limit.
"""
from __future__ import annotations

import json
from dataclasses import replace
from fractions import Fraction

import pytest

from mcl2pnml import pipeline
from mcl2pnml.core.bounds import MAX_ACK_WITHIN, MAX_REPORT_GAP
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import Net, Timing
from mcl2pnml.core.timing import (exact_seconds, finer_than_a_microsecond, mission_timing,
                                  seconds_setting)
from mcl2pnml.io.pnml.writer import write_pnml
from mcl2pnml.runtime import autopilot

from helpers import ROOT, run_cli

SAUCE = ROOT / "examples" / "sauce.mcl"

FINE = """primitive P();
task T() = AchieveGoal(P()) timeout 0.0000001;
mission { T(); }
"""
CARET = ("m.mcl:2:37: a timeout is a whole number of microseconds (0.000001 s), not 0.0000001\n"
         "    task T() = AchieveGoal(P()) timeout 0.0000001;\n"
         "                                        ^\n")


@pytest.mark.parametrize("command", [["check"], ["compile"], ["run"], ["analyze"],
                                     ["analyze", "--timed"], ["functional"]])
def test_every_command_refuses_a_time_out_finer_than_a_microsecond_at_its_place(
        tmp_path, command):
    mission = tmp_path / "m.mcl"
    mission.write_text(FINE)
    out = run_cli(*command, mission, cwd=tmp_path)
    assert (out.returncode, out.stdout) == (2, "")
    assert out.stderr.replace(str(mission), "m.mcl") == CARET
    assert not list(tmp_path.glob("m.*[!l]"))           # nothing written beside it


def test_the_last_microsecond_of_the_longest_time_out_is_one(tmp_path):
    # a double holds 999999999.999999 only to within a tenth of a microsecond: read back
    # as the decimal it was written as, it is whole microseconds for the checker and the
    # analysis alike
    assert not finer_than_a_microsecond(999999999.999999)
    assert exact_seconds(999999999.999999) * 10 ** 6 == 999999999999999
    assert finer_than_a_microsecond(1e-7) and finer_than_a_microsecond(0.1 + 1e-12)
    assert not finer_than_a_microsecond(0.1 + 0.2)        # 0.30000000000000004: 0.3
    net = pipeline.compile_source("primitive P();\n"
                                  "task T() = AchieveGoal(P()) timeout 999999999.999999;\n"
                                  "mission { T(); }\n")
    timed = mission_timing(net)
    assert timed.unit == exact_seconds(1e-6) and timed.intervals["T.t03"][0] == 10 ** 15 - 1


def _with_time_out(net: Net, seconds: float) -> Net:
    """``net`` with its time-out ``T.t03`` of ``seconds``, as a file may hold it."""
    timed = [replace(t, timing=Timing.delay(seconds)) if t.id == "T.t03" else t
             for t in net.transitions]
    return Net(net.name, net.places, timed, net.arcs, net.initial)


def test_a_net_read_from_a_file_with_a_finer_bound_names_it(tmp_path):
    net = pipeline.compile_source(FINE.replace("0.0000001", "3"), "m.mcl")
    fine = _with_time_out(net, 1e-7)
    with pytest.raises(Mcl2PnmlError) as refused:
        mission_timing(fine)
    expected = ("net 'm': the time-out of transition T.t03, 0.0000001 s, is finer than a "
                "microsecond, the finest time the timed analysis counts")
    assert refused.value.message == expected
    path = tmp_path / "m.pnml"
    write_pnml(net, path)
    # a file another tool wrote: this one's checker refuses such a time-out
    path.write_text(path.read_text().replace('earliest="3" latest="3"',
                                             'earliest="0.0000001" latest="0.0000001"'))
    out = run_cli("analyze", path, "--timed")
    assert (out.returncode, out.stdout, out.stderr) == (2, "", expected + "\n")
    assert "--time" not in out.stderr


# -- the bounds on the assumptions ---------------------------------------------------------

@pytest.mark.parametrize("args, message", [
    (["--ack-within", "1000000"], "Invalid value for --ack-within: '1000000' is not between 0 "
                                  "and 600 seconds (ten minutes: a vehicle slower to "
                                  "acknowledge has a broken link)"),
    (["--ack-within", "600.000001"], "--ack-within: '600.000001' is not between 0 and 600"),
    (["--report-gap", "86401"], "Invalid value for --report-gap: '86401' is not between 0 "
                                "and 86,400 seconds (a day)"),
    # read without building the power of ten (hours), or rounding it to 0
    (["--report-gap", "1e999999999"], "--report-gap: '1e999999999' is not between 0 and"),
    (["--ack-within", "1e-999999999"], "--ack-within: '1e-999999999' is finer than a "
                                       "microsecond"),
])
def test_an_assumption_past_its_bound_is_one_message(args, message):
    out = run_cli("analyze", SAUCE, "--timed", *args)
    assert (out.returncode, out.stdout) == (2, "")
    assert out.stderr.count("\n") == 1 and "Traceback" not in out.stderr
    assert message in out.stderr


def test_the_bounds_themselves_are_assumed(tmp_path):
    assert seconds_setting("600", "ack_within") == MAX_ACK_WITHIN
    assert seconds_setting("86400", "report_gap") == MAX_REPORT_GAP
    assert seconds_setting("0.000001", "report_gap") == Fraction(1, 10 ** 6)
    out = run_cli("compile", SAUCE, "--format", "tapn", "-o", tmp_path / "s.tapn",
                  "--ack-within", "601")
    assert out.returncode == 2 and "--ack-within: '601' is not between 0 and 600" in out.stderr


def test_the_autopilot_waits_for_an_acknowledgement_as_long_as_the_analysis_assumes():
    assert autopilot.SCHEMA["properties"]["ack_within"]["maximum"] == MAX_ACK_WITHIN


# -- times printed exactly -----------------------------------------------------------------

@pytest.mark.parametrize("timeouts, text, latest", [
    (["100000.5"], "100000.5", 100000.5), (["1000000000"], "1000000000", 1000000000),
    (["100000.5", "1000000000"], "1000100000.5", 1000100000.5),
    (["999999999.999999"], "999999999.999999", 999999999.999999),
])
def test_the_end_times_are_printed_exactly(tmp_path, timeouts, text, latest):
    mission = tmp_path / "long.mcl"
    tasks = "".join(f"task T{n}() = AchieveGoal(P()) timeout {t};\n"
                    for n, t in enumerate(timeouts))
    calls = " ".join(f"T{n}();" for n in range(len(timeouts)))
    mission.write_text(f"primitive P();\n{tasks}mission {{ {calls} }}\n")
    out = run_cli("analyze", mission, "--timed")
    assert out.returncode == 0, out.stderr
    assert f"  end time: earliest 0 s, latest {text} s (" in out.stdout
    timed = json.loads(run_cli("analyze", mission, "--timed", "--json").stdout)["timed"]
    assert (timed["earliest"], timed["latest"]) == (0, latest)
