"""The payload records: one mapping to and from the JSON that PNML carries."""
from __future__ import annotations

from pathlib import Path

import pytest

from mcl2pnml.pipeline import compile_file
from mcl2pnml.core import payloads
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import NetBuilder, freeze
from mcl2pnml.core.payloads import (ActionKind, ActionSpec, CallEntry, EventBinding, EventKind,
                                    MissionPlace, Param, PayloadError, TimeOut,
                                    TransitionPayload, TupleOf, Value)
from mcl2pnml.language.template_parser import parse_template
from mcl2pnml.runtime import aal

from conftest import ROOT

EXAMPLES = sorted((ROOT / "examples").glob("*.mcl"))


@pytest.mark.parametrize("mission", EXAMPLES, ids=lambda p: p.stem)
def test_every_compiled_payload_reads_and_writes_back_the_same(mission: Path):
    net = compile_file(mission)
    for t in net.transitions:
        assert freeze(payloads.read(t.payload).to_json()) == t.payload, t.id
    entries = [payloads.read(t.payload).entry for t in net.transitions if t.id.endswith(".enter")]
    assert entries and all(isinstance(e, CallEntry) for e in entries)
    assert {p.id for p in MissionPlace} <= set(net.place_index)


def test_records_map_to_the_json_the_executor_has_always_read():
    enter = TransitionPayload(doc="enter", entry=CallEntry(
        "Goto", "Survey", (("wp", Param("p")), ("d", Value((1.0, 2.0))))))
    assert enter.to_json() == {"call": "Goto", "scope": "Survey", "doc": "enter",
                               "bind": {"wp": {"param": "p"}, "d": {"value": (1.0, 2.0)}}}
    actions = TransitionPayload(actions=(
        ActionSpec(ActionKind.ENABLE, "KeepDepth", "Dive", (Param("d"),)),
        ActionSpec(ActionKind.DISABLE, "KeepDepth")))
    assert actions.to_json() == {"actions": [
        {"action": "enable", "primitive": "KeepDepth", "scope": "Dive",
         "args": [{"param": "d"}]},
        {"action": "disable", "primitive": "KeepDepth"}]}
    assert TransitionPayload(timeout=TimeOut()).to_json() == {"timeout": True}
    assert TransitionPayload(timeout=TimeOut(300)).to_json() == {"timeout": 300}
    assert TransitionPayload().to_json() is None
    event = TransitionPayload(event=EventBinding(EventKind.ON)).of_primitive("KeepDepth")
    assert event.to_json() == {"event": "on", "primitive": "KeepDepth"}


def test_arguments_evaluate_as_the_vehicle_receives_them():
    assert Value((1.0, 2.0)).evaluate({}) == (1.0, 2.0)
    assert Param("wp").evaluate({"wp": [3, 4]}) == (3, 4)


def test_a_tuple_naming_a_parameter_is_made_at_the_call_and_written_as_such():
    arg = TupleOf((Param("a"), Value(0.0), TupleOf((Param("b"), Value("x")))))
    assert arg.evaluate({"a": 1.5, "b": [2, 3]}) == (1.5, 0.0, ((2, 3), "x"))
    record = TransitionPayload(entry=CallEntry("Leg", "Row", (("wp", arg),)))
    assert payloads.read(record.to_json()) == record
    deep: dict = {"param": "a"}
    for _ in range(payloads.MAX_ARG_NESTING + 1):
        deep = {"tuple": [deep]}
    with pytest.raises(PayloadError, match="nest at most"):
        payloads.read({"call": "Leg", "scope": "Row", "bind": {"wp": deep}})


PARAMETER_IN_A_TUPLE = """\
primitive GoToWayPoint(wp);
task Go(wp) = AchieveGoal(GoToWayPoint(wp)) timeout 10;
function Leg(wp) { Go(wp); }
function Row(a, d) { Leg((a, 0.0, d)); Go((a, 1.0, d)); }
mission { Row(1.0, 2.0); Row(3.0, 4.0); }
"""


def test_a_function_parameter_inside_a_tuple_argument_reaches_the_vehicle_on_both_engines():
    from helpers import both
    from mcl2pnml.pipeline import check_source
    petri, reference = both(check_source(PARAMETER_IN_A_TUPLE, "row.mcl"),
                            {"GoToWayPoint": ["ok@1"] * 4})
    assert petri == reference and petri["outcome"] == "OK"
    sent = [e["args"][0] for e in petri["trace"] if e.get("action") == "enable"]
    assert sent == [[1.0, 0.0, 2.0], [1.0, 1.0, 2.0], [3.0, 0.0, 4.0], [3.0, 1.0, 4.0]]


def test_unknown_keys_are_kept_and_bad_known_ones_refused():
    tagged = payloads.read({"doc": "d", "colour": "red"})
    assert tagged.extra == (("colour", "red"),) and tagged.to_json() == {"doc": "d",
                                                                          "colour": "red"}
    assert payloads.read([1, 2]) == TransitionPayload()   # another tool's payload
    with pytest.raises(PayloadError, match="'event' is one of on, achieved, failed, off"):
        payloads.read({"event": "arrived"})
    b = NetBuilder("n")
    b.transition("t", payload={"actions": [{"action": "jump", "primitive": "P"}]})
    with pytest.raises(Mcl2PnmlError, match="transition 't': 'action' is one of"):
        payloads.read_transition(b.build().transition_index["t"])


def test_a_template_tag_with_a_bad_event_kind_is_an_error_of_the_template():
    text = 'primitive p\nplace ON interface\ntransition t: ON -> ON event=arrived\n'
    with pytest.raises(Mcl2PnmlError, match="'event' is one of"):
        parse_template(text, "p.pnt")


def test_the_abstraction_layer_re_exports_the_kinds_and_the_mission_names_its_places():
    assert aal.EventKind is EventKind and aal.ActionKind is ActionKind
    assert [p.id for p in MissionPlace] == ["mission.B", "mission.A", "mission.OK",
                                            "mission.FAIL", "mission.ABORTED"]
