"""Hostile offline inputs: each is one clear message and exit status 2, never a traceback,
a hang, a destroyed input or a file left behind (docs/faults.md, "Bad offline inputs").

A journal edited by hand, a FIFO where a file is expected, two resumes of one
journal at once, an output that is an input, a finished run resumed, a write
killed outright, a world that would never end, a chain of thousands of
functions, numbers past what the readers can hold, and graphviz missing.
The messages of the invalid files are golden, under tests/data (``journal/``,
``world/``, and beside the others in ``mcl/``, ``formats/``, ``pnml/``).
"""
from __future__ import annotations

import json
import os
import re
import signal

import pytest

import forkcli
from helpers import DATA, ROOT, assert_error_golden, cli, one_error, run_cli
from mcl2pnml.core.errors import Mcl2PnmlError

SAUCE = ROOT / "examples" / "sauce.mcl"
FOUND = {"GoToWayPoint": ["ok@30", "ok@40"], "DetectCross": ["ok@50"],
         "KeepDepth": ["ok@5", "ok@6"], "ReleaseMarker": ["ok@1"]}
JOURNALS = sorted((DATA / "journal" / "invalid").glob("*.journal"))
WORLDS = sorted((DATA / "world" / "invalid").glob("*.json"))
TOO_LARGE = [DATA / "mcl" / "invalid" / "huge_timeout.mcl",
             DATA / "mcl" / "invalid" / "infinite_timeout.mcl",
             DATA / "mcl" / "invalid" / "timeout_too_long.mcl",
             DATA / "formats" / "invalid" / "huge_marking.net",
             DATA / "formats" / "invalid" / "huge_weight.net",
             DATA / "formats" / "invalid" / "huge_interval.net",
             DATA / "formats" / "invalid" / "huge_tokens.lola",
             DATA / "formats" / "invalid" / "huge_consume.lola",
             DATA / "pnml" / "invalid" / "huge_marking.pnml",
             DATA / "pnml" / "invalid" / "huge_weight.pnml",
             DATA / "pnml" / "invalid" / "timing_too_long.pnml",
             DATA / "pnml" / "invalid" / "payload_too_deep.pnml"]


@pytest.fixture
def script(tmp_path):
    path = tmp_path / "vehicle.json"
    path.write_text(json.dumps(FOUND))
    return path


def killed_journal(tmp_path, script, lines: int = 10):
    """A journal of a run of sauce killed after ``lines`` lines: one to resume."""
    journal = tmp_path / "run.journal"
    env = {**os.environ, "MCL2PNML_JOURNAL_KILL_AFTER": str(lines)}
    out = run_cli("run", SAUCE, "--vehicle", script, "--journal", journal, env=env, timeout=60)
    assert out.returncode == -signal.SIGKILL, out.stderr
    return journal


# -- 1. a journal's header, checked field by field ------------------------------------------

@pytest.mark.timeout(30)
@pytest.mark.parametrize("path", JOURNALS, ids=lambda p: p.stem)
def test_a_bad_journal_is_one_located_message(path, monkeypatch):
    from mcl2pnml.runtime.journal import load
    before = path.read_bytes()
    monkeypatch.chdir(path.parent)
    with pytest.raises(Mcl2PnmlError) as info:
        load(path.name)
    assert_error_golden(path, info.value)
    assert path.read_bytes() == before


HEADER = {"journal": 1, "mission": "sauce.mcl", "engine": "petri", "vehicle": "vehicle.json",
          "world": None, "max_time": 86400.0, "mission_sha256": "0" * 64,
          "vehicle_sha256": "1" * 64}
HOSTILE = [None, True, 0, -1, 1.5, 1e308, "", "x", "sim", "bridge:m.json", [], {}, [1, 2],
           {"a": 1}, "f" * 64]


def _load_header(path, header) -> None:
    from mcl2pnml.runtime.journal import load
    path.write_text(json.dumps(header) + "\n")
    try:
        loaded = load(path)
    except Mcl2PnmlError as e:
        assert str(e).startswith(f"{path}:1:"), str(e)
    else:       # a header that happens to be valid: its fields are what a resume takes
        os.close(loaded.fd)
        assert loaded.header["engine"] in ("petri", "reference")
        assert isinstance(loaded.header["max_time"], (int, float))


