"""Faults from the vehicle's side: each ends in a result or a diagnosed stall, with a safe stop.

docs/faults.md lists the outcome of each fault; every test here runs the
same faulty vehicle against both engines, which must agree, and checks
that no primitive is left enabled on the vehicle at the end.
"""
from __future__ import annotations

import heapq
import json
import signal

import pytest

from mcl2pnml.pipeline import check_source
from mcl2pnml.runtime.aal import (Action, ActionKind, Event, EventKind, SafeStop, ScriptedVehicle,
                          Vehicle, VehicleInputError)
from mcl2pnml.runtime.bridge import MappedVehicle, QueueTransport, VehicleMapping
from mcl2pnml.runtime.engine import Outcome, Run, run, run_realtime

from helpers import engines, run_cli as cli

MISSION = """\
primitive P(x);
primitive Q(x);
task T(x) = AchieveGoal(P(x)) timeout 10;
task U(x) = AchieveGoal(Q(x));
mission {
    if (T(1)) then { U(1); }
    U(2);
}
"""
SCRIPT = {"P": ["ok@5"], "Q": ["ok@5", "ok@5"]}
ACHIEVED, ON = EventKind.ACHIEVED, EventKind.ON


class Faulty(Vehicle):
    """A scripted vehicle with faults injected between it and the engine.

    Rules name an event by (primitive, kind, n): the n-th such event the
    script sends. ``drop`` loses it, ``duplicate`` sends it again that many
    seconds later, ``delay`` sends it that many seconds late (a disable no
    longer cancels it: a late event); ``inject`` adds events of its own
    (sent before the script's at the same instant); ``fail_act`` makes
    :meth:`act` raise on the n-th action of that kind to that primitive;
    ``interrupt_at`` raises KeyboardInterrupt when the first event at or
    after that time is taken.
    """

    def __init__(self, script: dict, *, drop=(), duplicate=None, delay=None, inject=(),
                 fail_act=None, interrupt_at=None):
        self.inner = ScriptedVehicle.from_json(json.dumps(script))
        self.drop, self.duplicate, self.delay = set(drop), duplicate or {}, delay or {}
        self.queue: list[tuple[float, int, str, int, Event]] = []
        self.seq = 0
        for event in inject:
            self._push(event)
        self.seen: dict[tuple[str, EventKind], int] = {}
        self.acted: dict[tuple[ActionKind, str], int] = {}
        self.fail_act, self.interrupt_at = fail_act, interrupt_at

    def _push(self, event: Event) -> None:
        self.seq += 1
        heapq.heappush(self.queue, (event.t, 0, event.primitive, self.seq, event))

    def _rule(self, event: Event):
        n = self.seen.get((event.primitive, event.kind), 0) + 1
        key = (event.primitive, event.kind, n)
        return key in self.drop or key in self.duplicate or key in self.delay, key

    def _pull(self) -> None:
        """Take the script's next event into the queue if a rule is about it."""
        while (nxt := self.inner._next()) is not None:
            event = self.inner.pending[nxt[1]][0]
            faulted, key = self._rule(event)
            if not faulted:
                return
            self.inner.take_event()
            self.seen[key[:2]] = key[2]
            if key in self.duplicate:
                self._push(event)
                self._push(Event(event.t + self.duplicate[key], event.kind, event.primitive))
            elif key in self.delay:
                self._push(Event(event.t + self.delay[key], event.kind, event.primitive))

    def next_event_time(self):
        self._pull()
        times = [t for t in (self.inner.next_event_time(),
                             self.queue[0][0] if self.queue else None) if t is not None]
        return min(times) if times else None

    def take_event(self) -> Event:
        self._pull()
        t = self.inner.next_event_time()
        if self.queue and (t is None or self.queue[0][0] <= t):
            event = heapq.heappop(self.queue)[-1]
        else:
            event = self.inner.take_event()
            self.seen[(event.primitive, event.kind)] = self._rule(event)[1][2]
        if self.interrupt_at is not None and event.t >= self.interrupt_at:
            raise KeyboardInterrupt
        return event

    def act(self, action: Action) -> None:
        key = (action.kind, action.primitive)
        self.acted[key] = self.acted.get(key, 0) + 1
        if self.fail_act == (action.kind, action.primitive, self.acted[key]):
            raise RuntimeError("thruster driver: CAN bus timeout")
        self.inner.act(action)


FAULTS = check_source(MISSION, "faults.mcl")


