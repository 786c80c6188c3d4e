"""The autopilot mapping file (``--vehicle mavlink:MAPPING.json``) and where its faults are shown.

The package's own mapping loads and binds only primitives the simulator
gives a meaning to. Every invalid mapping is one message at the file,
line and column of the bad value (each golden file of
``tests/data/autopilot/invalid`` holds its input's message), whatever the
file is: not JSON, cut short, a NaN, a key given twice, not UTF-8, too
large, nested too deep; a sensor or actuator bound to be flown by the
autopilot, an empty safe state (``"none"`` says it on purpose). A UTF-8
byte order mark is ignored. The command line
checks the mapping before it connects to anything. Positions come from
:mod:`mcl2pnml.core.jsontext`, tested here against positions counted by
hand.
"""
from __future__ import annotations

import json
import socket
from importlib import resources

import pytest
from hypothesis import given, settings, strategies as st

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.jsontext import dotted, locator, offsets
from mcl2pnml.runtime.autopilot import MAX_MAPPING, SAFE_STEPS, AutopilotMapping, Binding
from mcl2pnml.runtime.simprims import installed

from helpers import DATA, ROOT, assert_error_golden, one_error, run_cli
from sampling import sample

INVALID = sorted((DATA / "autopilot" / "invalid").glob("*.json"))
SAUCE = ROOT / "examples" / "sauce.mcl"
GOOD = {"primitives": {"GoToWayPoint": {"by": "autopilot"}}}


def error_of(text: str, name: str = "m.json") -> Mcl2PnmlError:
    with pytest.raises(Mcl2PnmlError) as info:
        AutopilotMapping.from_json(text, name)
    return info.value


# -- the package's own mapping ----------------------------------------------------------------

def test_the_default_mapping_loads_with_its_documented_settings():
    mapping = AutopilotMapping.ardusub()
    assert mapping.safe_state == SAFE_STEPS == ("hold", "surface", "disarm")
    assert (mapping.ready_within, mapping.ack_within, mapping.position_lost_after,
            mapping.telemetry_rate, mapping.hold_within, mapping.surface_depth,
            mapping.surface_within) == (180, 3, 5, 10, 10, 0.3, 120)
    assert mapping.home is None
    bindings = mapping.bindings
    assert bindings["ReleaseMarker"] == Binding("ReleaseMarker", "servo", channel=9, pwm=1900,
                                                release_pwm=1100)
    assert {name for name, b in bindings.items() if b.by == "autopilot"} == {
        "GoToWayPoint", "GoToPoint", "HomeToDock", "KeepDepth", "KeepHeading"}
    # every primitive it binds has a simulated primitive that says what it means
    assert set(bindings) <= set(installed())


def test_a_small_mapping_takes_the_defaults_for_what_it_leaves_out():
    mapping = AutopilotMapping.from_json(json.dumps({
        "home": [2, 4], "safe_state": ["surface", "disarm"],
        "primitives": {"GoToWayPoint": {"by": "autopilot", "settle": 1, "tolerance": 0.5},
                       "FireBottle": {"by": "relay", "relay": 3},
                       "DetectCross": {"by": "simulated"}}}), "small.json")
    assert mapping.home == (2.0, 4.0) and all(isinstance(v, float) for v in mapping.home)
    assert mapping.safe_state == ("surface", "disarm")
    assert mapping.ack_within == AutopilotMapping.ack_within
    assert mapping.bindings["GoToWayPoint"] == Binding("GoToWayPoint", "autopilot", settle=1,
                                                       tolerance=0.5)
    assert mapping.bindings["FireBottle"] == Binding("FireBottle", "relay", relay=3)
    assert mapping.filename == "small.json"


def test_a_safe_state_may_leave_steps_out_but_keeps_their_order():
    for steps in (["hold"], ["disarm"], ["hold", "disarm"], ["surface", "disarm"]):
        mapping = AutopilotMapping.from_json(json.dumps({**GOOD, "safe_state": steps}))
        assert mapping.safe_state == tuple(steps)
    for steps in (["surface", "hold"], ["disarm", "surface"], ["hold", "disarm", "surface"]):
        e = error_of(json.dumps({**GOOD, "safe_state": steps}))
        assert "the steps go in the order hold, surface, disarm" in str(e)