@pytest.mark.timeout(60)
def test_every_field_of_a_header_with_every_hostile_value_is_our_error(tmp_path):
    path = tmp_path / "run.journal"
    for key in HEADER:
        for value in HOSTILE:
            _load_header(path, {**HEADER, key: value})
        _load_header(path, {k: v for k, v in HEADER.items() if k != key})


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_random_headers_are_our_error(tmp_path):
    import random
    rng = random.Random(7)
    path = tmp_path / "run.journal"
    for _ in range(5000):
        header = dict(HEADER)
        for key in rng.sample(sorted(HEADER), rng.randint(1, 4)):
            if rng.random() < 0.2:
                header.pop(key)
            else:
                header[key] = rng.choice(HOSTILE)
        _load_header(path, header)


@pytest.mark.timeout(60)
def test_a_tampered_header_through_the_cli(tmp_path, script):
    journal = killed_journal(tmp_path, script)
    header, rest = journal.read_text().split("\n", 1)
    journal.write_text(json.dumps({**json.loads(header), "engine": "fast"}) + "\n" + rest)
    before = journal.read_bytes()
    out = run_cli("run", SAUCE, "--resume", journal, timeout=60)
    one_error(out, f"{journal}:1:", "unknown engine 'fast'; valid: petri, reference")
    assert journal.read_bytes() == before


# -- 2. only regular files are read ----------------------------------------------------------

@pytest.mark.timeout(60)
def test_resume_of_a_fifo_is_refused_not_waited_on(tmp_path):
    fifo = tmp_path / "run.journal"
    os.mkfifo(fifo)
    out = run_cli("run", SAUCE, "--resume", fifo, timeout=30)
    one_error(out, f"{fifo}: cannot read the journal: this is a FIFO")


def _fifo_cases(tmp_path, script):
    fifos = {}
    for name in ("m.mcl", "n.pnml", "n.net", "n.lola", "world.json", "script.json",
                 "log.jsonl", "map.json"):
        fifos[name] = tmp_path / name
        os.mkfifo(fifos[name])
    return fifos, [
        (("check", fifos["m.mcl"]), "m.mcl: cannot read: this is a FIFO"),
        (("functional", fifos["m.mcl"]), "m.mcl: cannot read: this is a FIFO"),
        (("analyze", fifos["n.pnml"]), "n.pnml: cannot read: this is a FIFO"),
        (("validate", fifos["n.pnml"]), "n.pnml: cannot read: this is a FIFO"),
        (("analyze", fifos["n.net"]), "n.net: cannot read: this is a FIFO"),
        (("analyze", fifos["n.lola"]), "n.lola: cannot read: this is a FIFO"),
        (("run", SAUCE, "--world", fifos["world.json"]),
         "world.json: cannot read the world file: this is a FIFO"),
        (("run", SAUCE, "--vehicle", fifos["script.json"]),
         "script.json: cannot read the vehicle script: this is a FIFO"),
        (("show", SAUCE, "--run", fifos["log.jsonl"], "-o", tmp_path / "page.html"),
         "log.jsonl: cannot read the run log: this is a FIFO"),
        (("run", SAUCE, "--vehicle", f"bridge:{fifos['map.json']}", "--connect", "localhost:9"),
         "map.json: cannot read the mapping file: this is a FIFO"),
        (("check", "/dev/null"), "/dev/null: cannot read: this is a character device"),
    ]


@pytest.mark.timeout(60)
def test_every_input_refuses_what_is_not_a_regular_file(tmp_path, script):
    fifos, cases = _fifo_cases(tmp_path, script)
    for args, message in cases:
        one_error(cli(*args), message)
    assert not (tmp_path / "page.html").exists()


# -- 3. one run at a time on a journal --------------------------------------------------------

