"""Running missions: the executor, the abstraction layer, the simulated AUV, the run command."""
from __future__ import annotations

import json

import pytest

from mcl2pnml.pipeline import check_file, check_source
from mcl2pnml.runtime.aal import Action, ActionKind, Event, EventKind, ScriptedVehicle, Vehicle
from mcl2pnml.language.compiler import compile_checked
from mcl2pnml.runtime.engine import Outcome, run
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.runtime.executor import PetriEngine
from mcl2pnml.io.pnml import parse_pnml, to_pnml
from mcl2pnml.runtime.simulator import AUVSimulator, World

from helpers import ENGINES, ROOT, engines, run_cli as cli
from bench.missions import survey

SAUCE = ROOT / "examples" / "sauce.mcl"
FOUND = {"GoToWayPoint": ["ok@30", "ok@40"], "DetectCross": ["ok@50"],
         "KeepDepth": ["ok@5", "ok@6"], "ReleaseMarker": ["ok@1"]}


def checked(source: str):
    return check_source(source, "m.mcl")


def scripted(script: dict) -> ScriptedVehicle:
    return ScriptedVehicle.from_json(json.dumps(script))


# -- the executor ------------------------------------------------------------------

def test_the_pnml_alone_runs_the_mission():
    """Bindings, actions, events and time-outs all travel in the PNML."""
    c = check_file(SAUCE)
    net = compile_checked(c)
    from_pnml = parse_pnml(to_pnml(net))
    a = run(PetriEngine(net), scripted(FOUND)).as_json()
    b = run(PetriEngine(from_pnml), scripted(FOUND)).as_json()
    assert a == b and a["outcome"] == "OK"


def test_a_net_that_is_not_a_mission_is_refused():
    from mcl2pnml.language.library import default_library
    with pytest.raises(Mcl2PnmlError, match="not a compiled mission.*mission.OK"):
        PetriEngine(default_library().composed("task"))


def _work_per_event(calls: int) -> tuple[float, float]:
    """Per vehicle event: transitions examined (median), and examined per firing (max)."""
    engine = PetriEngine(compile_checked(checked(survey(calls))))
    vehicle = scripted({"KeepDepth": ["ok@1"] * calls, "GoToWayPoint": ["ok@1"] * calls})
    examined, fired = [0], [0]   # the start, then one entry per event
    update, fire, on_event = engine._update, engine._fire, engine.on_event

    def counting_update(i):
        examined[-1] += 1
        update(i)

    def counting_fire(i):
        fired[-1] += 1
        return fire(i)

    def each_event(event):
        examined.append(0)
        fired.append(0)
        return on_event(event)
    engine._update, engine._fire, engine.on_event = counting_update, counting_fire, each_event
    assert run(engine, vehicle).outcome is Outcome.OK
    per_event = sorted(examined[1:])
    return per_event[len(per_event) // 2], max(e / max(f, 1) for e, f in
                                               zip(examined[1:], fired[1:]))


def test_the_cost_of_an_event_does_not_grow_with_the_mission():
    """Incremental enabling: what one event makes the executor look at is local.

    The typical event examines as many transitions in a survey of 400 calls
    as in one of 10, and no event examines more than a fixed number of
    transitions per transition it fires. (The very last event fires one
    transition per nesting level, as the mission's result goes up through
    its 400 nested sequences; those firings are the mission's, not overhead.)
    """
    small, large = _work_per_event(10), _work_per_event(400)
    assert small[0] == large[0]
    assert large[1] <= small[1]


def test_a_mission_that_waits_for_ever_stalls_and_says_on_what(engine):
    c = checked("primitive P(x);\ntask T(x) = AchieveGoal(P(x));\nmission { T(1); }\n")
    result = run(engine(c), scripted({"P": ["never"]}))
    assert result.outcome is Outcome.STALLED and result.time == 0
    assert any("P: waits for the vehicle's 'achieved' or 'failed'" in w
               or "P: waits for the vehicle's 'achieved'" in w for w in result.waiting), \
        result.waiting


def test_a_loop_that_never_lets_time_pass_is_an_error_not_a_hang(engine):
    c = checked("primitive P(x);\ntask T(x) = AchieveGoal(P(x));\n"
                "mission { while ({ }) { } }\n")
    with pytest.raises(Mcl2PnmlError, match="without time passing"):
        run(engine(c), scripted({}))


