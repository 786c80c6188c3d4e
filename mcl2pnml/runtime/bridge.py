"""Binding a mission's primitives to a real vehicle's architecture: the mapping file.

A vehicle's own software (ROS, MOOS-IvP, COLA2, a serial protocol...) does
not speak of "enable GoToWayPoint"; it has its own commands and messages.
A **mapping file** says, per primitive, which command an action becomes and
which incoming message is which event::

    {
      "vehicle": "ictineu",
      "primitives": {
        "GoToWayPoint": {
          "enable":  {"command": "goto", "args": {"x": "$1[0]", "y": "$1[1]", "z": "$1[2]"}},
          "disable": {"command": "goto_cancel"},
          "events":  {"achieved": {"message": "goto_status", "status": "reached"},
                      "failed":   {"message": "goto_status", "status": "aborted"}}
        }
      }
    }

``$1`` is the first argument of the enable action (``$1[0]`` its first
item); every other value is sent as written. An incoming message is an
event of a primitive when all the fields its rule names have the values it
gives; ``on`` and ``off`` default to the vehicle's acknowledgement of the
commands (rules ``"on"`` and ``"off"`` may say otherwise).

Commands and messages are JSON objects, one per line, over a
:class:`Transport`: standard streams, a TCP socket, or anything a bridge
provides. The bridge on the vehicle's side translates them to its
middleware; ``examples/bridges/`` has one for ROS 2 and one for MOOS-IvP.
"""
from __future__ import annotations

import json
import queue
import re
import socket
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from mcl2pnml.runtime.aal import Action, ActionKind, Event, EventKind, LinkLost, LiveVehicle, VehicleInputError
from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import read_text

_ARG = re.compile(r"^\$(\d+)((?:\[\d+\])*)$")


@dataclass(frozen=True)
class Rule:
    """An incoming message that means one event: the fields it must have."""

    kind: EventKind
    fields: Mapping[str, Any]

    def matches(self, message: Mapping[str, Any]) -> bool:
        return all(message.get(k) == v for k, v in self.fields.items())


@dataclass(frozen=True)
class Binding:
    """One primitive: the commands its actions become, the messages that are its events."""

    primitive: str
    enable: Mapping[str, Any]
    disable: Mapping[str, Any]
    rules: tuple[Rule, ...]
    acknowledged: frozenset[EventKind]   # on/off sent by us when the command is sent


class VehicleMapping:
    """A loaded mapping file (see the module's documentation)."""

    def __init__(self, vehicle: str, bindings: dict[str, Binding]):
        self.vehicle, self.bindings = vehicle, bindings

    @classmethod
    def from_json(cls, text: str, filename: str = "<mapping>") -> "VehicleMapping":
        def fail(message: str, line: int | None = None, column: int | None = None):
            return Mcl2PnmlError(message, Location(filename, line, column))
        try:
            data = json.loads(text)
        except json.JSONDecodeError as e:
            raise fail(f"not a mapping file: {e.msg}", e.lineno, e.colno) from None
        if not isinstance(data, dict) or not isinstance(data.get("primitives"), dict):
            raise fail('a mapping file is a JSON object with "primitives": '
                       '{"NAME": {"enable": ..., "disable": ..., "events": ...}}')
        bindings = {}
        kinds = {k.value: k for k in EventKind}
        for name, spec in data["primitives"].items():
            where = f"primitive '{name}'"
            if not isinstance(spec, dict):
                raise fail(f"{where}: an object with enable, disable and events")
            unknown = sorted(set(spec) - {"enable", "disable", "events"})
            if unknown:
                raise fail(f"{where}: unknown key '{unknown[0]}'; valid: enable, disable, events")
            for key in ("enable", "disable"):
                if not isinstance(spec.get(key), dict) or "command" not in spec[key]:
                    raise fail(f'{where}: "{key}" must be an object with a "command"')
            rules, acknowledged = [], {EventKind.ON, EventKind.OFF}
            for event, rule in (spec.get("events") or {}).items():
                if event not in kinds:
                    raise fail(f"{where}: unknown event '{event}'; valid: "
                               + ", ".join(kinds))
                if not isinstance(rule, dict) or not rule:
                    raise fail(f"{where}, event '{event}': the fields a message must have, "
                               'as {"message": "goto_status", "status": "reached"}')
                rules.append(Rule(kinds[event], dict(rule)))
                acknowledged.discard(kinds[event])
            for key in ("enable", "disable"):
                _check_placeholders(spec[key], fail, f"{where}, {key}")
            bindings[name] = Binding(name, spec["enable"], spec["disable"], tuple(rules),
                                     frozenset(acknowledged))
        return cls(str(data.get("vehicle", "vehicle")), bindings)

    @classmethod
    def load(cls, path: str | Path) -> "VehicleMapping":
        return cls.from_json(read_text(path, "mapping file"), str(path))

    def command(self, action: Action) -> dict[str, Any]:
        binding = self.bindings[action.primitive]
        spec = binding.enable if action.kind is ActionKind.ENABLE else binding.disable
        return _fill(spec, action.args)

    def event(self, message: Mapping[str, Any], t: float) -> Event | None:
        for binding in self.bindings.values():
            for rule in binding.rules:
                if rule.matches(message):
                    return Event(t, rule.kind, binding.primitive)
        return None