# -- every invalid mapping is one located message ----------------------------------------------

@pytest.mark.parametrize("path", INVALID, ids=lambda p: p.stem)
def test_an_invalid_mapping_is_one_located_message(path, monkeypatch):
    monkeypatch.chdir(path.parent)
    with pytest.raises(Mcl2PnmlError) as info:
        AutopilotMapping.load(path.name)
    assert_error_golden(path, info.value)
    location = info.value.location
    assert location.file == path.name and location.line and location.column


@pytest.mark.parametrize("text, line, column, words", [
    ('{\n  "primitives": {},\n  "ack_within": 3,\n  "liveness": 5\n}', 4, 15,
     "the file: unknown setting ('liveness' was unexpected); valid: ack_within, autopilot, "
     "hold_within, home, position_lost_after, primitives, ready_within, safe_state, "
     "secure_within, surface_depth, surface_within, telemetry_rate"),
    ('{"primitives": {"R": {"by": "thrusters"}}}', 1, 29,
     'primitives.R.by: "thrusters" is not one of autopilot, servo, relay, simulated'),
    ('{"primitives": {"R": {"by": "servo", "pwm": 1900}}}', 1, 22,
     "primitives.R: 'channel' is a required property"),
    ('{"primitives": {"R": {"by": "servo", "channel": 9,\n "pwm": 2501}}}', 2, 9,
     "primitives.R.pwm: 2501 is greater than the maximum of 2500"),
    ('{"primitives": {"R": {"by": "servo", "channel": 9, "pwm": 499}}}', 1, 59,
     "primitives.R.pwm: 499 is less than the minimum of 500"),
    ('{"safe_state": ["disarm", "hold"], "primitives": {}}', 1, 16,
     "safe_state: the steps go in the order hold, surface, disarm"),
    ('{"primitives": {}, "ready_within": -0.5}', 1, 36,
     "ready_within: -0.5 is less than the minimum of 1"),
    ('{"primitives": "GoToWayPoint"}', 1, 16,
     "primitives: 'GoToWayPoint' is not of type 'object'"),
    ('{"primitives": {}, "hold_within": NaN}', 1, 35, "hold_within: NaN is not a number"),
    ('{"primitives": {"G": {"by": "autopilot", "settle": NaN}}}', 1, 52,
     "primitives.G.settle: NaN is not a number"),
    ('{"primitives": {}, "home": [0, NaN]}', 1, 32, "home[1]: NaN is not a number"),
    ('{"primitives": {"9G": {"by": "autopilot"}}}', 1, 23,
     "primitives: '9G' does not match"),
    ('{"primitives": {}, "ack_within": 1, "ack_within": 0.01}', 1, 37,
     'ack_within: the key "ack_within" is given twice (first at 1:20)'),
    ('{"primitives": {"KeepDepth": {"by": "autopilot"}},\n "primitives": {}}', 2, 2,
     'primitives: the key "primitives" is given twice (first at 1:2)'),
    ('{"primitives": {"G": {"by": "autopilot",\n  "settle": 1, "by": "servo"}}}', 2, 16,
     'primitives.G.by: the key "by" is given twice (first at 1:23)'),
    ('{"primitives": {"DetectCross": {"by": "autopilot"}}}', 1, 39,
     'primitives.DetectCross.by: the autopilot cannot fly DetectCross: it steers nothing'),
    ('{"primitives": {"ReleaseMarker": {"by": "autopilot"}}}', 1, 41,
     'primitives.ReleaseMarker.by: the autopilot cannot fly ReleaseMarker'),
    ('{"primitives": {},\n "safe_state": []}', 2, 16,
     'safe_state: an empty list would leave the vehicle as it is when the run ends (armed, '
     'wherever it is); to mean that, write "safe_state": "none"'),
    ('{"primitives": {}, "safe_state": "nothing"}', 1, 34, "safe_state: 'nothing'"),
    ('{"primitives": {}, "home": [0, Infinity]}', 1, 32, "home[1]: Infinity is not a number"),
], ids=["unknown-setting", "unknown-by", "servo-without-channel", "pwm-too-high",
        "pwm-too-low", "safe-state-order", "negative-ready-within", "primitives-not-object",
        "nan", "nan-in-a-binding", "nan-in-home", "bad-name", "duplicate-key",
        "duplicate-primitives", "duplicate-key-deep", "sensor-flown", "actuator-flown",
        "empty-safe-state", "safe-state-word", "infinity"])