def both(make_vehicle, **kw):
    """Run both engines, each with a fresh faulty vehicle; they must agree on everything."""
    results, vehicles = [], []
    for engine in engines(FAULTS):
        vehicles.append(make_vehicle())
        results.append(run(engine, vehicles[-1], **kw))
    a, b = results
    assert a.as_json() == b.as_json()
    assert [(e, r) for e, r in a.ignored] == [(e, r) for e, r in b.ignored]
    for v in vehicles:      # no primitive left enabled, whatever happened
        assert v.inner.enabled == set(), v.inner.enabled
    return a


CLEAN = None


def clean():
    global CLEAN
    CLEAN = CLEAN or both(lambda: Faulty(SCRIPT))
    return CLEAN


def without(r, ignored) -> dict:
    """The run's object with the ignored events taken out of its trace (they are traced)."""
    out = r.as_json()
    drop = [e.as_json() for e, _ in ignored]
    out["trace"] = [e for e in out["trace"] if e not in drop]
    return out


def test_the_clean_run():
    r = clean()
    assert r.outcome is Outcome.OK and r.time == 15 and not r.safe_stop and not r.ignored


def test_a_lost_reply_with_no_time_out_stalls_and_is_safely_stopped():
    r = both(lambda: Faulty(SCRIPT, drop={("Q", ACHIEVED, 1)}))
    assert r.outcome is Outcome.STALLED and r.time == 5
    assert any("Q: waits for the vehicle's 'achieved'" in w for w in r.waiting), r.waiting
    assert r.safe_stop == [SafeStop(5, ActionKind.DISABLE, "Q")]
    assert r.as_json()["safe_stop"] == [{"t": 5, "action": "disable", "primitive": "Q",
                                         "args": [], "safe_stop": True}]


def test_a_lost_reply_under_a_time_out_fails_the_task_and_the_mission_goes_on():
    r = both(lambda: Faulty(SCRIPT, drop={("P", ACHIEVED, 1)}))
    assert r.outcome is Outcome.OK and r.time == 15 and not r.safe_stop
    assert {"t": 10, "action": "disable", "primitive": "P", "args": []} in r.as_json()["trace"]
    # the time-out failed T: U(1) was skipped, U(2) ran from t=10
    enables = [e for e in r.as_json()["trace"] if e.get("action") == "enable"]
    assert [(e["t"], e["primitive"], e["args"]) for e in enables] == [(0, "P", [1]),
                                                                      (10, "Q", [2])]


def test_a_lost_acknowledgement_stalls_naming_it():
    r = both(lambda: Faulty(SCRIPT, drop={("P", ON, 1)}))
    # the time-out counts from 'on' (mcl.md): it never starts; the goal comes while P is off
    assert r.outcome is Outcome.STALLED and r.time == 5
    assert [(e.t, e.kind) for e, _ in r.ignored] == [(5, ACHIEVED)]
    assert any("P: waits for the vehicle's 'on'" in w for w in r.waiting), r.waiting
    assert [a.primitive for a in r.safe_stop] == ["P"]


def test_a_duplicated_event_is_ignored():
    r = both(lambda: Faulty(SCRIPT, duplicate={("P", ACHIEVED, 1): 0.5}))
    assert without(r, r.ignored) == clean().as_json()
    assert [(e.t, e.primitive, e.kind) for e, _ in r.ignored] == [(5.5, "P", ACHIEVED)]
    assert r.ignored[0][1] == "nothing waits for 'achieved' from 'P' now"


def test_a_late_event_after_the_time_out_is_ignored():
    r = both(lambda: Faulty(SCRIPT, delay={("P", ACHIEVED, 1): 7}))
    assert r.outcome is Outcome.OK and r.time == 15
    assert [(e.t, e.primitive) for e, _ in r.ignored] == [(12, "P")]
    assert {"t": 10, "action": "disable", "primitive": "P", "args": []} in r.as_json()["trace"]


def test_events_out_of_order_or_for_another_primitive_are_ignored():
    r = both(lambda: Faulty(SCRIPT, inject=[Event(0, ACHIEVED, "P"),      # before 'on'
                                            Event(3, ACHIEVED, "Q"),      # Q not enabled
                                            Event(4, EventKind.OFF, "P"),  # off, no disable
                                            Event(6, ACHIEVED, "Thruster")]))
    assert without(r, r.ignored) == clean().as_json()
    assert [r for _, r in r.ignored] == [
        "nothing waits for 'achieved' from 'P' now", "nothing waits for 'achieved' from 'Q' now",
        "nothing waits for 'off' from 'P' now", "no primitive 'Thruster' in this mission"]


