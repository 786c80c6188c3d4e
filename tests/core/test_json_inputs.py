"""Every JSON input cut short is one located message and exit status 2, never a traceback.

The JSON files a command reads (an autopilot mapping, a world, a fault file,
a certificate, a vehicle model, a vehicle script, a bridge's mapping), each
a good one of the package cut at an offset: the reader raises our error,
naming the file, a line and a column, and renders its excerpt (the property
on random offsets here, on every offset under the ``slow`` marker). Through
the command line, each command that reads one gives exit status 2 for it,
also ``run``, where 1 would mean FAIL, and ``certify --check``, where 1
would mean "does not hold"; a file cut after a newline (the error past the
last line) among them. A key given twice is refused where it is given
again, and a file over its size bound before it is read.
"""
from __future__ import annotations

import functools
import json
import re
import shutil
import tempfile
from importlib import resources
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.pipeline import certify_file, load_certificate
from mcl2pnml.runtime.aal import ScriptedVehicle
from mcl2pnml.runtime.autopilot import AutopilotMapping
from mcl2pnml.runtime.bridge import VehicleMapping
from mcl2pnml.runtime.faults import Faults
from mcl2pnml.runtime.simulator import World
from mcl2pnml.runtime.vehicle_model import VehicleModel

from helpers import ROOT, run_cli

SAUCE = ROOT / "examples" / "sauce.mcl"
NAME = "cut.json"


def _certificate_text() -> str:
    cert, _, problems = certify_file(SAUCE)
    assert problems == []
    return json.dumps(cert, indent=1)


def _load_certificate(text: str, name: str) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / name
        path.write_text(text, encoding="utf-8")
        try:
            load_certificate(path)
        except Mcl2PnmlError as e:   # the error names the file as it was given
            raise Mcl2PnmlError(e.message, e.location and type(e.location)(
                name, e.location.line, e.location.column, e.location.source_line)) from None


#: Each kind of JSON input: a good file of it, and its reader of a text.
KINDS = {
    "mapping": (lambda: resources.files("mcl2pnml.runtime").joinpath("ardusub.json")
                .read_text("utf-8"), AutopilotMapping.from_json),
    "world": (lambda: (ROOT / "examples" / "lawnmower.world.json").read_text(), World.from_json),
    "faults": (lambda: (ROOT / "examples" / "sauce.faults.json").read_text(), Faults.from_json),
    "model": (lambda: (ROOT / "examples" / "sauce.model.json").read_text(),
              VehicleModel.from_json),
    "script": (lambda: (ROOT / "examples" / "lawnmower.vehicle.json").read_text(),
               ScriptedVehicle.from_json),
    "bridge": (lambda: (ROOT / "examples" / "bridges" / "sim_mapping.json").read_text(),
               VehicleMapping.from_json),
    "certificate": (_certificate_text, _load_certificate),
}


@functools.cache
def good(kind: str) -> str:
    return KINDS[kind][0]()


def assert_cut_is_located(kind: str, offset: int) -> None:
    """The file of ``kind`` cut at ``offset``: our error, at a line and column of it."""
    text = good(kind)
    with pytest.raises(Mcl2PnmlError) as info:
        KINDS[kind][1](text[:offset], NAME)
    location = info.value.location
    assert location is not None and location.file == NAME, str(info.value)
    assert location.line is not None and location.column is not None, str(info.value)
    assert 1 <= location.line <= max(1, text[:offset].count("\n") + 1), str(info.value)
    assert str(info.value).startswith(f"{NAME}:{location.line}:{location.column}: ")


def _cuts(kind: str) -> range:
    """The offsets that leave a text no reader takes: up to the end of its value."""
    return range(len(good(kind).rstrip()))


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kind=st.sampled_from(sorted(KINDS)), where=st.floats(0, 1, exclude_max=True))
def test_a_json_input_cut_anywhere_is_one_located_error(kind, where):
    assert_cut_is_located(kind, int(where * len(_cuts(kind))))


@pytest.mark.slow
@pytest.mark.parametrize("kind", sorted(KINDS))
def test_a_json_input_cut_at_every_offset_is_one_located_error(kind):
    for offset in _cuts(kind):
        assert_cut_is_located(kind, offset)


#: Every reader reads its JSON with the shared reader, so each shows a fault past the
#: last line where the file stops, ignores a byte order mark, refuses a key twice.
SHARED = sorted(KINDS)