def test_the_message_is_at_the_bad_value(text, line, column, words):
    e = error_of(text)
    assert (e.location.file, e.location.line, e.location.column) == ("m.json", line, column)
    assert e.message.startswith(words) or words in e.message, e.message
    assert str(e).startswith(f"m.json:{line}:{column}: ")
    head, *excerpt = str(e).split("\n")
    assert len(excerpt) == 2 and excerpt[1].index("^") == 4 + column - 1, str(e)


@pytest.mark.parametrize("text", ["", "  \n\t\n", "{", "{\n", "[1, 2", "[1, 2\n\n",
                                  '{"primitives": {}}}', "\ufeff", "\ufeff{",
                                  '{"primitives": {}, "ack_within": 1' + "0" * 5000 + "}"],
                         ids=["empty", "blanks", "open", "open-newline", "open-array",
                              "open-array-newlines", "trailing", "bom-only", "bom-open",
                              "huge-int"])
def test_text_that_is_no_json_is_one_message(text):
    e = error_of(text)
    assert str(e).startswith("m.json:") and "not an autopilot mapping: " in str(e)
    assert e.location.file == "m.json"


def test_a_safe_state_of_no_step_is_said_on_purpose():
    mapping = AutopilotMapping.from_json(json.dumps({**GOOD, "safe_state": "none"}))
    assert mapping.safe_state == ()


def test_a_utf8_byte_order_mark_is_ignored_and_columns_count_after_it():
    mapping = AutopilotMapping.from_json("\ufeff" + json.dumps(GOOD))
    assert mapping.bindings["GoToWayPoint"].by == "autopilot"
    e = error_of('\ufeff{"primitives": {}, "ack_within": 0}')
    assert (e.location.line, e.location.column) == (1, 34)


def test_a_mapping_that_is_not_utf8_is_refused_at_its_first_bad_byte(tmp_path):
    path = tmp_path / "latin1.json"
    path.write_bytes('{"autopilot": "ArduSub",\n "primitives": {"Caf\u00e9": {}}}'
                     .encode("latin-1"))
    with pytest.raises(Mcl2PnmlError) as info:
        AutopilotMapping.load(path)
    assert str(info.value) == (
        f"{path}:2:21: not UTF-8 text: byte 0xe9 (invalid continuation byte); save the file "
        'as UTF-8\n     "primitives": {"Caf\ufffd": {}}}\n' + " " * 24 + "^")


def test_a_mapping_over_one_mib_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / "big.json"
    path.write_text(json.dumps({**GOOD, "autopilot": "x" * MAX_MAPPING}))
    with pytest.raises(Mcl2PnmlError) as info:
        AutopilotMapping.load(path)
    assert str(info.value) == (f"{path}: cannot read the autopilot mapping: it is 1.0 MiB, "
                               "over the limit of 1.0 MiB")
    assert info.value.location == Location(str(path))


def _deepest_json() -> int:
    """The deepest array ``json.loads`` reads at about this depth of the stack."""
    depth = 1
    while True:
        try:
            json.loads("[" * (depth + 1) + "]" * (depth + 1))
        except RecursionError:
            return depth
        depth += 1