def test_time_outs_fire_on_virtual_time(engine):
    c = checked("primitive P(x);\ntask T(x) = AchieveGoal(P(x)) timeout 42.5;\n"
                "mission { T(1); }\n")
    result = run(engine(c), scripted({"P": ["never"]}))
    assert result.outcome is Outcome.FAIL and result.time == 42.5


# -- bad vehicle events: logged, ignored, and the mission goes on ---------------------

class Meddling(Vehicle):
    """A scripted vehicle that also sends events nobody asked for."""

    def __init__(self, inner: ScriptedVehicle, extra: list[Event]):
        self.inner, self.extra = inner, sorted(extra, key=lambda e: (e.t, e.primitive))

    def act(self, action: Action) -> None:
        self.inner.act(action)

    def next_event_time(self):
        times = [t for t in (self.inner.next_event_time(),
                             self.extra[0].t if self.extra else None) if t is not None]
        return min(times) if times else None

    def take_event(self) -> Event:
        t = self.inner.next_event_time()
        if self.extra and (t is None or self.extra[0].t < t):
            return self.extra.pop(0)
        return self.inner.take_event()


def test_bad_events_are_logged_and_ignored_alike_by_both_engines():
    c = check_file(SAUCE)
    bad = [Event(10, EventKind.ACHIEVED, "Thruster"),        # no such primitive
           Event(12, EventKind.ACHIEVED, "ReleaseMarker"),   # not enabled
           Event(15, EventKind.OFF, "GoToWayPoint"),         # off without a disable
           Event(50.5, EventKind.ACHIEVED, "DetectCross"),   # disabled already
           Event(55, EventKind.ACHIEVED, "KeepDepth")]       # a second report
    results = []
    for engine in engines(c):
        result = run(engine, Meddling(scripted(FOUND), bad))
        results.append(result)
    clean = run(PetriEngine(compile_checked(c)), scripted(FOUND))
    for result in results:
        assert result.outcome is clean.outcome and result.time == clean.time
        assert [e for e, _ in result.ignored] == bad
    assert [r for _, r in results[0].ignored] == [r for _, r in results[1].ignored]
    assert "no primitive 'Thruster' in this mission" == results[0].ignored[0][1]


# -- the scripted vehicle --------------------------------------------------------------

@pytest.mark.parametrize("text, message", [
    ('{"P": ["ok@5"', "not a vehicle script"),
    ('["ok@5"]', "a vehicle script is a JSON object"),
    ('{"P": "ok@5"}', "a list of replies"),
    ('{"P": ["ok5"]}', "'ok5' is not a reply; one of ok@SECONDS, fail@SECONDS, never"),
    ('{"P": ["ok@-1"]}', "not a number of seconds >= 0"),
])
def test_bad_scripts_say_what_is_valid(text, message):
    with pytest.raises(Mcl2PnmlError, match=message):
        ScriptedVehicle.from_json(text, "s.json")


def test_script_replies_in_order_then_never():
    v = scripted({"P": ["ok@2", "fail@1"]})
    seen = []
    for k in range(3):
        v.act(Action(10.0 * k, ActionKind.ENABLE, "P"))
        while v.next_event_time() is not None:
            seen.append((v.next_event_time(), v.take_event().kind.value))
        v.act(Action(10.0 * k + 5, ActionKind.DISABLE, "P"))
        seen.append((v.next_event_time(), v.take_event().kind.value))
    assert seen == [(0, "on"), (2, "achieved"), (5, "off"), (10, "on"), (11, "failed"),
                    (15, "off"), (20, "on"), (25, "off")]


# -- the simulated AUV --------------------------------------------------------------------

def _drive(sim: AUVSimulator, name: str, *args, until: float = 300.0) -> list[Event]:
    sim.act(Action(sim.state.t, ActionKind.ENABLE, name, args))
    events = []
    while (t := sim.next_event_time()) is not None and t <= until:
        events.append(sim.take_event())
        if events[-1].kind in (EventKind.ACHIEVED, EventKind.FAILED):
            break
    return events