def test_an_adapter_that_raises_stalls_the_run_saying_so():
    r = both(lambda: Faulty(SCRIPT, fail_act=(ActionKind.ENABLE, "Q", 1)))
    assert r.outcome is Outcome.STALLED and r.time == 5
    assert r.waiting[0] == ("the vehicle failed to carry out enable Q at t=5 s: "
                            "RuntimeError: thruster driver: CAN bus timeout")
    assert [a.primitive for a in r.safe_stop] == ["Q"]   # it may have half-started


def test_the_time_limit_cuts_the_run_short_at_the_limit_and_stops_the_vehicle():
    r = both(lambda: Faulty(SCRIPT), max_time=3)
    # not STALLED: P's report was due at 5 s; the run ends at the limit, not at the last event
    assert r.outcome is Outcome.TIMELIMIT and r.time == 3
    assert r.waiting[0] == "stopped at the time limit of 3 s; a vehicle event was due at t=5 s"
    assert [(a.t, a.primitive) for a in r.safe_stop] == [(3, "P")]


def test_a_time_out_due_past_the_limit_is_named():
    # P never answers: T's time-out (10 s after P's on) is what was still due
    r = both(lambda: Faulty(SCRIPT, drop={("P", ACHIEVED, 1)}), max_time=7)
    assert r.outcome is Outcome.TIMELIMIT and r.time == 7
    assert r.waiting[0].startswith("stopped at the time limit of 7 s; the time-out of ")
    assert r.waiting[0].endswith(" was due at t=10 s")
    assert [(a.t, a.primitive) for a in r.safe_stop] == [(7, "P")]


def test_a_stall_before_the_limit_is_still_a_stall():
    r = both(lambda: Faulty(SCRIPT, drop={("Q", ACHIEVED, 1)}), max_time=1000)
    assert r.outcome is Outcome.STALLED and r.time == 5


def test_the_time_limit_of_a_live_run_is_timelimit_at_the_limit(engine):
    ticks = iter(range(0, 10_000, 10))     # each reading of the clock 10 s later
    r = run_realtime(engine(FAULTS), MappedVehicle(MAPPING, QueueTransport()),
                     clock=lambda: float(next(ticks)), max_time=25)
    assert r.outcome is Outcome.TIMELIMIT and r.time == 25
    assert r.waiting[0] == "stopped at the time limit of 25 s"
    # (which primitive depends on how far the leaping clock took the mission)
    assert len(r.safe_stop) == 1 and r.safe_stop[0].t == 25


def test_each_outcome_has_an_exit_status_of_its_own():
    statuses = {o: o.exit_status for o in Outcome}
    assert statuses[Outcome.OK] == 0
    assert len(set(statuses.values())) == len(Outcome)
    # 2 is bad input, 3 a partial analysis: never an outcome; an interrupt is 128 + its
    # signal (SIGINT's 130 for the outcome alone)
    assert not set(statuses.values()) & {2, 3}
    assert statuses[Outcome.INTERRUPTED] == 128 + signal.SIGINT
    assert Run(Outcome.INTERRUPTED, 0.0, signum=signal.SIGTERM).exit_status == 143


@pytest.mark.parametrize("script, extra, outcome", [
    (SCRIPT, [], "OK"),
    ({"P": ["ok@5"], "Q": ["fail@5"]}, [], "FAIL"),
    ({"P": ["ok@5"], "Q": ["never"]}, [], "STALLED"),
    (SCRIPT, ["--max-time", "3"], "TIMELIMIT"),
])
def test_run_exits_with_its_outcomes_status(tmp_path, script, extra, outcome):
    mission, vehicle = tmp_path / "m.mcl", tmp_path / "v.json"
    mission.write_text(MISSION)
    vehicle.write_text(json.dumps(script))
    for engine in ("petri", "reference"):
        out = cli("run", mission, "--vehicle", vehicle, "--engine", engine, "--json", *extra)
        assert json.loads(out.stdout)["outcome"] == outcome, out.stderr
        assert out.returncode == Outcome(outcome).exit_status, out.stderr


def test_an_interrupt_stops_the_vehicle_before_it_is_passed_on(engine):
    vehicle = Faulty(SCRIPT, interrupt_at=6)
    seen = []
    with pytest.raises(KeyboardInterrupt):
        run(engine(FAULTS), vehicle, listener=seen.append)
    assert vehicle.inner.enabled == set()
    assert seen[-1] == SafeStop(10, ActionKind.DISABLE, "Q")   # the time reached