def _check_placeholders(spec: Any, fail, where: str) -> None:
    if isinstance(spec, str) and spec.startswith("$") and not _ARG.match(spec):
        raise fail(f"{where}: '{spec}' is not an argument; write $1, $1[0], $2 ...")
    if isinstance(spec, dict):
        for v in spec.values():
            _check_placeholders(v, fail, where)
    if isinstance(spec, list):
        for v in spec:
            _check_placeholders(v, fail, where)


def _fill(spec: Any, args: tuple) -> Any:
    """The command with ``$n`` (and ``$n[i]...``) replaced by the action's arguments."""
    if isinstance(spec, str):
        m = _ARG.match(spec)
        if not m:
            return spec
        value: Any = args[int(m.group(1)) - 1]
        for index in re.findall(r"\[(\d+)\]", m.group(2)):
            value = value[int(index)]
        return list(value) if isinstance(value, tuple) else value
    if isinstance(spec, dict):
        return {k: _fill(v, args) for k, v in spec.items()}
    if isinstance(spec, list):
        return [_fill(v, args) for v in spec]
    return spec


class Transport:
    """JSON objects out (commands) and in (messages), one per line."""

    def send(self, obj: Mapping[str, Any]) -> None:
        raise NotImplementedError

    def receive(self, timeout: float | None) -> dict[str, Any] | None:
        """The next message, or None if none came within ``timeout`` seconds."""
        raise NotImplementedError


class _Closed:
    """Put in the inbox when the link closes: what follows it can never come."""


class QueueTransport(Transport):
    """In memory: a bridge (or a test) reads ``sent`` and puts messages in ``inbox``.

    :meth:`close` (or a :class:`LinkLost`, or a line that is not a JSON object,
    put in the inbox) is how the other side's faults reach :meth:`receive`.
    """

    def __init__(self) -> None:
        self.sent: queue.Queue[dict[str, Any]] = queue.Queue()
        self.inbox: queue.Queue[Any] = queue.Queue()
        self.closed = False

    def send(self, obj: Mapping[str, Any]) -> None:
        if self.closed:
            raise LinkLost("the link is closed")
        self.sent.put(dict(obj))

    def close(self) -> None:
        """The other side hung up: pending messages are still read, then the link is lost."""
        self.inbox.put(_Closed())

    def receive(self, timeout: float | None) -> dict[str, Any] | None:
        try:
            item = self.inbox.get(timeout=timeout)
        except queue.Empty:
            return None
        if isinstance(item, _Closed):
            self.closed = True
            self.inbox.put(item)     # and for every later call
            raise LinkLost("the vehicle's bridge closed the link")
        if isinstance(item, (bytes, str)):   # a line received that is no message
            text = item.decode(errors="replace") if isinstance(item, bytes) else item
            raise VehicleInputError(f"the vehicle's bridge sent a line that is not a JSON "
                                    f"object: {text.rstrip()!r}")
        return item


class TcpTransport(QueueTransport):
    """JSON lines over TCP to the bridge on the vehicle (``host:port``)."""

    def __init__(self, address: str):
        super().__init__()
        host, _, port = address.rpartition(":")
        try:
            self.sock = socket.create_connection((host or "localhost", int(port)), timeout=10)
        except (OSError, ValueError) as e:
            raise Mcl2PnmlError(f"cannot connect to the vehicle's bridge at {address}: {e}") \
                from None
        self.sock.settimeout(None)    # the reader blocks until a line or the end
        self.file = self.sock.makefile("rwb")
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        try:
            for line in self.file:
                try:
                    obj = json.loads(line)
                except (json.JSONDecodeError, UnicodeDecodeError):
                    obj = None
                self.inbox.put(obj if isinstance(obj, dict) else line)
        except OSError:
            pass          # reset by the peer: the same as a close
        self.close()

    def send(self, obj: Mapping[str, Any]) -> None:
        if self.closed:
            raise LinkLost("the link is closed")
        try:
            self.file.write(json.dumps(dict(obj)).encode() + b"\n")
            self.file.flush()
        except OSError as e:
            self.closed = True
            raise LinkLost(f"cannot send to the vehicle's bridge: {e.strerror or e}") from None


class MappedVehicle(LiveVehicle):
    """A real vehicle behind a mapping file and a transport, in real time.

    Not a virtual-time :class:`~mcl2pnml.runtime.aal.Vehicle`: its events come when
    they come. :func:`~mcl2pnml.runtime.engine.run_realtime` drives it.
    """

    def __init__(self, mapping: VehicleMapping, transport: Transport):
        self.mapping, self.transport = mapping, transport
        self.primitives = frozenset(mapping.bindings)
        self.pending: list[Event] = []        # acknowledgements we give ourselves
        self.unmatched: list[dict[str, Any]] = []

    def act(self, action: Action) -> None:
        self.transport.send(self.mapping.command(action))
        binding = self.mapping.bindings[action.primitive]
        ack = EventKind.ON if action.kind is ActionKind.ENABLE else EventKind.OFF
        if ack in binding.acknowledged:
            self.pending.append(Event(action.t, ack, action.primitive))

    def wait_event(self, timeout: float | None, clock) -> Event | None:
        """The next event, stamped with ``clock()`` when it came; None after ``timeout`` s.

        A message that no rule of the mapping matches is kept in
        :attr:`unmatched` (the live log shows it) and waiting goes on.
        """
        if self.pending:
            return self.pending.pop(0)
        message = self.transport.receive(timeout)
        if message is None:
            return None
        event = self.mapping.event(message, clock())
        if event is None:
            self.unmatched.append(message)
        return event
