"""Every command ends within its memory budget: a partial answer (exit 3) or one message
(exit 2), never a process the kernel kills.

The estimates each stage is judged by are checked on their own; the commands are run
in child processes on big generated nets (tests/support/bignets.py), and the child's peak
resident size is held to the budget plus what the interpreter takes on its own. The
million-place variants are slow and run under a hard limit of address space, so that a
regression fails the test instead of taking the machine's memory.
"""
from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys

import pytest

from bignets import write_lola, write_pnml
from mcl2pnml.analysis import report
from mcl2pnml.analysis.structure.invariants import AnalysisLimit
from mcl2pnml.analysis.structure.siphons import minimal_siphons
from mcl2pnml.analysis.zoo import cycle
from mcl2pnml.core import memory
from mcl2pnml.core.memory import (Budget, BudgetExceeded, check_load, guard, load_estimate,
                                  resident)
from mcl2pnml.core.structure import structure
from mcl2pnml.io.pnml.reader import read_pnml

MB = 1 << 20
#: What a child interpreter may hold beyond its budget: none is allowed where the
#: budget is above what the interpreter takes on its own (python, click, lxml,
#: sympy: 60 to 120 MB measured), so only a budget below that floor is exceeded.
FLOOR = 160 * MB


#: Starts the command from a small process and reports its peak: a child forked from
#: the test process would count the test process's own size (its pages before exec)
#: in its peak.
LAUNCH = """
import os, resource, sys
limit = int(sys.argv[1])
pid = os.fork()
if pid == 0:
    if limit:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    os.execv(sys.executable, [sys.executable, "-m", "mcl2pnml", *sys.argv[2:]])
_, status, usage = os.wait4(pid, 0)
sys.stderr.write(f"\\n@peak {usage.ru_maxrss} {os.waitstatus_to_exitcode(status)}\\n")
"""