@pytest.mark.timeout(60)
def test_a_second_resume_of_a_journal_in_use_is_refused(tmp_path, script):
    from mcl2pnml.runtime import journal as journals
    journal = killed_journal(tmp_path, script)
    before = journal.read_bytes()
    held = journals.load(journal)       # the first resume, still running
    try:
        out = run_cli("run", SAUCE, "--resume", journal, timeout=60)
        one_error(out, f"{journal}: the journal is in use by another run")
        assert journal.read_bytes() == before
    finally:
        os.close(held.fd)
    out = run_cli("run", SAUCE, "--resume", journal, "--json", timeout=60)
    assert out.returncode == 0, out.stderr     # free again once the first has ended


@pytest.mark.timeout(60)
def test_a_new_journal_is_locked_from_its_creation(tmp_path):
    from mcl2pnml.runtime import journal as journals
    path = tmp_path / "new.journal"
    writer = journals.create(path, {"mission": "sauce.mcl", "engine": "petri",
                                    "vehicle": "sim", "world": None, "max_time": 10.0,
                                    "mission_sha256": "0" * 64})
    try:
        with pytest.raises(Mcl2PnmlError, match="the journal is in use by another run"):
            journals.load(path)
    finally:
        writer.close()


# -- 4. no output is an input, nor another output --------------------------------------------

@pytest.mark.timeout(60)
def test_an_output_that_is_an_input_is_refused(tmp_path, script, monkeypatch):
    mission = tmp_path / "s.mcl"
    mission.write_bytes(SAUCE.read_bytes())
    os.link(mission, tmp_path / "hard.pnml")
    os.symlink(mission, tmp_path / "soft.pnml")
    run_log = tmp_path / "run.jsonl"
    run_log.write_text("")
    journal = killed_journal(tmp_path, script)
    kept = {p: p.read_bytes() for p in (mission, script, journal, run_log)}
    monkeypatch.chdir(tmp_path)     # files named as a user in that directory would
    cases = [
        (("compile", "s.mcl", "-o", "s.mcl"), "-o: 's.mcl' is the mission"),
        (("compile", "s.mcl", "-o", "hard.pnml"), "-o: 'hard.pnml' is the mission"),
        (("compile", "s.mcl", "-o", "soft.pnml"), "-o: 'soft.pnml' is the mission"),
        (("compile", "s.mcl", "-o", "x/../s.mcl"), "-o: 'x/../s.mcl' is the mission"),
        (("compile", "s.mcl", "-o", tmp_path / "s.mcl"), "is the mission"),
        (("run", "s.mcl", "--vehicle", "vehicle.json", "--journal", "j", "--log", "./j"),
         "--log: 'j' is also the file of --journal"),
        (("run", "s.mcl", "--vehicle", "vehicle.json", "--log", "vehicle.json"),
         "--log: 'vehicle.json' is the vehicle script (--vehicle)"),
        (("run", "s.mcl", "--vehicle", "vehicle.json", "--log", "s.mcl"),
         "--log: 's.mcl' is the mission"),
        (("run", "s.mcl", "--vehicle", "vehicle.json", "--journal", "s.mcl"),
         "--journal: 's.mcl' is the mission"),
        (("run", SAUCE, "--resume", "run.journal", "--log", "run.journal"),
         "--log: 'run.journal' is the journal it resumes (--resume)"),
        (("show", "s.mcl", "-o", "s.mcl"), "-o: 's.mcl' is the net or mission"),
        (("show", "s.mcl", "--run", "run.jsonl", "-o", "run.jsonl"),
         "-o: 'run.jsonl' is the run log (--run)"),
    ]
    for args, message in cases:
        assert "Invalid value for" in one_error(cli(*args), message)
    for path, data in kept.items():
        assert path.read_bytes() == data, path
    assert not (tmp_path / "j").exists()


# -- 5. a finished run is not resumed ---------------------------------------------------------

@pytest.mark.timeout(60)
def test_resuming_a_finished_run_says_so(tmp_path, script):
    journal = tmp_path / "done.journal"
    out = cli("run", SAUCE, "--vehicle", script, "--journal", journal, "--json")
    assert out.exit_code == 0, out.output
    before = journal.read_bytes()
    time = json.loads(out.output.strip().splitlines()[-1])["time"]
    out = cli("run", SAUCE, "--resume", journal)
    one_error(out, f"{journal}: this run has ended (OK at t={time:g} s", "nothing to resume")
    assert journal.read_bytes() == before


