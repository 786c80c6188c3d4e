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
:class:`Transport`: in memory, or a TCP socket (optionally TLS) to the
bridge on the vehicle, through the bounded, heartbeating and optionally
authenticated link of :mod:`mcl2pnml.runtime.link`. The bridge translates
them to its middleware; ``examples/bridges/`` has one for ROS 2 and one for
MOOS-IvP. A mapping is checked against every argument the mission may send
before anything is sent (:meth:`MappedVehicle.check_enables`): a ``$1[7]``
where ``$1`` has three items is refused then, not blamed on the vehicle later.
"""
from __future__ import annotations

import queue
import re
import socket
import ssl
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping

from mcl2pnml.runtime.aal import (Action, ActionKind, Event, EventKind, LinkLost, LiveVehicle,
                                  VehicleInputError, _strings)
from mcl2pnml.core.errors import LISTED, Location, Mcl2PnmlError, visible
from mcl2pnml.core.files import read_text
from mcl2pnml.core.jsontext import parse_located, without_bom
from mcl2pnml.runtime.link import (BadLine, Deadline, Link, LinkBroken, LinkOptions, Side,
                                   client_tls, connect, parse_address, quote_line, read_secret,
                                   tls_handshake)

#: Messages from the vehicle that no rule matched, kept for the log (the oldest dropped first).
UNMATCHED_KEPT = 100

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
    #: where each placeholder ($1[0]...) of the enable is written: (line, column)
    placeholders: Mapping[str, tuple[int, int]] | None = None


#: A mapping file may have at most this many bytes (checked before it is read).
MAX_MAPPING = 1 << 20


class VehicleMapping:
    """A loaded mapping file (see the module's documentation)."""

    def __init__(self, vehicle: str, bindings: dict[str, Binding], filename: str = "<mapping>"):
        self.vehicle, self.bindings, self.filename = vehicle, bindings, filename

    @classmethod
    def from_json(cls, text: str, filename: str = "<mapping>") -> "VehicleMapping":
        # the one JSON reader of configuration files: a key given twice, NaN, a file cut
        # short are refused at their line and column; each fault below is at its value
        data, where = parse_located(text, filename, "a mapping file")

        def fail(message: str, *path) -> Mcl2PnmlError:
            return Mcl2PnmlError(message, where(path))
        if not isinstance(data, dict) or not isinstance(data.get("primitives"), dict):
            raise fail('a mapping file is a JSON object with "primitives": '
                       '{"NAME": {"enable": ..., "disable": ..., "events": ...}}',
                       *(("primitives",) if isinstance(data, dict) and "primitives" in data
                         else ()))
        bindings = {}
        kinds = {k.value: k for k in EventKind}
        for name, spec in data["primitives"].items():
            where_ = f"primitive '{visible(name)}'"
            at = ("primitives", name)
            if not isinstance(spec, dict):
                raise fail(f"{where_}: an object with enable, disable and events", *at)
            unknown = sorted(set(spec) - {"enable", "disable", "events"})
            if unknown:
                raise fail(f"{where_}: unknown key '{visible(unknown[0])}'; valid: enable, "
                           "disable, events", *at, unknown[0])
            for key in ("enable", "disable"):
                if not isinstance(spec.get(key), dict) or "command" not in spec[key]:
                    raise fail(f'{where_}: "{key}" must be an object with a "command"',
                               *at, *((key,) if key in spec else ()))
            events = spec.get("events") or {}
            if not isinstance(events, dict):
                raise fail(f'{where_}: "events" is an object of event: the fields a message '
                           "must have", *at, "events")
            rules, acknowledged = [], {EventKind.ON, EventKind.OFF}
            for event, rule in events.items():
                if event not in kinds:
                    raise fail(f"{where_}: unknown event '{visible(event)}'; valid: "
                               + ", ".join(kinds), *at, "events", event)
                if not isinstance(rule, dict) or not rule:
                    raise fail(f"{where_}, event '{event}': the fields a message must have, "
                               'as {"message": "goto_status", "status": "reached"}',
                               *at, "events", event)
                rules.append(Rule(kinds[event], dict(rule)))
                acknowledged.discard(kinds[event])
            for key in ("enable", "disable"):
                _check_placeholders(spec[key], fail, f"{where_}, {key}", (*at, key))
            bindings[name] = Binding(name, spec["enable"], spec["disable"], tuple(rules),
                                     frozenset(acknowledged), _placed(without_bom(text), name))
        return cls(str(data.get("vehicle", "vehicle")), bindings, filename)

    @classmethod
    def load(cls, path: str | Path) -> "VehicleMapping":
        """The mapping file at ``path`` (at most :data:`MAX_MAPPING` bytes, UTF-8)."""
        return cls.from_json(read_text(path, "mapping file", MAX_MAPPING), str(path))

    def command(self, action: Action) -> dict[str, Any]:
        """The command of ``action``; a placeholder its arguments do not have is an error.

        The error (a :class:`VehicleInputError`: the vehicle's side is
        misdescribed) names the mapping file, where the placeholder is
        written, the primitive, and the placeholders these arguments have.
        """
        binding = self.bindings[action.primitive]
        spec = binding.enable if action.kind is ActionKind.ENABLE else binding.disable
        try:
            return _fill(spec, action.args)
        except _Missing as e:
            placeholder = e.args[0]
            line, column = (binding.placeholders or {}).get(placeholder, (None, None))
            shown = ", ".join(repr(a) for a in action.args) or "none"
            valid = _valid_placeholders(action.args)
            listed = ", ".join(valid[:LISTED]) + (" ..." if len(valid) > LISTED else "")
            raise VehicleInputError(
                f"primitive '{action.primitive}', {action.kind.value}: '{placeholder}' is not "
                f"in its arguments ({shown}); valid: {listed or 'no placeholder'}",
                Location(self.filename, line, column)) from None

    def event(self, message: Mapping[str, Any], t: float) -> Event | None:
        for binding in self.bindings.values():
            for rule in binding.rules:
                if rule.matches(message):
                    return Event(t, rule.kind, binding.primitive)
        return None


def _check_placeholders(spec: Any, fail, where: str, path: tuple = ()) -> None:
    """Every ``$...`` string in ``spec`` is an argument (``$1``, ``$1[0]``); ``fail(message,
    *path)`` is raised at the first that is not, ``path`` being where ``spec`` stands."""
    stack = [(path, spec)]      # a loop, not recursion: a hostile file may nest deep
    while stack:
        at, value = stack.pop()
        if isinstance(value, str) and value.startswith("$") and not _ARG.match(value):
            raise fail(f"{where}: '{visible(value)}' is not an argument; write $1, $1[0], "
                       "$2 ...", *at)
        items = value.items() if isinstance(value, dict) else \
            enumerate(value) if isinstance(value, list) else ()
        stack.extend(reversed([((*at, k), v) for k, v in items]))


def _placed(text: str, primitive: str) -> dict[str, tuple[int, int]]:
    """Where each placeholder of ``primitive``'s entry is written: the first after its name."""
    strings = list(_strings(text))
    start = next((i for i, (s, _, _) in enumerate(strings) if s == primitive), len(strings))
    found: dict[str, tuple[int, int]] = {}
    for s, line, column in strings[start + 1:]:
        if s in found or not isinstance(s, str) or not _ARG.match(s):
            continue
        found[s] = (line, column)
    return found


class _Missing(Exception):
    """A placeholder the action's arguments do not have (the placeholder)."""


def _valid_placeholders(args: tuple) -> list[str]:
    """Every placeholder these arguments have: $1, $1[0], $1[0][1]..."""
    out: list[str] = []

    def walk(name: str, value: Any) -> None:
        out.append(name)
        if isinstance(value, (tuple, list)):
            for i, item in enumerate(value):
                walk(f"{name}[{i}]", item)
    for n, arg in enumerate(args, 1):
        walk(f"${n}", arg)
    return out


def _fill(spec: Any, args: tuple) -> Any:
    """The command with ``$n`` (and ``$n[i]...``) replaced by the action's arguments."""
    if isinstance(spec, str):
        m = _ARG.match(spec)
        if not m:
            return spec
        n = int(m.group(1))
        if not 1 <= n <= len(args):
            raise _Missing(spec)
        value: Any = args[n - 1]
        for index in re.findall(r"\[(\d+)\]", m.group(2)):
            if not isinstance(value, (tuple, list)) or int(index) >= len(value):
                raise _Missing(spec)
            value = value[int(index)]
        return list(value) if isinstance(value, tuple) else value
    if isinstance(spec, dict):
        return {k: _fill(v, args) for k, v in spec.items()}
    if isinstance(spec, list):
        return [_fill(v, args) for v in spec]
    return spec


class Transport:
    """JSON objects out (commands) and in (messages), one per line."""

    def open(self) -> None:
        """Connect, once the mission is checked: nothing is sent before (default: nothing)."""

    def hang_up(self) -> None:
        """Our side ends the link, after the safe stop (default: nothing)."""

    def send(self, obj: Mapping[str, Any]) -> None:
        raise NotImplementedError

    def receive(self, timeout: float | None) -> dict[str, Any] | None:
        """The next message, or None if none came within ``timeout`` seconds."""
        raise NotImplementedError


def _not_json(why: str) -> VehicleInputError:
    return VehicleInputError(f"the vehicle's bridge sent a line that is not a JSON object: {why}")


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
            raise _not_json(quote_line(item))
        return item


class TcpTransport(Transport):
    """JSON lines over TCP (or TLS) to the bridge on the vehicle, through a :class:`Link`.

    ``address`` is ``HOST:PORT`` (a name, IPv4, or ``[IPv6]``); ``options``
    bound the link and give its secret and certificates, all checked here,
    before :meth:`open` connects. Every failure of the link reaches
    :meth:`send` and :meth:`receive` as a :class:`LinkLost` (closed, reset,
    silent, a send that does not complete, a line too long, a bad MAC) or a
    :class:`VehicleInputError` (a line that is not a JSON object).
    """

    def __init__(self, address: str, options: LinkOptions | None = None):
        self.address, self.options = address, options or LinkOptions()
        self.host, self.port = parse_address(address)
        self.secret = read_secret(self.options.secret) if self.options.secret else None
        self.tls = client_tls(self.options)
        self.link: Link | None = None

    def open(self) -> None:
        """Connect, the TLS handshake and the hellos, all within one deadline: the link's
        ``opening`` (``connect_timeout``, or the run's ``max_time`` when smaller), however
        slowly the bridge sends its bytes."""
        if self.link is not None:
            return
        sock = link = None
        deadline = Deadline.after(self.options.opening)
        try:
            sock = connect(self.host, self.port, deadline)
            if self.tls is not None:
                sock = tls_handshake(sock, self.tls, deadline, server_hostname=self.host)
            link = Link(sock, Side.CONTROLLER, self.options, self.secret,
                        peer="the vehicle's bridge")
            try:
                link.handshake(deadline)
            except LinkBroken as e:
                link.refuse(str(e))
                raise
        except (OSError, LinkBroken) as e:
            if link is not None:
                link.close()
            elif sock is not None:
                sock.close()
            if isinstance(e, ssl.SSLCertVerificationError):
                why = f"TLS: {e.verify_message} ({e.reason})"
            elif isinstance(e, (TimeoutError, socket.timeout)):
                why = (f"no answer within {deadline.seconds:g} s (the bound on opening the "
                       "link)")
            else:
                why = e if isinstance(e, LinkBroken) else (
                    getattr(e, "reason", None) or e.strerror or e)
            raise Mcl2PnmlError(f"cannot connect to the vehicle's bridge at {self.address}: "
                                f"{why}") from None
        link.start()
        self.link = link

    def hang_up(self) -> None:
        if self.link is not None:
            self.link.close()

    def send(self, obj: Mapping[str, Any]) -> None:
        if self.link is None:
            raise LinkLost("the link is not open")
        try:
            self.link.send(dict(obj))
        except LinkBroken as e:
            raise LinkLost(str(e)) from None

    def receive(self, timeout: float | None) -> dict[str, Any] | None:
        if self.link is None:
            raise LinkLost("the link is not open")
        try:
            return self.link.receive(timeout)
        except LinkBroken as e:
            raise LinkLost(str(e)) from None
        except BadLine as e:
            raise _not_json(str(e)) from None


class MappedVehicle(LiveVehicle):
    """A real vehicle behind a mapping file and a transport, in real time.

    Not a virtual-time :class:`~mcl2pnml.runtime.aal.Vehicle`: its events come when
    they come. :func:`~mcl2pnml.runtime.engine.run_realtime` drives it.
    """

    def __init__(self, mapping: VehicleMapping, transport: Transport,
                 kept: int = UNMATCHED_KEPT):
        self.mapping, self.transport = mapping, transport
        self.primitives = frozenset(mapping.bindings)
        self.pending: list[Event] = []        # acknowledgements we give ourselves
        #: the last ``kept`` messages no rule matched, and how many older ones were dropped
        self.unmatched: deque[dict[str, Any]] = deque(maxlen=kept)
        self.dropped = 0

    def check_enables(self, enables: Mapping[str, Iterable[tuple]] | None) -> None:
        """Refuse, before anything is sent, a mapping the mission's arguments do not fit.

        ``enables`` holds every argument tuple each primitive may be
        enabled with (:meth:`~mcl2pnml.runtime.engine.Engine.enable_arguments`;
        None: the engine cannot tell, and each command is checked as it is made).
        """
        for primitive, argument_tuples in sorted((enables or {}).items()):
            if primitive in self.mapping.bindings:
                for args in argument_tuples:
                    self.mapping.command(Action(0.0, ActionKind.ENABLE, primitive, tuple(args)))

    def open(self) -> None:
        self.transport.open()

    def close(self) -> None:
        self.transport.hang_up()

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
            if len(self.unmatched) == self.unmatched.maxlen:
                self.dropped += 1
            self.unmatched.append(message)
        return event