def run_measured(*args, limit: int | None = None, timeout: float = 600):
    """``mcl2pnml ARGS`` in a child process: the completed process and the child's
    peak resident size in bytes (its own rusage, from wait4). ``limit``: a hard cap
    on its address space, so that a runaway child fails instead of taking the
    machine's memory; past ``timeout`` seconds it is killed (a negative status)."""
    launcher = subprocess.Popen([sys.executable, "-c", LAUNCH, str(limit or 0),
                                 *map(str, args)], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        out, err = launcher.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(launcher.pid, signal.SIGKILL)   # the command too: it is in that group
        raise
    err, _, report = err.rpartition("\n@peak ")
    peak, code = map(int, report.split())
    return subprocess.CompletedProcess(args, code, out, err.removesuffix("\n")), peak * 1024


# -- the estimates ---------------------------------------------------------------------------

@pytest.mark.timeout(60)
def test_the_read_estimate_counts_the_elements_of_the_file(tmp_path):
    small = write_pnml(tmp_path / "small.pnml", "ring", 1_000)
    big = write_pnml(tmp_path / "big.pnml", "ring", 10_000)
    need, what = load_estimate(small)
    assert what == "1,000 places, 1,000 transitions and 2,000 arcs"
    need_big, _ = load_estimate(big)
    assert 9 * need < need_big < 11 * need   # linear in the net
    # what reading takes is under the estimate (the reader's own peak, measured here)
    before = resident()
    net = read_pnml(big)
    assert len(net.places) == 10_000 and resident() - before < need_big
    words, what = load_estimate(write_lola(tmp_path / "n.lola", "ring", 1_000))
    assert "words" in what and 0 < words < need


@pytest.mark.timeout(60)
def test_a_file_past_the_budget_is_refused_before_it_is_read(tmp_path):
    path = write_pnml(tmp_path / "ring.pnml", "ring", 10_000)
    need, _ = load_estimate(path)
    with pytest.raises(BudgetExceeded) as e:
        check_load(path, Budget(resident() + need // 2))
    message = str(e.value)
    assert message.startswith(f"{path}: 10,000 places, 10,000 transitions and 20,000 arcs")
    assert "would need about" in message and "(--max-memory)" in message
    check_load(path, Budget(resident() + 2 * need))   # room enough: nothing said


def test_the_stage_estimates_grow_with_the_net():
    small, big = structure(cycle(100)), structure(cycle(1_000))
    assert report.structure_estimate(big.net) > 9 * report.structure_estimate(small.net)
    assert report.elimination_estimate(big) > 9 * report.elimination_estimate(small)
    assert report.farkas_rows(big, 100 * MB) < report.farkas_rows(big, 1_000 * MB)
    assert report.output_estimate([{"p1": 1, "p2": 1}] * 10) == \
        10 * report.output_estimate([{"p1": 1, "p2": 1}])


@pytest.mark.timeout(60)
def test_the_guard_stops_what_grows_and_lets_the_rest_run():
    before = signal.getsignal(signal.SIGINT)    # Python's own, or ignored under nohup
    budget = Budget(resident() + 100 * MB)
    held = []
    with pytest.raises(BudgetExceeded, match="growing stopped at the memory budget"):
        with guard(budget, "growing"):
            while True:
                try:
                    held.append(bytearray(1 << 16))
                except Exception:   # what a library's broad handler would do: no effect
                    pass
    assert len(held) * (1 << 16) >= 80 * MB
    held.clear()
    with guard(Budget(resident() + 500 * MB), "small"):
        total = sum(range(100_000))
    assert total == 4_999_950_000
    assert signal.getsignal(signal.SIGINT) is before       # the guard put it back


@pytest.mark.timeout(60)
@pytest.mark.parametrize("handler", [signal.SIG_IGN, signal.default_int_handler])
def test_a_ctrl_c_inside_a_guard_is_handled_as_before_it(handler):
    # a script's background job starts with SIGINT ignored: the guard's own handler must
    # not turn a Ctrl-C it was never meant to see into an interruption
    before = signal.signal(signal.SIGINT, handler)
    try:
        interrupted = False
        try:
            with guard(Budget(resident() + 500 * MB), "ctrl-c"):
                os.kill(os.getpid(), signal.SIGINT)
                for _ in range(1_000):   # backward jumps: where a pending handler runs
                    pass
        except KeyboardInterrupt:
            interrupted = True
        assert interrupted is (handler is signal.default_int_handler)
        assert signal.getsignal(signal.SIGINT) is handler
    finally:
        signal.signal(signal.SIGINT, before)


@pytest.mark.timeout(60)
def test_a_guard_entered_past_its_budget_stops_the_stage_and_says_so(monkeypatch):
    # the watcher trips on its first look, at once: the interruption lands while the
    # guard is still starting it, before the body (on a loaded machine, the first look
    # comes before the main thread is back from starting it); the stage ends in the message
    monkeypatch.setattr(memory, "POLL", 0.0)
    before = signal.getsignal(signal.SIGINT)
    for _ in range(200):
        with pytest.raises(BudgetExceeded, match="late stopped at the memory budget"):
            with guard(Budget(1024), "late"):
                while True:
                    pass
    assert signal.getsignal(signal.SIGINT) is before


@pytest.mark.timeout(60)
def test_the_siphon_enumeration_is_bounded_in_the_places_it_looks_at():
    s = structure(cycle(500))   # one minimal siphon of 500 places: about 500,000 steps
    with pytest.raises(AnalysisLimit, match="steps enumerating the minimal siphons"):
        minimal_siphons(s, work=50_000)
    assert [len(x) for x in minimal_siphons(s, work=5_000_000)] == [500]


def test_lists_that_would_not_print_within_the_budget_are_left_out_and_said():
    vectors = [{f"p{i}": 1, f"q{i}": -1} for i in range(20_000)]
    result = {"p_invariants": vectors, "siphons": [["p1"]], "t_invariants": []}
    limits, left_out = {}, {}
    report._fit_output(result, limits, left_out, Budget(resident() + MB))
    assert result["p_invariants"] is None and result["siphons"] == [["p1"]]
    assert left_out == {"p_invariants": limits["p_invariants"]}
    assert limits["p_invariants"].startswith("20,000 vectors, not printed: printing them "
                                             "would need about")
    assert "Partial answer: left out to stay within the memory budget: p invariants." in \
        report.render_text({"net": "n", "bounded": None, "safe": None, "states": None,
                            "terminal_markings": None, "p_invariants": None,
                            "partial": {"left_out": left_out}, "limits": limits})
    result = {"p_invariants": vectors}
    report._fit_output(result, limits, {}, Budget(resident() + 512 * MB))
    assert result["p_invariants"] is vectors   # room enough: all printed


# -- the commands, on 10^4 and 10^5 places -----------------------------------------------------

@pytest.fixture(scope="module")
def ring_100k(tmp_path_factory):
    return write_pnml(tmp_path_factory.mktemp("big") / "ring.pnml", "ring", 100_000)


@pytest.mark.timeout(120)
def test_analyze_refuses_a_net_its_budget_cannot_read(ring_100k):
    """The forgiving reading holds the file's tree: refused before a byte is parsed. The
    strict one streams (docs/pnml.md): the net is read within the budget, and the analysis
    refused before it starts. Either way nothing is printed, and the process stays under."""
    out, peak = run_measured("analyze", ring_100k, "--max-memory", "200M", "--json",
                             "--lenient")
    assert out.returncode == 2, out.stderr
    assert out.stderr.startswith(f"{ring_100k}: 100,000 places, 100,000 transitions and "
                                 "200,000 arcs to read would need about ")
    assert "the budget is 200.0 MB (--max-memory)" in out.stderr and not out.stdout
    assert peak < 200 * MB
    out, peak = run_measured("analyze", ring_100k, "--max-memory", "200M", "--json")
    assert out.returncode == 2, out.stderr
    assert out.stderr.startswith("net 'ring': 100,000 places, 100,000 transitions and "
                                 "200,000 arcs to analyse would need about ")
    assert "the budget is 200.0 MB (--max-memory)" in out.stderr and not out.stdout
    assert peak < 200 * MB


@pytest.mark.timeout(120)
@pytest.mark.parametrize("options", [["--json"], [], ["--state-space", "--json"]])
def test_analyze_past_its_budget_gives_a_partial_answer_within_it(tmp_path, options):
    """A ring of 10,000 places: its markings would take 800 MB; the answer says how many
    were explored within 150 MB, keeps the invariant basis, and the child stays under."""
    path = write_pnml(tmp_path / "ring.pnml", "ring", 10_000)
    out, peak = run_measured("analyze", path, "--max-memory", "150M", *options)
    assert out.returncode == 3, out.stderr
    assert peak < 150 * MB
    if "--json" not in options:
        assert "Partial answer: " in out.stdout and " markings explored;" in out.stdout
        assert "states: not computed (the exploration stopped at " in out.stdout
        return
    r = json.loads(out.stdout)
    assert r["partial"]["markings_explored"] > 0 and r["states"] is None
    assert "memory budget of 150.0 MB" in r["limits"]["states"]
    if "--state-space" not in options:
        assert r["p_invariants"] == [{f"p{i}": 1 for i in range(10_000)}]
        assert "steps enumerating the minimal siphons" in r["limits"]["siphons"]


@pytest.mark.timeout(120)
def test_compile_stops_at_its_budget_with_one_message_and_no_file(tmp_path):
    """A mission of 20,000 calls compiles to 360,000 places (870 MB): within 200 MB it
    is one message, exit 2, no output file, and the child stays under its budget."""
    mission = tmp_path / "calls.mcl"
    mission.write_text("primitive P(x);\ntask T(x) = AchieveGoal(P(x)) timeout 10;\nmission {\n"
                       + "".join(f"    T({i});\n" for i in range(20_000)) + "}\n")
    output = tmp_path / "calls.pnml"
    out, peak = run_measured("compile", mission, "-o", output, "--layout", "none",
                             "--max-memory", "200M")
    assert out.returncode == 2, out.stderr
    assert out.stderr == f"compiling {mission} stopped at the memory budget of 200.0 MB"
    assert not output.exists() and not list(tmp_path.glob(".calls.pnml*"))
    assert peak < 200 * MB


# -- a million places: every command, under a hard cap ------------------------------------------

#: The address space each child may take at most: a command that read the million-place
#: nets (1.6 to 8 GB each) would fail here, not take the machine's memory; the default
#: budget, half of it, is below what reading the smallest would need.
CAP = 2 << 30


@pytest.fixture(scope="module", params=["ring", "components", "siphons", "dense"])
def million(request, tmp_path_factory):
    return write_pnml(tmp_path_factory.mktemp("million") / f"{request.param}.pnml",
                      request.param, 1_000_000)


@pytest.mark.slow
@pytest.mark.timeout(900)
@pytest.mark.parametrize("command", [
    ["analyze", "{net}"], ["analyze", "{net}", "--json"],
    ["analyze", "{net}", "--state-space", "--max-memory", "1G"],
    ["validate", "{net}"], ["show", "{net}", "-o", "{tmp}/page.html"],
    ["run", "{net}", "--vehicle", "sim"]])
def test_a_million_places_are_refused_by_every_command_before_reading(million, tmp_path,
                                                                      command):
    """The default budget is half of what the process may take (here its address-space
    cap): the file is refused before it is read, naming what it holds and the budget."""
    args = [a.format(net=million, tmp=tmp_path) for a in command]
    out, peak = run_measured(*args, limit=CAP)
    assert out.returncode == 2, out.stderr[-2000:]
    assert out.stderr.startswith(f"{million}: ") and "to read would need about" in out.stderr
    assert "the budget is " in out.stderr and not (tmp_path / "page.html").exists()
    assert peak < CAP // 2


@pytest.mark.slow
@pytest.mark.timeout(1800)
@pytest.mark.parametrize("shape, budget", [("ring", 1500), ("components", 1500),
                                           ("siphons", 1500), ("dense", 800)])
def test_every_shape_of_a_hundred_thousand_places_ends_within_its_budget(tmp_path, shape,
                                                                         budget):
    """Read, then each stage within its budget: what does not fit is left out and said.
    (The dense net's elimination fills in slowly: a smaller budget stops it sooner.)"""
    path = write_pnml(tmp_path / f"{shape}.pnml", shape, 100_000)
    out, peak = run_measured("analyze", path, "--json", "--max-memory", f"{budget}M",
                             limit=6 << 30, timeout=1700)
    assert out.returncode in (0, 3), out.stderr[-2000:]
    assert peak < budget * MB
    r = json.loads(out.stdout)
    assert r["places"] in (99_999, 100_000)
    assert (out.returncode == 3) == ("partial" in r)


@pytest.mark.parametrize("given", [1, 1 << 20, 90 << 20, 4 << 30])
def test_a_budget_below_the_process_stops_a_stage_only_once_it_has_grown(given):
    """A structural stage under a budget smaller than the process runs under one raised
    past what the process holds: its guard trips only after the stage has grown by
    SLACK, never at its first look (which made a small stage's result depend on how long
    it took on a loaded machine)."""
    budget = Budget(given)
    floored = memory.floored(budget)
    trip = floored.limit - memory.margin(floored.limit)
    assert trip >= memory.resident() + memory.SLACK or floored is budget
    if floored is budget:       # a budget that already leaves that room is kept
        assert budget.limit - memory.margin(budget.limit) >= memory.resident() + memory.SLACK
    else:
        assert floored.given == budget.given