# -- 6. a write killed outright leaves a temporary that the next write removes ----------------

TEMPORARY = re.compile(r"\.sauce\.pnml\.mcl2pnml-(\d+)-[a-z0-9_]+\.tmp")


@pytest.mark.timeout(60)
def test_a_killed_write_leaves_a_temporary_the_next_write_removes(tmp_path):
    target = tmp_path / "sauce.pnml"
    env = {**os.environ, "MCL2PNML_WRITE_KILL": "1"}
    out = run_cli("compile", SAUCE, "--layout", "none", "-o", target, env=env, timeout=60)
    assert out.returncode == -signal.SIGKILL, out.stderr
    left = [p for p in tmp_path.iterdir() if TEMPORARY.fullmatch(p.name)]
    assert len(left) == 1 and not target.exists()
    assert left[0].stat().st_size > 10_000     # the whole net, never moved into place
    # what is not ours, or not dead, stays: another name, a live process's temporary
    strangers = [tmp_path / ".sauce.pnml.other-1-abc.tmp",
                 tmp_path / f".sauce.pnml.mcl2pnml-{os.getpid()}-abc.tmp",
                 tmp_path / f".other.pnml.mcl2pnml-{left[0].name.split('-')[1]}-abc.tmp"]
    for p in strangers:
        p.write_text("not yours")
    out = run_cli("compile", SAUCE, "--layout", "none", "-o", target, timeout=60)
    assert out.returncode == 0, out.stderr
    assert not left[0].exists()
    assert all(p.exists() for p in strangers)
    from mcl2pnml.io.pnml.reader import read_pnml
    assert len(read_pnml(target).places) > 0


# -- 7. world files ---------------------------------------------------------------------------

@pytest.mark.timeout(30)
@pytest.mark.parametrize("path", WORLDS, ids=lambda p: p.stem)
def test_a_bad_world_is_one_located_message(path, monkeypatch):
    from mcl2pnml.runtime.simulator import World
    monkeypatch.chdir(path.parent)
    with pytest.raises(Mcl2PnmlError) as info:
        World.load(path.name)
    assert_error_golden(path, info.value)


@pytest.mark.timeout(60)
def test_every_world_field_with_every_hostile_value_is_our_error():
    from mcl2pnml.runtime.simulator import MAX_DT, MIN_DT, World
    values = [*HOSTILE, 1e-9, 0.5, 1e400, -1e400, [0, 0, 0], [1, 1], [1e400, 1, 1],
              [True, 1, 1], ["1", 1, 1], [3, 3, 3, 3]]
    for key in World.__dataclass_fields__:
        for value in values:
            text = json.dumps({key: value})
            try:
                world = World.from_json(text, "w.json")
            except Mcl2PnmlError as e:
                assert str(e).startswith("w.json:"), str(e)
                assert f'"{key}"' in str(e) or "default start" in str(e), str(e)
            else:
                assert MIN_DT <= world.dt <= MAX_DT and all(v > 0 for v in world.tank)


@pytest.mark.timeout(60)
def test_a_world_whose_step_is_zero_is_refused_not_run_for_ever(tmp_path):
    world = tmp_path / "world.json"
    world.write_text('{"dt": 0}\n')
    out = run_cli("run", SAUCE, "--world", world, timeout=30)
    one_error(out, f"{world}:1:8:", '"dt" is the time step in seconds', "from 0.01 to 10")


def test_a_good_world_still_runs():
    from mcl2pnml.runtime.simulator import World
    world = World.from_json('{"tank": [20, 10, 6], "start": [1, 1, 0], "cross": null, '
                            '"start_yaw": 90, "dt": 0.05, "seed": null}')
    assert world.tank == (20.0, 10.0, 6.0) and world.cross is None and world.seed is None
    assert abs(world.start_yaw - 3.141592653589793 / 2) < 1e-12


# -- 8. deep chains of calls ------------------------------------------------------------------

def chain(n: int) -> str:
    """A mission whose functions F0 ... F(n-1) each call the next; the last calls a task."""
    lines = ["primitive P();", "task T() = AchieveGoal(P());"]
    lines += [f"function F{i}() {{ F{i + 1}(); }}" for i in range(n - 1)]
    lines += [f"function F{n - 1}() {{ T(); }}", "mission { F0(); }"]
    return "\n".join(lines) + "\n"


