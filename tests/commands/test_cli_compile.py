"""`mcl2pnml compile`: MCL in, one composed net out, as cli.md says."""
from __future__ import annotations

import shutil

import pytest

from mcl2pnml.io.pnml import read_pnml

from helpers import DATA, ROOT, run_cli as run

SAUCE = ROOT / "examples" / "sauce.mcl"


def test_compile_writes_a_valid_pnml_of_the_mission(tmp_path, assert_valid):
    out = run("compile", SAUCE, "-o", tmp_path / "sauce.pnml")
    assert out.returncode == 0, out.stderr
    assert out.stderr.startswith(f"wrote {tmp_path / 'sauce.pnml'}: sauce: 203 places")
    data = (tmp_path / "sauce.pnml").read_bytes()
    assert_valid(data)
    net = read_pnml(tmp_path / "sauce.pnml")
    # cli.md: the mission's own interface places, mission.B and mission.MTX marked
    for p in ("B", "A", "MTX", "OK", "FAIL", "ABORTED"):
        assert f"mission.{p}" in net.place_index
    assert net.initial["mission.B"] == 1 and net.initial["mission.MTX"] == 1
    assert "AchieveDepth.MTX" in net.place_index   # instance-prefixed paper names
    assert b'<toolspecific tool="mcl2pnml"' in data


def test_default_output_is_next_to_the_mission(tmp_path):
    mission = tmp_path / "sauce.mcl"
    shutil.copy(SAUCE, mission)
    out = run("compile", mission)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "sauce.pnml").exists()


def test_dot_source_draws_one_call_at_a_time(tmp_path):
    """The mission's own net by default, each call it makes shut in a box named as MCL
    writes it; ``--expand`` draws the calls it names (by their names or, where one call
    alone has it, as MCL writes them), ``all`` the whole net."""
    out = run("compile", SAUCE, "--format", "dot", "-o", tmp_path / "sauce.dot")
    assert out.returncode == 0, out.stderr
    text = (tmp_path / "sauce.dot").read_text()
    assert text.startswith("digraph") and "subgraph cluster_mission " in text
    assert "class=box" in text and "AchieveDepth(SurfaceDepth)\nAchieveDepth-2" in text
    assert "AchieveDepth-1" not in text               # a call inside the if-then-else
    for call in ("AchieveDepth-1", "AchieveDepth(CrossDepth)"):
        out = run("compile", SAUCE, "--format", "dot", "--expand", call, "-o",
                  tmp_path / "call.dot")
        assert out.returncode == 0, out.stderr
        text = (tmp_path / "call.dot").read_text()
        assert "subgraph \"cluster_AchieveDepth-1\" " in text and "task AchieveDepth(d)" in text
    twice = run("compile", SAUCE, "--format", "dot", "--expand", "AchieveDepth(d)", "-o",
                tmp_path / "x.dot")
    assert twice.returncode == 2 and "no call 'AchieveDepth(d)'" in twice.stderr
    out = run("compile", SAUCE, "--format", "dot", "--expand", "all", "-o",
              tmp_path / "open.dot")
    assert out.returncode == 0, out.stderr
    text = (tmp_path / "open.dot").read_text()
    for instance in ("AchieveDepth", "Survey", "KeepDepth"):
        assert f"subgraph cluster_{instance} " in text


@pytest.mark.parametrize("fmt, magic", [("svg", b"<svg"), ("png", b"\x89PNG")])
def test_drawings(tmp_path, dot, fmt, magic):
    out = run("compile", SAUCE, "--format", fmt, "-o", tmp_path / f"sauce.{fmt}")
    assert out.returncode == 0, out.stderr
    assert magic in (tmp_path / f"sauce.{fmt}").read_bytes()[:1000]


@pytest.mark.parametrize("layout, graphics", [("none", False), ("layers", True), ("dot", True)])
def test_layout_choice(tmp_path, dot, assert_valid, layout, graphics):
    target = tmp_path / "m.pnml"
    out = run("compile", SAUCE, "--layout", layout, "-o", target)
    assert out.returncode == 0, out.stderr
    data = target.read_bytes()
    assert_valid(data)
    assert (b"<graphics>" in data) == graphics


@pytest.mark.parametrize("mission, where", [
    (DATA / "mcl" / "invalid" / "several_errors.mcl", "several_errors.mcl:6:5:"),
    (DATA / "mcl" / "invalid" / "too_deep.mcl", "too_deep.mcl:5:797:"),
    (DATA / "mcl" / "invalid" / "binary.mcl", "binary.mcl:1:"),
])
def test_bad_missions_exit_2_and_write_nothing(tmp_path, mission, where):
    target = tmp_path / "out.pnml"
    out = run("compile", mission, "-o", target)
    assert out.returncode == 2 and where in out.stderr and "^" in out.stderr
    assert "Traceback" not in out.stderr
    assert list(tmp_path.iterdir()) == []


def test_unwritable_output_is_one_message(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    out = run("compile", SAUCE, "-o", blocker / "sub" / "out.pnml")
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "cannot write" in out.stderr and len(out.stderr.strip().splitlines()) == 1


def test_bad_options(tmp_path):
    out = run("compile", SAUCE, "--format", "gif")
    assert out.returncode == 2 and "'gif' is not one of" in out.stderr
    out = run("compile", SAUCE, "--layout", "circo")
    assert out.returncode == 2 and "'circo' is not one of" in out.stderr


def test_outputs_get_the_permissions_of_a_plain_file(tmp_path):
    """Written through a private temporary file, an output still ends up as open() would
    make it (under the umask), or as the file it replaces was."""
    import os
    import stat

    umask = os.umask(0o022)
    try:
        out = run("compile", SAUCE, "-o", tmp_path / "sauce.pnml")
        assert out.returncode == 0, out.stderr
        assert stat.S_IMODE((tmp_path / "sauce.pnml").stat().st_mode) == 0o644
        (tmp_path / "sauce.pnml").chmod(0o640)
        assert run("compile", SAUCE, "-o", tmp_path / "sauce.pnml").returncode == 0
        assert stat.S_IMODE((tmp_path / "sauce.pnml").stat().st_mode) == 0o640
    finally:
        os.umask(umask)