@pytest.mark.parametrize("kind", SHARED)
def test_a_json_input_cut_after_a_newline_is_located_on_its_last_line(kind):
    text = good(kind)
    offset = text.index("\n", len(text) // 2) + 1     # the error lies past the last line
    with pytest.raises(Mcl2PnmlError) as info:
        KINDS[kind][1](text[:offset], NAME)
    location = info.value.location
    assert (location.file, location.line) == (NAME, text[:offset].count("\n")), str(info.value)


@pytest.mark.parametrize("kind", SHARED)
def test_a_utf8_byte_order_mark_is_ignored(kind):
    read = KINDS[kind][1]
    with_mark, without = read("\ufeff" + good(kind), NAME), read(good(kind), NAME)
    # read as without it (a script or a bridge's mapping compared by what it holds and where)
    plain = ("script", "bridge")
    assert (vars(with_mark) if kind in plain else with_mark) == \
        (vars(without) if kind in plain else without)


@pytest.mark.parametrize("kind", SHARED)
def test_a_key_given_twice_is_refused_where_it_is_given_again(kind):
    text = good(kind).rstrip()
    key, value = next(iter(json.loads(text).items()))
    again = f",\n {json.dumps(key)}: {json.dumps(value)}}}"   # the first key, last
    with pytest.raises(Mcl2PnmlError) as info:
        KINDS[kind][1](text[:-1] + again, NAME)
    location = info.value.location
    # said as the shared reader says it, or as a script says it ("'P' is scripted twice")
    assert re.search(rf"(the key {json.dumps(key)} is given|'{key}' is scripted) twice",
                     info.value.message), info.value.message
    assert (location.line, location.column) == (text.count("\n") + 2, 2), str(info.value)


# -- through the command line: exit status 2 for every command ---------------------------------

@pytest.fixture(scope="module")
def cut(tmp_path_factory):
    """``cut(kind)``: a file of ``kind`` cut after a newline in its middle."""
    folder = tmp_path_factory.mktemp("cut")

    def make(kind: str, name: str | None = None) -> Path:
        text = good(kind)
        path = folder / (name or f"{kind}.json")
        path.write_text(text[:text.index("\n", len(text) // 2) + 1])
        return path
    return make


def commands(cut, tmp: Path) -> list[tuple[str, list]]:
    mission = tmp / "sauce.mcl"
    shutil.copy(SAUCE, mission)
    cut("certificate", "sauce.cert.json").replace(tmp / "sauce.cert.json")
    return [
        ("script", ["run", SAUCE, "--vehicle", cut("script")]),
        ("model", ["run", SAUCE, "--vehicle", f"model:{cut('model')}"]),
        ("mapping", ["run", SAUCE, "--vehicle", f"mavlink:{cut('mapping')}", "--connect",
                     "tcp:127.0.0.1:1"]),
        ("bridge", ["run", SAUCE, "--vehicle", f"bridge:{cut('bridge')}", "--connect",
                    "127.0.0.1:1"]),
        ("world", ["run", SAUCE, "--vehicle", "sim", "--world", cut("world")]),
        ("faults", ["run", SAUCE, "--vehicle", "sim", "--faults", cut("faults")]),
        ("certificate", ["certify", cut("certificate"), "--check", SAUCE]),
        ("certificate", ["analyze", mission]),
        ("model", ["odds", SAUCE, "--vehicle-model", cut("model")]),
        ("model", ["campaign", SAUCE, "--vehicle-model", cut("model"), "--runs", "1",
                   "--workers", "1"]),
        ("world", ["campaign", SAUCE, "--world", cut("world"), "--runs", "1", "--workers", "1"]),
    ]


@pytest.mark.timeout(240)
def test_every_command_says_exit_2_for_a_json_file_cut_short(cut, tmp_path):
    for kind, args in commands(cut, tmp_path):
        out = run_cli(*args, timeout=120)
        command = " ".join(map(str, args))
        assert out.returncode == 2, (command, out.returncode, out.stderr)
        assert "Traceback" not in out.stderr, (command, out.stderr)
        first = out.stderr.splitlines()[0] if out.stderr else ""
        assert re.match(r"\S+\.json:\d+:\d+: ", first), (command, out.stderr)
        assert out.stdout == "", (command, out.stdout)


@pytest.mark.parametrize("load, limit, what", [
    (World.load, "MAX_WORLD", "world file"), (ScriptedVehicle.load, "MAX_SCRIPT",
                                              "vehicle script")])
def test_a_json_input_over_its_bound_is_refused_before_it_is_read(tmp_path, load, limit,
                                                                   what):
    import importlib
    module = importlib.import_module(load.__self__.__module__)
    bound = getattr(module, limit)
    path = tmp_path / "big.json"
    with open(path, "wb") as f:      # sparse: nothing of it is written, nor read
        f.truncate(bound + 1)
    with pytest.raises(Mcl2PnmlError) as info:
        load(path)
    assert str(info.value).startswith(f"{path}: cannot read the {what}: it is ")