@pytest.mark.timeout(60)
@pytest.mark.parametrize("n", [1000, pytest.param(5000, marks=pytest.mark.slow)])
def test_a_deep_chain_of_functions_checks_compiles_and_runs(tmp_path, n):
    from mcl2pnml import pipeline
    mission = tmp_path / f"chain{n}.mcl"
    mission.write_text(chain(n))
    out = cli("check", mission)
    assert out.exit_code == 0 and f"{n:,} functions" in out.output, out.output
    checked = pipeline.check_file(mission)
    assert checked.function_order[0] == f"F{n - 1}" and checked.function_order[-1] == "F0"
    lines = pipeline.functional_form(checked, functions=True)
    assert lines[-1] == "F0()" and len(lines) == n + 1
    net = pipeline.compile_checked(checked)
    assert net.initial["mission.B"] == 1
    script = tmp_path / "vehicle.json"
    script.write_text('{"P": ["ok@1"]}')
    for engine in ("petri", "reference"):
        result = pipeline.run_mission(mission, pipeline.RunOptions(engine=engine,
                                                                   vehicle=str(script)))
        assert result.outcome.value == "OK" and result.time == 1, engine


def test_recursion_in_a_long_chain_is_still_found(tmp_path):
    from mcl2pnml import pipeline
    text = chain(2000).replace("function F1999() { T(); }", "function F1999() { F3(); }")
    with pytest.raises(Mcl2PnmlError, match=r"recursion: F3 calls F4 calls .* calls F3"):
        pipeline.check_source(text, "loop.mcl")


def test_a_long_chain_of_consts_resolves_and_a_cycle_in_it_is_found():
    from mcl2pnml import pipeline
    n = 5000
    consts = [f"const C{i} = C{i + 1};" for i in range(n - 1)] + [f"const C{n - 1} = (1, 2);"]
    text = "\n".join(["primitive P(x);", *consts, "task T() = AchieveGoal(P(C0));",
                      "mission { T(); }"]) + "\n"
    checked = pipeline.check_source(text, "consts.mcl")
    assert checked.consts["C0"] == (1, 2) and len(checked.consts) == n
    looped = text.replace(f"const C{n - 1} = (1, 2);", f"const C{n - 1} = (1, C7);")
    with pytest.raises(Mcl2PnmlError, match=r"const 'C7' is defined in terms of itself: "
                                            r"C7 -> C8 -> .* -> C4999 -> C7"):
        pipeline.check_source(looped, "consts.mcl")


# -- 9, 10. numbers past what the readers hold ------------------------------------------------

@pytest.mark.timeout(60)
@pytest.mark.parametrize("path", TOO_LARGE, ids=lambda p: p.name)
def test_numbers_too_large_are_one_located_message(path):
    command = "check" if path.suffix == ".mcl" else "analyze"
    text = one_error(cli(command, path), f"{path}:")
    assert re.search(r"too large|too long|too deeply|at most|go up to", text.splitlines()[0]), \
        text
    assert "^" in text      # the line, and a caret under the number


@pytest.mark.timeout(60)
def test_json_inputs_with_a_number_past_the_digit_limit_are_one_message(tmp_path):
    big = "9" * 5000
    script = tmp_path / "script.json"
    script.write_text('{"GoToWayPoint": ["ok@1"], "x": ' + big + "}")
    mapping = tmp_path / "map.json"
    mapping.write_text('{"primitives": ' + big + "}")
    one_error(cli("run", SAUCE, "--vehicle", script),
              f"{script}: not a vehicle script: a number of more than 4,300 digits")
    one_error(cli("run", SAUCE, "--vehicle", f"bridge:{mapping}", "--connect", "localhost:9"),
              f"{mapping}: not a mapping file: a number of more than 4,300 digits")
    one_error(cli("analyze", SAUCE, "--initial", f"mission.B*{big}"),
              "--initial", "a place holds at most 2^63-1")
    one_error(cli("analyze", SAUCE, "--initial", f"mission.B*{2 ** 63 - 1},mission.B"),
              "--initial", "too many tokens")