# -- unknown events: bad input, one message naming where it came from ------------------

def test_a_script_naming_an_unknown_kind_or_primitive_names_file_line_and_column(tmp_path):
    with pytest.raises(VehicleInputError) as e:
        ScriptedVehicle.from_json('{"P": ["ok@5",\n      "arrived@3"]}', "v.json")
    assert str(e.value).startswith("v.json:2:7: 'P' reply 2: 'arrived@3' is not a reply")
    script = tmp_path / "v.json"
    script.write_text('{"P": ["ok@5"],\n "Thruster": ["ok@1"]}')
    mission = tmp_path / "m.mcl"
    mission.write_text(MISSION)
    out = cli("run", mission, "--vehicle", script)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert out.stderr.startswith(f"{script}:2:2: the script scripts 'Thruster', which the "
                                 "mission does not use; it uses P, Q"), out.stderr


# -- a live link: garbled lines and a dropped link ---------------------------------------

MAPPING = VehicleMapping.from_json(json.dumps({"primitives": {
    name: {"enable": {"command": f"start_{name}", "x": "$1"},
           "disable": {"command": f"stop_{name}"},
           "events": {"achieved": {"primitive": name, "status": "done"}}}
    for name in ("P", "Q")}}))


def live(engine, *messages):
    """A real-time run against a link whose other side sends ``messages`` then whatever follows."""
    transport = QueueTransport()
    for m in messages:
        transport.inbox.put(m)
    # the clock stands still: only the link's messages (all queued already) make things happen
    result = run_realtime(engine, MappedVehicle(MAPPING, transport), clock=lambda: 0.0)
    return result, transport


def sent(transport) -> list[dict]:
    out = []
    while not transport.sent.empty():
        out.append(transport.sent.get_nowait())
    return out


def test_a_garbled_line_on_the_link_is_one_message_quoting_it_after_a_safe_stop(engine):
    transport = QueueTransport()
    transport.inbox.put(b'{"primitive": "P", "sta\n')
    with pytest.raises(VehicleInputError, match=r"""not a JSON object: '{"primitive": "P", "sta'"""):
        run_realtime(engine(FAULTS), MappedVehicle(MAPPING, transport), clock=lambda: 0.0)
    assert sent(transport) == [{"command": "start_P", "x": 1}, {"command": "stop_P"}]


def test_a_report_read_after_its_time_out_is_taken_after_it(engine):
    """A run late to read its link (its clock, an autopilot's, already past a time-out)
    fires the time-out before the report that came after it, as a run on time would."""
    transport = QueueTransport()
    transport.inbox.put({"primitive": "P", "status": "done"})
    transport.close()
    ticks = iter([0.0])     # the start at 0; every later reading 12 s, past T's 10 s
    result = run_realtime(engine(FAULTS), MappedVehicle(MAPPING, transport),
                          clock=lambda: next(ticks, 12.0))
    assert [(e.t, e.task) for e in result.timeouts] == [(10.0, "T")]
    # T failed: U(1) skipped, U(2) started; P's late report changed nothing
    assert sent(transport) == [{"command": "start_P", "x": 1}, {"command": "stop_P"},
                               {"command": "start_Q", "x": 2}]


def test_a_dropped_link_stalls_the_run_saying_so():
    results = []
    for engine in engines(FAULTS):
        transport = QueueTransport()
        transport.inbox.put({"primitive": "P", "status": "done"})
        transport.close()
        results.append(run_realtime(engine, MappedVehicle(MAPPING, transport),
                                    clock=lambda: 0.0))
        # the disable of P (T's own) and the enable of Q(1) went out before the link closed
        assert sent(transport) == [{"command": "start_P", "x": 1}, {"command": "stop_P"},
                                   {"command": "start_Q", "x": 1}]
    a, b = results
    assert a.as_json() == b.as_json() and a.outcome is Outcome.STALLED
    assert a.waiting[0] == ("the link to the vehicle was lost (waiting): the vehicle's bridge "
                            "closed the link")
    assert [s.primitive for s in a.safe_stop] == ["Q"]
    assert "safe stop: could not disable Q: LinkLost: the link is closed" in a.waiting


def test_a_lost_off_stalls_the_task_that_waits_for_it():
    r = both(lambda: Faulty(SCRIPT, drop={("P", EventKind.OFF, 1)}))
    assert r.outcome is Outcome.STALLED and r.time == 5
    assert "P: waits for the vehicle's 'off'" in r.waiting
    assert r.safe_stop == []     # the disable was sent already; only its answer was lost