def test_the_auv_reaches_a_waypoint_within_its_limits():
    sim = AUVSimulator(World(cross=None))
    events = _drive(sim, "GoToWayPoint", (10.0, 4.0, 2.0))
    assert [e.kind for e in events] == [EventKind.ON, EventKind.ACHIEVED]
    s = sim.state
    assert abs(s.x - 10) ** 2 + abs(s.y - 4) ** 2 + abs(s.z - 2) ** 2 <= 0.5 ** 2 + 1e-9
    # never faster than its limits
    w = sim.world
    for (t0, x0, y0, z0), (t1, x1, y1, z1) in zip(sim.trajectory, sim.trajectory[1:]):
        dt = t1 - t0
        assert ((x1 - x0) ** 2 + (y1 - y0) ** 2) ** 0.5 <= w.max_speed * dt + 1e-9
        assert abs(z1 - z0) <= w.max_heave * dt + 1e-9
    # 8 m at 0.5 m/s at best
    assert events[-1].t >= 8 / w.max_speed


def test_the_auv_refuses_what_it_cannot_do_at_once():
    sim = AUVSimulator()
    events = _drive(sim, "GoToWayPoint", (40.0, 0.0, 2.0))
    assert [e.kind for e in events] == [EventKind.ON, EventKind.FAILED]
    assert "outside the 16 x 8 x 5 m tank" in sim.problems[0][2]


def test_the_camera_sees_the_cross_only_where_there_is_one():
    for cross, seen in (((2.0, 4.0), True), (None, False)):
        sim = AUVSimulator(World(cross=cross))
        events = _drive(sim, "DetectCross", until=60)
        assert (EventKind.ACHIEVED in [e.kind for e in events]) == seen


def test_depth_is_held_lost_and_regained():
    sim = AUVSimulator()
    events = _drive(sim, "KeepDepth", 3.0)
    assert events[-1].kind is EventKind.ACHIEVED and abs(sim.state.z - 3.0) <= 0.2


def test_noise_is_seeded():
    def path(seed):
        sim = AUVSimulator(World(noise=0.1, seed=seed, cross=None))
        _drive(sim, "GoToWayPoint", (10.0, 4.0, 2.0))
        return sim.trajectory
    assert path(1) == path(1) and path(1) != path(2)


def test_both_engines_agree_on_the_simulated_auv():
    c = check_file(SAUCE)
    runs = [run(e, AUVSimulator(World(noise=0.05, seed=4)), max_time=3600).as_json()
            for e in engines(c)]
    assert runs[0] == runs[1] and runs[0]["outcome"] == "OK"


# -- the run command -------------------------------------------------------------------

def test_run_json_is_the_object_of_the_spec(tmp_path):
    script = tmp_path / "v.json"
    script.write_text(json.dumps(FOUND))
    outs = [json.loads(cli("run", SAUCE, "--engine", e, "--vehicle", script, "--json").stdout)
            for e in ENGINES]
    assert outs[0] == outs[1]
    assert set(outs[0]) == {"outcome", "time", "trace"} and outs[0]["outcome"] == "OK"
    assert outs[0]["trace"][0] == {"t": 0, "action": "enable", "primitive": "DetectCross",
                                   "args": []}
    assert {"t": 50, "event": "achieved", "primitive": "DetectCross"} in outs[0]["trace"]


def test_run_live_log_and_jsonl(tmp_path):
    log = tmp_path / "run.jsonl"
    out = cli("run", SAUCE, "--transitions", "--log", log)
    assert out.returncode == 0, out.stderr
    assert "action    enable    GoToWayPoint((10.0, 0.0, 2.0))" in out.stdout
    assert "fire      " in out.stdout and out.stdout.strip().endswith("s")
    assert "outcome OK at t=" in out.stdout
    entries = [json.loads(line) for line in log.read_text().splitlines()]
    assert {"fire", "action", "event"} <= {k for e in entries for k in e}


@pytest.mark.parametrize("args, message", [
    (["--engine", "reference", "--vehicle", "x.json"],
     "x.json: cannot read the vehicle script: No such file"),
    (["--vehicle", "sim", "--world", ROOT / "README.md"], "not a world file"),
])
def test_run_bad_input_is_one_message(args, message):
    out = cli("run", SAUCE, *args)
    assert out.returncode == 2 and message in out.stderr and "Traceback" not in out.stderr