@pytest.mark.timeout(60)
def test_an_infinite_timeout_is_refused_by_check_before_any_engine_sees_it():
    path = DATA / "mcl" / "invalid" / "infinite_timeout.mcl"
    for command in (("check",), ("compile", "-o", os.devnull), ("functional",)):
        one_error(cli(command[0], path, *command[1:]), f"{path}:3:37: 1e309 is too large")


# -- 11. graphviz missing ---------------------------------------------------------------------

@pytest.mark.timeout(60)
def test_a_missing_dot_is_one_message_saying_how_to_get_it(tmp_path):
    empty = tmp_path / "bin"
    empty.mkdir()
    env = {**os.environ, "PATH": str(empty)}
    out = run_cli("compile", SAUCE, "--layout", "dot", "-o", tmp_path / "s.pnml", env=env,
                  timeout=60)
    one_error(out, "--layout", "graphviz's 'dot' program is not installed",
              "apt-get install graphviz", "layers and none work without it")
    out = run_cli("compile", SAUCE, "--format", "svg", "-o", tmp_path / "s.svg", env=env,
                  timeout=60)
    one_error(out, "--format", "graphviz's 'dot' program is not installed",
              "pnml, tina, lola and dot (the source) work without it")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bin"]


# -- a file broken everywhere: a screenful and a count ---------------------------------------

def _broken_everywhere(tmp_path):
    arcs = "".join(f'<arc id="a{i}" source="nowhere{i}" target="p"/>' for i in range(200))
    net = tmp_path / "broken.pnml"
    net.write_text('<?xml version="1.0"?><pnml xmlns="http://www.pnml.org/version-2009/grammar/'
                   'pnml"><net id="n" type="http://www.pnml.org/version-2009/grammar/ptnet">'
                   f'<page id="g"><place id="p"/>{arcs}</page></net></pnml>')
    return net


def _a_screenful_and_a_count(net, *command: str) -> None:
    from mcl2pnml.core.errors import SHOWN_ERRORS
    out = run_cli(*command, net)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    lines = out.stderr.splitlines()
    located = [line for line in lines if line.startswith(f"{net}:")]
    assert len(located) <= SHOWN_ERRORS + 1, (command, len(located))
    assert any(re.fullmatch(r"\.\.\. and [\d,]+ more errors \(the first 50 are shown\)",
                            line) for line in lines), (command, lines[-3:])


def test_a_file_broken_everywhere_read_leniently_shows_its_first_errors_and_how_many_more(
        tmp_path):
    _a_screenful_and_a_count(_broken_everywhere(tmp_path), "analyze", "--lenient")


def test_a_file_broken_everywhere_shows_its_first_errors_and_how_many_more(tmp_path):
    net = _broken_everywhere(tmp_path)
    for command in ("analyze", "validate"):
        _a_screenful_and_a_count(net, command)


# -- what an error quotes of its input is never printed raw ---------------------------------

#: Bytes that act on a terminal or change how text reads, as UTF-8: the C0 controls but the
#: newline, DEL, the C1 controls, the bidirectional overrides and isolates.
RAW = re.compile(rb"[\x00-\x09\x0b-\x1f\x7f]|\xc2[\x80-\x9f]|\xe2\x80[\xaa-\xae]|"
                 rb"\xe2\x81[\xa6-\xa9]")
TITLE = "\x1b]0;PWNED\x07"        # sets the terminal's title when printed


def stderr_bytes(*args, cwd=None) -> bytes:
    """``mcl2pnml ARGS``'s exit status and standard error, byte for byte (no decoding, no
    newline translation: a carriage return must show), from a process of its own forked
    from the command server (a fresh interpreter's imports, 0.4 s a command, prove nothing
    here: the streams are opened as a fresh interpreter opens them)."""
    out = forkcli.run(args, cwd=cwd, timeout=120, text=False)
    assert out.returncode == 2 and b"Traceback" not in out.stderr, out.stderr
    return out.stderr