@pytest.mark.timeout(60)
def test_a_mapping_nested_deep_is_one_message_at_every_depth():
    e = error_of("[" * 100_000 + "]" * 100_000)
    assert str(e) == "m.json: not an autopilot mapping: arrays or objects nested too deeply"
    # a value nested a little less deep than json reads, in each place one can stand:
    # writing its message (the value's repr) overflowed the stack
    deepest = _deepest_json()
    for template in ('{"primitives": {"A": %s}}', '{"primitives": {"A": {"by": %s}}}',
                     '{"primitives": {}, "home": %s}', '%s'):
        for depth in range(deepest - 6, deepest + 3):
            e = error_of(template % ("[" * depth + "]" * depth))    # ours, no RecursionError
            assert str(e).startswith("m.json:")


def test_the_command_line_checks_the_mapping_before_it_connects(tmp_path):
    bad = tmp_path / "BAD.json"
    bad.write_text('{\n  "ack_within": 3,\n  "primitives": {\n'
                   '    "ReleaseMarker": {"by": "servo", "channel": 9, "pwm": 3000}\n  }\n}\n')
    # a listener that would see the connection, if one were made
    with socket.create_server(("127.0.0.1", 0)) as listener:
        port = listener.getsockname()[1]
        out = run_cli("run", SAUCE, "--vehicle", f"mavlink:{bad}", "--connect",
                      f"tcp:127.0.0.1:{port}", "--liveness", "1", timeout=60)
        one_error(out, f"{bad}:4:59: primitives.ReleaseMarker.pwm: 3000 is greater than the "
                       "maximum of 2500")
        listener.setblocking(False)
        with pytest.raises(BlockingIOError):
            listener.accept()
    assert out.stdout == ""
    # and to an address nothing listens on: the mapping's message, not the connection's
    out = run_cli("run", SAUCE, "--vehicle", f"mavlink:{bad}", "--connect",
                  "tcp:127.0.0.1:1", timeout=60)
    text = one_error(out, f"{bad}:4:59:")
    assert "cannot connect" not in text


def test_a_mapping_that_binds_a_primitive_nothing_gives_a_meaning_is_refused(tmp_path):
    mission = tmp_path / "m.mcl"
    mission.write_text("primitive Hover(depth);\n"
                       "task H() = AchieveGoal(Hover(2.0)) timeout 10;\n"
                       "mission { H(); }\n")
    mapping = tmp_path / "hover.json"
    mapping.write_text(json.dumps({"primitives": {"Hover": {"by": "autopilot"}}}))
    out = run_cli("run", mission, "--vehicle", f"mavlink:{mapping}", "--connect",
                  "tcp:127.0.0.1:1", timeout=60)
    one_error(out, "the mapping binds 'Hover', but no simulated primitive of that name")


# -- positions in a JSON text (mcl2pnml.core.jsontext) --------------------------------------------

NESTED = ('{\n'
          '  "a": 1,\n'
          '  "b": {"c": [10, {"d": "x"}, [ ]], "e": null},\n'
          '  "a": [true]\n'
          '}')


def test_offsets_of_nested_objects_and_arrays():
    # counted by hand: line 3 is '  "b": {"c": [10, {"d": "x"}, [ ]], "e": null},'
    where = locator(NESTED, "n.json")
    expected = {(): (1, 1), ("b",): (3, 8), ("b", "c"): (3, 14), ("b", "c", 0): (3, 15),
                ("b", "c", 1): (3, 19), ("b", "c", 1, "d"): (3, 25), ("b", "c", 2): (3, 31),
                ("b", "e"): (3, 42),
                # a key given twice: JSON takes the last, and so does the locator
                ("a",): (4, 8), ("a", 0): (4, 9)}
    for path, (line, column) in expected.items():
        location = where(path)
        assert (location.line, location.column) == (line, column), path
    assert where(("b", "c", 1)).source_line == NESTED.split("\n")[2]
    assert set(offsets(NESTED)) == set(expected)