def test_run_a_pnml_with_the_reference_engine_is_refused(tmp_path):
    pnml = tmp_path / "sauce.pnml"
    assert cli("compile", SAUCE, "-o", pnml).returncode == 0
    out = cli("run", pnml, "--engine", "reference")
    assert out.returncode == 2 and "reads MCL" in out.stderr
    out = cli("run", pnml, "--json")
    assert out.returncode == 0 and json.loads(out.stdout)["outcome"] == "OK"


# -- a real vehicle through a mapping file and a bridge (in real time) ------------------

BRIDGES = ROOT / "examples" / "bridges"


def test_mapping_files_say_what_is_wrong(tmp_path):
    from mcl2pnml.runtime.bridge import VehicleMapping
    for text, message in [
        ('{"primitives": {"P": {"enable": {"command": "go"}}}}', '"disable" must be an object'),
        ('{"primitives": {"P": {"enable": {"command": "go"}, "disable": {"command": "s"}, '
         '"events": {"arrived": {"m": 1}}}}}', "unknown event 'arrived'; valid: on, achieved"),
        ('{"primitives": {"P": {"enable": {"command": "go", "x": "$x"}, '
         '"disable": {"command": "s"}}}}', r"'\$x' is not an argument"),
        ('{"vehicle": "v"}', 'with "primitives"'),
    ]:
        with pytest.raises(Mcl2PnmlError, match=message) as info:
            VehicleMapping.from_json(text, "m.json")
        # each fault at its line and column: the value it is about, in the file's one line
        assert info.value.location.line == 1 and info.value.location.column is not None, \
            str(info.value)


def test_the_mapping_turns_actions_into_commands_and_messages_into_events():
    from mcl2pnml.runtime.bridge import VehicleMapping
    m = VehicleMapping.load(BRIDGES / "sim_mapping.json")
    cmd = m.command(Action(0, ActionKind.ENABLE, "GoToWayPoint", ((10.0, 0.0, 2.0),)))
    assert cmd == {"command": "start_GoToWayPoint", "args": {"x": 10.0, "y": 0.0, "z": 2.0}}
    assert m.command(Action(0, ActionKind.DISABLE, "KeepDepth")) == {"command": "stop_KeepDepth"}
    event = m.event({"message": "status", "primitive": "KeepDepth", "status": "done"}, 3.0)
    assert event == Event(3.0, EventKind.ACHIEVED, "KeepDepth")
    assert m.event({"message": "battery", "level": 80}, 3.0) is None


def test_a_mission_runs_in_real_time_through_the_bridge():
    import importlib.util
    import sys
    sys.path.insert(0, str(BRIDGES))
    spec = importlib.util.spec_from_file_location("bridge_server", BRIDGES / "bridge_server.py")
    server_module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(server_module)
    server = server_module.serve(0, "fake", delay=0.02)
    try:
        port = server.server_address[1]
        out = cli("run", SAUCE, "--vehicle", f"bridge:{BRIDGES / 'sim_mapping.json'}",
                  "--connect", f"127.0.0.1:{port}", "--json", "--max-time", "30")
        assert out.returncode == 0, out.stderr
        result = json.loads(out.stdout)
        # the fake vehicle does everything at once: the camera sees the cross first
        assert result["outcome"] == "OK" and result["time"] < 5
        assert [e["primitive"] for e in result["trace"] if e.get("action") == "enable"][-2:] \
            == ["ReleaseMarker", "KeepDepth"]
    finally:
        server.shutdown()


def test_a_run_stopped_at_its_time_limit_names_the_timers_it_waits_for():
    c = checked("primitive P(x);\ntask T(x) = AchieveGoal(P(x)) timeout 500;\n"
                "mission { T(1); }\n")
    for engine in engines(c):
        result = run(engine, scripted({"P": ["never"]}), max_time=100)
        assert result.outcome is Outcome.TIMELIMIT and result.time == 100
        assert any("time-out" in w and "t=500 s" in w for w in result.waiting), result.waiting


def test_heading_is_held():
    sim = AUVSimulator()
    events = _drive(sim, "KeepHeading", 90.0)
    assert events[-1].kind is EventKind.ACHIEVED
    assert abs(sim.state.yaw - 3.14159265 / 2) <= sim.world.heading_band