@pytest.mark.timeout(120)
def test_an_error_never_prints_the_control_characters_of_its_input(tmp_path):
    mission = tmp_path / "title.mcl"
    mission.write_text("primitive P(x);\n"
                       f'task T() = AchieveGoal(Q("{TITLE}\\u\x1b[2J")) timeout 5;\n'
                       "mission { T(); }\n")
    named = tmp_path / f"m{TITLE}\r\u202e.mcl"     # the file's name quoted too
    named.write_text(f"primitive P(x);\ntask T{TITLE}\u2066\x85\x7f() = AchieveGoal(P(1));\n")
    mapping = tmp_path / "map.json"
    mapping.write_text('{"primitives": {"K\\u001b]0;T\\u0007": {"by": "servo"}},\n'
                       f' "autopilot": "{TITLE}"}}\n')
    cases = [("check", mission), ("check", named),
             ("run", SAUCE, "--vehicle", f"mavlink:{mapping}", "--connect", "tcp:127.0.0.1:1")]
    for args in cases:
        err = stderr_bytes(*args)
        assert not RAW.search(err), (args, err)
        assert rb"\x1b" in err, (args, err)    # shown, as an escape
    # the caret stays under the character it points at, after the escapes before it
    err = stderr_bytes("check", named).decode()
    line, caret = err.splitlines()[1:3]
    assert line[caret.index("^"):].startswith(r"\x1b]0;"), err
    # nor does a command that succeeds, naming its input
    good = tmp_path / f"good{TITLE}.mcl"
    good.write_bytes(SAUCE.read_bytes())
    out = forkcli.run(["check", good], timeout=120, text=False)
    assert out.returncode == 0 and not RAW.search(out.stdout + out.stderr), out


@pytest.mark.parametrize("char, shown", [
    ("\x1b", r"\x1b"), ("\x07", r"\x07"), ("\r", r"\r"), ("\x7f", r"\x7f"), ("\x85", r"\x85"),
    ("\u202e", r"\u202e"), ("\u2069", r"\u2069"), ("\x00", r"\x00"), ("\u2028", r"\u2028")])
def test_an_excerpt_escapes_each_control_and_keeps_its_caret(char, shown):
    from mcl2pnml.core.errors import Location
    for column in (1, 3, 4, 6):     # before, on and after the control character
        source = f"ab{char}cd{char}e"
        excerpt = Location("f", 1, column, source).excerpt()
        line, caret = (text[4:] for text in excerpt.split("\n"))
        assert line == f"ab{shown}cd{shown}e" and line.isprintable()
        # the caret under the start of what column points at, escaped or not
        target = source[column - 1]
        assert line[caret.index("^"):].startswith(shown if target == char else target)


@pytest.mark.timeout(60)
def test_an_output_on_a_fifo_is_written_into_never_replaced(tmp_path):
    import threading
    fifo = tmp_path / "out.pnml"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()), daemon=True)
    reader.start()
    out = run_cli("compile", SAUCE, "-o", fifo, timeout=60)
    reader.join(30)
    assert out.returncode == 0, out.stderr
    assert os.path.exists(fifo) and not os.path.isfile(fifo)    # still the FIFO
    assert got and got[0].startswith(b"<?xml")


def test_a_string_with_escapes_keeps_its_other_characters():
    from mcl2pnml.language.parser import parse
    program = parse('primitive Say(t);\ntask S() = AchieveGoal(Say("caf\u00e9\\n\\u00e9 \u202e'
                    '\\x1b")) timeout 5;\nmission { S(); }\n')
    (string,) = program.declarations[1].primitives[0].args
    assert string.value == "caf\u00e9\n\u00e9 \u202e\x1b"


@pytest.mark.timeout(60)
def test_an_excerpt_of_a_line_of_megabytes_escapes_only_its_window():
    from mcl2pnml.core.errors import EXCERPT_WIDTH, Location
    line = "\x1b" * 8_000_000 + "X" + "\x07" * 8_000_000     # escaped whole: 100 MB of text
    excerpt = Location("f", 1, 8_000_001, line).excerpt()
    text, caret = (part[4:] for part in excerpt.split("\n"))
    assert text.startswith("...") and text.endswith("...") and text.isprintable()
    assert len(text) <= EXCERPT_WIDTH + 6 and text[caret.index("^")] == "X"