def test_offsets_are_characters_from_the_start():
    assert offsets('{"k": [1, 2]}') == {(): 0, ("k",): 6, ("k", 0): 7, ("k", 1): 10}
    assert offsets('  42 ') == {(): 2}
    assert offsets('{"a": {}, "b": []}') == {(): 0, ("a",): 6, ("b",): 15}
    # escapes and brackets inside strings are no structure
    assert offsets('{"a\\"}": "{[", "b": 2}') == {(): 0, ('a"}',): 9, ("b",): 20}
    # one character is one column, whatever its UTF-8 length
    assert offsets('{"é": [1]}') == {(): 0, ("é",): 6, ("é", 0): 7}
    # duplicate keys: the last
    assert offsets('{"x": 1, "x": {"y": 2}}') == {(): 0, ("x",): 14, ("x", "y"): 20}


def test_the_locator_counts_lines_and_columns_from_one():
    text = '{\r\n\t"a" :\t1,\r\n  "b": [\n    {"c": 3}\n  ]\r\n}'
    where = locator(text, "t.json")
    assert (where(()).line, where(()).column) == (1, 1)
    assert (where(("a",)).line, where(("a",)).column) == (2, 8)    # a tab is one column
    assert (where(("b",)).line, where(("b",)).column) == (3, 8)
    assert (where(("b", 0, "c")).line, where(("b", 0, "c")).column) == (4, 11)
    # a path that is not in the file: its nearest ancestor that is
    assert (where(("b", 0, "zz", 3)).line, where(("b", 0, "zz", 3)).column) == (4, 5)
    assert (where(("nothing",)).line, where(("nothing",)).column) == (1, 1)
    assert where(("a",)).file == "t.json"


def test_the_locator_takes_as_deep_a_text_as_json_reads():
    def nested(depth: int) -> str:
        return '{"k": ' + "[" * depth + "1" + "]" * depth + "}"
    depth = 100
    while True:     # the deepest json reads here
        try:
            json.loads(nested(depth + 100))
        except RecursionError:
            break
        depth += 100
    text = nested(depth)
    where = locator(text, "d.json")
    assert where(("k",) + (0,) * depth).column == 7 + depth
    assert where(("k",) + (0,) * (depth + 3)).column == 7 + depth


def test_dotted_paths():
    assert dotted(("primitives", "KeepDepth", "band")) == "primitives.KeepDepth.band"
    assert dotted(("safe_state", 1)) == "safe_state[1]"
    assert dotted(("home", 0)) == "home[0]"
    assert dotted(()) == "the file"


JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=5),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=4), inner,
                                                                max_size=4),
    max_leaves=20)


def _paths(value, path=()):
    yield path, value
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _paths(item, path + (key,))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            yield from _paths(item, path + (index,))


@settings(max_examples=sample(200, 70), deadline=None)
@given(JSON, st.sampled_from([None, 0, 2, "\t"]), st.sampled_from([(",", ":"), (", ", ": ")]),
       st.booleans())
def test_every_value_starts_where_the_locator_says(value, indent, separators, ascii_only):
    text = json.dumps(value, indent=indent, separators=separators, ensure_ascii=ascii_only)
    starts = offsets(text)
    decoder = json.JSONDecoder()
    for path, item in _paths(value):
        assert decoder.raw_decode(text, starts[path])[0] == item, (text, path)
        where = locator(text, "h.json")(path)
        assert text.split("\n")[where.line - 1][where.column - 1:] == \
            text[starts[path]:].split("\n")[0]


@pytest.mark.timeout(120)
def test_a_safe_state_of_no_step_leaves_the_autopilot_as_it_is(tmp_path):
    pytest.importorskip("pymavlink")
    from fake_autopilot import ARM_DISARM, FakeAutopilot
    mapping = json.loads(resources.files("mcl2pnml.runtime").joinpath("ardusub.json")
                         .read_text("utf-8"))
    path = tmp_path / "none.json"
    path.write_text(json.dumps({**mapping, "safe_state": "none"}))
    with FakeAutopilot() as fake:
        out = run_cli("run", SAUCE, "--vehicle", f"mavlink:{path}", "--connect", fake.address,
                      "--liveness", "5", "--json", timeout=90)
        fake.check()
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert result["outcome"] == "OK" and not result.get("safe_state")
    assert [p[0] for p in fake.commanded(ARM_DISARM)] == [1]     # armed, never disarmed
    assert fake.armed
