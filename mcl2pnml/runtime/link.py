"""The live link to a vehicle's bridge: JSON lines over TCP, bounded, with heartbeats and MACs.

Both ends use it: :class:`~mcl2pnml.runtime.bridge.TcpTransport` in
``mcl2pnml run --vehicle bridge:...`` and the bridge server of
``examples/bridges/bridge_server.py`` on the vehicle. A real vehicle's link
sets the bar (MAVLink: a 1 Hz heartbeat and a failsafe when it stops,
bounded frames, optional signing), so a link here:

* is **bounded**: a line is at most ``max_line`` bytes (read in chunks, so
  memory stays bounded before its newline), at most ``inbox`` messages wait
  to be handled, a send that cannot be written within ``send_timeout``
  seconds breaks the link;
* is **alive**: each end sends a heartbeat every ``heartbeat`` seconds, and
  no line for ``liveness`` seconds breaks the link;
* **opens within one deadline**: connecting, the TLS handshake and the
  hellos both ways (and, at the bridge, the controller's first
  authenticated line) share one :class:`Deadline` of ``connect_timeout``
  seconds (or the run's ``max_time``, when smaller), however the other end
  trickles its bytes: every read and write of the opening is given what is
  left of it, never a time-out of its own;
* may be **authenticated**: with a shared secret every line carries an
  HMAC-SHA256 over both ends' session nonces and its sequence number, so a
  line from anyone without the key, altered, replayed or reordered breaks
  the link and is never acted on; TLS (:func:`client_tls`, :func:`server_tls`)
  adds confidentiality and certificate checks where certificates are given.

One I/O thread per link owns the socket (non-blocking, a selector): the
caller's thread never blocks in the kernel, and every failure of the thread
(a closed or reset socket, a line too long, a bad MAC, any exception)
breaks the link with its reason; nothing dies silently.

The protocol, version 1 (docs/faults.md, "Trust and safety"), one JSON
object per line, UTF-8, ``\\n``-terminated; objects with the key ``link`` are
the link's own and never reach the vehicle or the mission:

* ``{"link": "hello", "protocol": 1, "auth": "none"|"hmac-sha256",
  "nonce": "<32 hex digits>", "heartbeat": SECONDS}``: each end's first line,
  never authenticated (it carries the nonces the MACs are over);
* ``{"link": "heartbeat"}``: every ``heartbeat`` seconds, from both ends;
* ``{"link": "error", "reason": "..."}``: why an end refuses or ends the
  link (one client at a time, a bad MAC...), then it closes;
* anything else: a command (to the bridge) or a message (from it).

With a secret, every line after the hello is an envelope
``{"seq": N, "body": "<the JSON object, as a string>", "mac": "<64 hex>"}``:
``seq`` counts 1, 2, 3... per direction, and ``mac`` is HMAC-SHA256 of the
key over ``mcl2pnml-link-1|DIRECTION|SENDER_NONCE|RECEIVER_NONCE|SEQ|BODY``
(DIRECTION ``c2s`` from the controller, ``s2c`` from the bridge).
"""
from __future__ import annotations

import enum
import hashlib
import hmac
import json
import os
import secrets
import selectors
import socket
import ssl
import stat
import threading
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import read_bytes
from mcl2pnml.core.settings import SettingError
from mcl2pnml.runtime.limits import HEARTBEAT, LIVENESS, MAX_LINE, SEND_TIMEOUT  # noqa: F401

PROTOCOL = 1
#: Messages received and not yet handled; the reading pauses while it is full.
INBOX = 1024
#: Lines waiting to be sent (each sender waits for its own: this bounds many senders).
OUTBOX = 64
#: Seconds for the whole opening of a link: connecting, the TLS handshake, the hellos
#: both ways (and at the bridge the first authenticated line), one deadline for all.
CONNECT_TIMEOUT = 10.0
#: A shared secret is at least this many bytes.
MIN_SECRET = 16
#: How much is read from the socket at a time: memory before a newline is bounded by it.
CHUNK = 16 * 1024
#: Characters of a bad line quoted in a message.
QUOTED = 80
#: Seconds a closing link reads and drops what the other end still sends.
DRAIN = 0.5

HEARTBEAT_LINE = {"link": "heartbeat"}
_MAC_LABEL = b"mcl2pnml-link-1"


class Side(enum.Enum):
    """Which end of the link: the direction label its MACs carry."""

    CONTROLLER = "c2s"     # mcl2pnml run
    BRIDGE = "s2c"         # the bridge server on the vehicle

    @property
    def other(self) -> "Side":
        return Side.BRIDGE if self is Side.CONTROLLER else Side.CONTROLLER


class LinkBroken(Exception):
    """The link cannot go on (closed, reset, silent, too long a line, a bad MAC...): why."""


class BadLine(Exception):
    """A line that is not a JSON object (the link goes on): what :func:`quote_line` says."""


@dataclass(frozen=True)
class LinkOptions:
    """The bounds and the security of a link: ``mcl2pnml run``'s link options, typed."""

    heartbeat: float = HEARTBEAT
    liveness: float = LIVENESS
    send_timeout: float = SEND_TIMEOUT
    max_line: int = MAX_LINE
    inbox: int = INBOX
    connect_timeout: float = CONNECT_TIMEOUT
    #: the run's time limit (``run --max-time``): the opening never waits longer
    max_time: float | None = None
    #: a file holding the shared secret (HMAC-SHA256 of every line)
    secret: Path | None = None
    #: TLS: the certificate authority to check the other end's certificate with,
    #: and this end's certificate and key
    tls_ca: Path | None = None
    tls_cert: Path | None = None
    tls_key: Path | None = None

    @property
    def opening(self) -> float:
        """Seconds the whole opening may take: ``connect_timeout``, or ``max_time`` if smaller."""
        return self.connect_timeout if self.max_time is None else \
            max(0.0, min(self.connect_timeout, self.max_time))


@dataclass(frozen=True)
class Deadline:
    """A moment on the monotonic clock by which a wait must end, and the bound it came from.

    One deadline covers a whole exchange: each read or write is given what is
    left of it (:meth:`left`), so a peer that trickles a byte every few seconds
    cannot stretch the exchange past the bound, as a time-out per read would let it.
    """

    at: float
    seconds: float

    @classmethod
    def after(cls, seconds: float) -> "Deadline":
        return cls(time.monotonic() + seconds, seconds)

    def left(self) -> float:
        """Seconds left, never negative."""
        return max(0.0, self.at - time.monotonic())

    def passed(self) -> bool:
        return time.monotonic() >= self.at


def quote_line(line: bytes | str, why: str = "") -> str:
    """The bad-line message's tail: the line quoted (cut at :data:`QUOTED` characters)."""
    text = line.decode("utf-8", "replace") if isinstance(line, bytes) else line
    text = text.rstrip("\r\n")
    shown = repr(text[:QUOTED]) + (f"... ({len(line):,} bytes)" if len(text) > QUOTED else "")
    return shown + (f" ({why})" if why else "")


def said(reason: Any) -> str:
    """The reason a peer gives, as our messages repeat it: text only, cut at
    :data:`QUOTED` characters, no control characters (no terminal escapes, no
    line breaks that would forge lines of our own log)."""
    text = reason if isinstance(reason, str) else json.dumps(reason)
    text = "".join(c if c.isprintable() else "?" for c in text[:QUOTED])
    return text + ("..." if len(reason if isinstance(reason, str) else text) > QUOTED else "")


def decode(line: bytes) -> dict[str, Any]:
    """The JSON object a line holds; :class:`BadLine` if it holds none."""
    try:
        obj = json.loads(line.decode("utf-8"))
    except UnicodeDecodeError:
        raise BadLine(quote_line(line, "not UTF-8")) from None
    except RecursionError:
        raise BadLine(quote_line(line, "nested too deeply")) from None
    except ValueError:      # JSONDecodeError, an integer of too many digits
        raise BadLine(quote_line(line)) from None
    if not isinstance(obj, dict):
        raise BadLine(quote_line(line))
    return obj


def encode(obj: Mapping[str, Any]) -> bytes:
    """One line: the object's JSON (ASCII, so that a line's length is its bytes) and ``\\n``."""
    return json.dumps(obj, separators=(",", ":")).encode() + b"\n"


def _end_gracefully(sock: socket.socket) -> None:
    """End our side after the last line sent (a FIN), then read and drop what the other
    end sent that was not read, for at most :data:`DRAIN` seconds: a socket closed with
    bytes unread makes the kernel reset the connection, and a reset can destroy the lines
    still on their way to the other end, the safe stop among them (a bridge that sent too
    long a line would never see its vehicle told to stop)."""
    try:
        sock.shutdown(socket.SHUT_WR)
        sock.settimeout(DRAIN / 10)
        deadline = time.monotonic() + DRAIN
        while time.monotonic() < deadline and sock.recv(CHUNK):
            pass
    except (OSError, ValueError):      # closed already, timed out, or a TLS end: done
        pass


class _Lines:
    """Cuts received bytes into lines, refusing a line past ``limit`` bytes before its end."""

    def __init__(self, limit: int):
        self.limit, self.buffer = limit, bytearray()

    def feed(self, data: bytes) -> list[bytes]:
        self.buffer += data
        *lines, rest = self.buffer.split(b"\n")
        if len(rest) > self.limit or any(len(line) > self.limit for line in lines):
            raise LinkBroken(f"a line longer than {self.limit:,} bytes (the line-length cap)")
        self.buffer = bytearray(rest)
        return [bytes(line) for line in lines]


# -- keys and certificates ----------------------------------------------------------------

def read_secret(path: Path, setting: str = "secret") -> bytes:
    """The shared secret in ``path``: a file only its owner can read, of 16 bytes or more
    (a file that cannot be read: a :class:`~mcl2pnml.core.settings.SettingError` of
    ``setting``)."""
    where = Location(str(path))
    key = read_bytes(path, "key file").strip()    # a regular file only: a FIFO would block
    try:
        mode = os.stat(path).st_mode
    except OSError as e:
        raise SettingError(setting, f"cannot read the key file {path}: {e.strerror or e}") \
            from None
    if mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise Mcl2PnmlError(f"the key file can be read by its group or others (mode "
                            f"{stat.filemode(mode)}); make it the owner's only: chmod 600 "
                            f"{path}", where)
    if len(key) < MIN_SECRET:
        raise Mcl2PnmlError(f"the key file holds {len(key)} bytes; a secret is at least "
                            f"{MIN_SECRET} (make one with: python -c \"import secrets; "
                            f"print(secrets.token_hex(32))\" > {path})", where)
    return key


def _tls_files(context: ssl.SSLContext, ca: Path | None, cert: Path | None,
               key: Path | None) -> ssl.SSLContext:
    for setting, path, load in (("tls_ca", ca, lambda: context.load_verify_locations(ca)),
                                ("tls_cert", cert,
                                 lambda: context.load_cert_chain(cert, key))):
        if path is None:
            continue
        try:
            load()
        except (OSError, ssl.SSLError) as e:
            raise SettingError(setting, f"cannot use {path}: "
                                        f"{getattr(e, 'reason', None) or e}") from None
    return context


def client_tls(options: LinkOptions) -> ssl.SSLContext | None:
    """The controller's TLS: the bridge's certificate checked against ``tls_ca`` (None: no TLS)."""
    if options.tls_ca is None:
        if options.tls_cert or options.tls_key:
            raise SettingError("tls_cert" if options.tls_cert else "tls_key",
                               "TLS needs --tls-ca, the authority that signed the bridge's "
                               "certificate (--tls-cert and --tls-key are this end's own)")
        return None
    if (options.tls_cert is None) != (options.tls_key is None):
        raise SettingError("tls_key" if options.tls_cert else "tls_cert",
                           "a certificate goes with its key: give both --tls-cert and --tls-key")
    context = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)      # checks certificate and host name
    context.minimum_version = ssl.TLSVersion.TLSv1_2
    return _tls_files(context, options.tls_ca, options.tls_cert, options.tls_key)


def server_tls(cert: Path, key: Path, ca: Path | None = None) -> ssl.SSLContext:
    """The bridge's TLS: its certificate; with ``ca``, clients must show one it signed."""
    context = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    context.minimum_version = ssl.TLSVersion.TLSv1_2
    if ca is not None:
        context.verify_mode = ssl.CERT_REQUIRED
    return _tls_files(context, ca, cert, key)


def parse_address(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (a name, an IPv4 address, or an IPv6 one in brackets) as (host, port)."""
    valid = "write HOST:PORT, as localhost:7777, 192.168.1.5:7777 or [::1]:7777"
    host, sep, port = text.rpartition(":")
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    elif ":" in host:
        raise SettingError("connect", f"'{text}': an IPv6 address goes in brackets; {valid}")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise SettingError("connect", f"'{text}' is not an address; {valid} (a port from "
                                      "1 to 65535)")
    return host, int(port)


def connect(host: str, port: int, deadline: Deadline) -> socket.socket:
    """A TCP connection to ``host:port`` made before ``deadline``: each of the host's
    addresses is tried in turn with what is left of it (:class:`TimeoutError` once it
    has passed; the last address's :class:`OSError` if none answers)."""
    error: OSError = TimeoutError(f"no connection within {deadline.seconds:g} s")
    for family, kind, proto, _, address in _resolve(host, port, deadline):
        if deadline.passed():
            raise TimeoutError(f"no connection within {deadline.seconds:g} s")
        sock = socket.socket(family, kind, proto)
        try:
            sock.settimeout(max(deadline.left(), 1e-3))    # 0 would make it non-blocking
            sock.connect(address)
            return sock
        except OSError as e:
            sock.close()
            error = e
    raise error


def _resolve(host: str, port: int, deadline: Deadline) -> list[tuple]:
    """``host``'s addresses, asked of the resolver in a thread of its own, so that a
    resolver that does not answer cannot hold the caller past ``deadline``
    (:class:`TimeoutError`; the thread, a daemon, ends when the resolver gives up)."""
    found: list[Any] = []
    done = threading.Event()

    def ask() -> None:
        try:
            found.append(socket.getaddrinfo(host, port, type=socket.SOCK_STREAM))
        except OSError as e:
            found.append(e)
        finally:
            done.set()
    threading.Thread(target=ask, daemon=True, name=f"resolving {host[:40]}").start()
    if not done.wait(deadline.left()):
        raise TimeoutError(f"no address for {host} within {deadline.seconds:g} s")
    if isinstance(found[0], OSError):
        raise found[0]
    return found[0]


def tls_handshake(sock: socket.socket, context: ssl.SSLContext, deadline: Deadline, *,
                  server_side: bool = False, server_hostname: str | None = None) -> ssl.SSLSocket:
    """``sock`` wrapped in TLS, its handshake done before ``deadline`` whatever the pace of
    the other end's bytes (non-blocking, each wait given what is left); :class:`TimeoutError`
    once it has passed, an :class:`ssl.SSLError` for a handshake that fails."""
    tls = context.wrap_socket(sock, server_side=server_side, server_hostname=server_hostname,
                              do_handshake_on_connect=False)
    tls.setblocking(False)
    with selectors.DefaultSelector() as selector:
        while True:
            try:
                tls.do_handshake()
                return tls
            except ssl.SSLWantReadError:
                wanted = selectors.EVENT_READ
            except ssl.SSLWantWriteError:
                wanted = selectors.EVENT_WRITE
            if deadline.passed():
                raise TimeoutError(f"no TLS handshake within {deadline.seconds:g} s")
            selector.register(tls, wanted)
            selector.select(deadline.left())
            selector.unregister(tls)


# -- the link -----------------------------------------------------------------------------

class _Out:
    """A line to send, and whether it was written (or why not)."""

    def __init__(self, body: Mapping[str, Any], sealed: bool):
        self.body, self.sealed, self.done, self.error = body, sealed, threading.Event(), None


class Link:
    """One end of the protocol over a connected socket (see the module's documentation).

    :meth:`handshake` exchanges the hellos, :meth:`start` starts the I/O
    thread; then :meth:`send` and :meth:`receive` from any thread, each
    bounded in time, and :meth:`close`. ``peer`` names the other end in
    messages ("the vehicle's bridge").
    """

    def __init__(self, sock: socket.socket, side: Side, options: LinkOptions,
                 secret: bytes | None = None, peer: str = "the other end"):
        self.sock, self.side, self.options = sock, side, options
        self.secret, self.peer = secret, peer
        self.nonce = secrets.token_hex(16)
        self.peer_nonce = ""
        self.sent_seq = self.received_seq = 0
        self.lines = _Lines(options.max_line)
        self.inbox: deque[dict[str, Any] | BadLine] = deque()
        self.outbox: deque[_Out] = deque()
        self.cond = threading.Condition()
        self.broken: str | None = None          # why receiving is over
        self.dead: str | None = None            # why sending is over
        self.last_heard = time.monotonic()
        self.early = b""                        # what came after the hello, with it
        self.backlog: deque[bytes] = deque()    # lines of the last chunk, for a full inbox
        self.wake_r, self.wake_w = socket.socketpair()
        self.stopping = False
        self.thread: threading.Thread | None = None

    # -- the hellos, before the thread starts (blocking, within one deadline)

    def hello(self) -> dict[str, Any]:
        return {"link": "hello", "protocol": PROTOCOL,
                "auth": "hmac-sha256" if self.secret else "none", "nonce": self.nonce,
                "heartbeat": self.options.heartbeat}

    def _line_by(self, deadline: Deadline, what: str) -> bytes:
        """The next line received (from :attr:`early` on), read before ``deadline``: each
        ``recv`` is given what is left of it, so a trickling peer cannot stretch it."""
        buffer = self.early
        try:
            while b"\n" not in buffer:
                if len(buffer) > self.options.max_line:
                    raise LinkBroken(f"{self.peer} sent {what} longer than "
                                     f"{self.options.max_line:,} bytes (the line-length cap)")
                if deadline.passed():
                    raise TimeoutError
                self.sock.settimeout(max(deadline.left(), 1e-3))
                data = self.sock.recv(CHUNK)
                if not data:
                    raise LinkBroken(f"{self.peer} closed the link before {what}")
                buffer += data
        except (socket.timeout, TimeoutError):
            raise LinkBroken(f"no {what} from {self.peer} within {deadline.seconds:g} s (the "
                             "bound on opening the link)") from None
        except OSError as e:
            raise LinkBroken(f"the link failed during the hello: {e.strerror or e}") from None
        first, _, self.early = buffer.partition(b"\n")
        return first

    def handshake(self, deadline: Deadline | None = None) -> None:
        """Send our hello and check the other end's, both before ``deadline`` (by default
        the options' :attr:`~LinkOptions.opening` from now); :class:`LinkBroken` says what
        went wrong.

        The caller then tells the other end why (:meth:`refuse`) and closes.
        """
        deadline = deadline or Deadline.after(self.options.opening)
        try:
            if deadline.passed():
                raise TimeoutError
            self.sock.settimeout(max(deadline.left(), 1e-3))   # sendall: a total time-out
            self.sock.sendall(encode(self.hello()))
        except (socket.timeout, TimeoutError):
            raise LinkBroken(f"could not send our hello to {self.peer} within "
                             f"{deadline.seconds:g} s (the bound on opening the link)") from None
        except OSError as e:
            raise LinkBroken(f"the link failed during the hello: {e.strerror or e}") from None
        first = self._line_by(deadline, "hello")
        try:
            hello = decode(first)
        except BadLine as e:
            raise LinkBroken(f"{self.peer} does not speak the link protocol {PROTOCOL}: its "
                             f"first line is {e}") from None
        if hello.get("link") == "error":
            raise LinkBroken(f"{self.peer} refused the link: {said(hello.get('reason'))}")
        if hello.get("link") != "hello" or hello.get("protocol") != PROTOCOL:
            raise LinkBroken(f"{self.peer} does not speak the link protocol {PROTOCOL}: its "
                             f"first line is {quote_line(first)}")
        mine = self.hello()["auth"]
        if hello.get("auth") != mine:
            why = (f"{self.peer} authenticates its lines (give --secret)" if mine == "none" else
                   f"{self.peer} does not authenticate its lines (it has no --secret)")
            raise LinkBroken(why)
        nonce, period = hello.get("nonce"), hello.get("heartbeat")
        if not (isinstance(nonce, str) and len(nonce) == 32
                and all(c in "0123456789abcdef" for c in nonce)):
            raise LinkBroken(f"{self.peer}'s hello has no nonce of 32 hex digits")
        if not isinstance(period, (int, float)) or isinstance(period, bool) or period <= 0 \
                or period >= self.options.liveness:
            raise LinkBroken(f"{self.peer} sends a heartbeat every {period} s, not within the "
                             f"liveness time-out of {self.options.liveness:g} s; give a "
                             "longer --liveness")
        self.peer_nonce = nonce
        self.last_heard = time.monotonic()

    def authenticated(self, deadline: Deadline) -> None:
        """Read the other end's first line after the hellos, before ``deadline``, and check
        its MAC (with a secret; without one, any line of the protocol): the bridge serves a
        controller only once it has shown it holds the key, so that a connection without it
        never takes the bridge's one place. A command in that line is kept for the
        caller; :class:`LinkBroken` if the line is late, unauthenticated or an error."""
        line = self._line_by(deadline, "first line after the hello")
        self.last_heard = time.monotonic()
        try:
            body = self._open(line) if self.secret else decode(line)
        except BadLine as e:
            raise LinkBroken(f"{self.peer} sent a first line that is not a JSON object: "
                             f"{e}") from None
        kind = body.get("link")
        if kind == "error":
            raise LinkBroken(f"{self.peer} ended the link: {said(body.get('reason'))}")
        if kind is None:
            self._deliver(body)

    def refuse(self, reason: str) -> None:
        """Tell the other end why the link ends (best effort, bounded), before closing it."""
        try:
            self.sock.settimeout(min(1.0, self.options.send_timeout))
            self.sock.sendall(encode({"link": "error", "reason": reason}))
        except (OSError, ValueError):
            pass       # it is gone already: the reason cannot reach it

    # -- MACs

    def _mac(self, side: Side, sender: str, receiver: str, seq: int, body: bytes) -> str:
        data = b"|".join([_MAC_LABEL, side.value.encode(), sender.encode(), receiver.encode(),
                          str(seq).encode(), body])
        return hmac.new(self.secret, data, hashlib.sha256).hexdigest()

    def _seal(self, body: Mapping[str, Any]) -> bytes:
        if not self.secret:
            return encode(body)
        self.sent_seq += 1
        text = json.dumps(body, separators=(",", ":"))
        mac = self._mac(self.side, self.nonce, self.peer_nonce, self.sent_seq, text.encode())
        return encode({"seq": self.sent_seq, "body": text, "mac": mac})

    def _open(self, line: bytes) -> dict[str, Any]:
        """The body of an authenticated line; :class:`LinkBroken` unless it is the next one."""
        try:
            envelope = decode(line)
        except BadLine as e:
            raise LinkBroken(f"{self.peer} sent a line without a MAC: {e}") from None
        if envelope.get("link") == "error":    # unauthenticated: it can only end the link
            raise LinkBroken(f"{self.peer} ended the link: {said(envelope.get('reason'))} "
                             "(an unauthenticated line)")
        seq, body, mac = envelope.get("seq"), envelope.get("body"), envelope.get("mac")
        if not (isinstance(seq, int) and isinstance(body, str) and isinstance(mac, str)):
            raise LinkBroken(f"{self.peer} sent a line without a MAC: {quote_line(line)}")
        expected = self._mac(self.side.other, self.peer_nonce, self.nonce, seq, body.encode())
        if not hmac.compare_digest(mac, expected):
            raise LinkBroken(f"line {seq} from {self.peer} failed authentication (a bad MAC: "
                             "another secret, or altered on the way)")
        if seq != self.received_seq + 1:
            raise LinkBroken(f"line {seq} from {self.peer} is replayed or out of order "
                             f"(expected line {self.received_seq + 1})")
        self.received_seq = seq
        return decode(body.encode())

    # -- the I/O thread

    def start(self) -> None:
        self.sock.setblocking(False)
        self.thread = threading.Thread(target=self._run, daemon=True,
                                       name=f"link to {self.peer}")
        self.thread.start()

    def _run(self) -> None:
        try:
            self._loop()
        except BaseException as e:     # never silent: whatever it is ends the link, said
            self._break(f"the link failed: {type(e).__name__}: {e}", sending=True)

    def _loop(self) -> None:
        self._received(self.early)
        selector = selectors.DefaultSelector()
        selector.register(self.wake_r, selectors.EVENT_READ)
        registered = 0
        pending, current = b"", None
        beat = time.monotonic()              # the first heartbeat at once
        tls = isinstance(self.sock, ssl.SSLSocket)
        while not self.stopping:
            self._take_backlog()
            now = time.monotonic()
            if not pending and self.dead is None:
                with self.cond:
                    current = self.outbox.popleft() if self.outbox else None
                    self.cond.notify_all()        # room in the outbox
                if current is not None:
                    pending = self._seal(current.body) if current.sealed else encode(current.body)
                elif now >= beat:
                    pending, beat = self._seal(HEARTBEAT_LINE), now + self.options.heartbeat
            reading = self.broken is None and not self.backlog
            wanted = (selectors.EVENT_READ if reading else 0) | \
                (selectors.EVENT_WRITE if pending and self.dead is None else 0)
            if wanted != registered:
                if registered:
                    selector.modify(self.sock, wanted) if wanted else \
                        selector.unregister(self.sock)
                else:
                    selector.register(self.sock, wanted)
                registered = wanted
            # a full inbox is polled: the caller empties it without waking us
            timeout = max(0.0, beat - now) if not pending and self.dead is None else None
            if self.backlog and self.broken is None:
                timeout = 0.05
            if tls and reading and self.sock.pending():
                timeout = 0.0
            ready = selector.select(timeout)
            events = 0
            for key, mask in ready:
                if key.fileobj is self.wake_r:
                    self.wake_r.recv(4096)
                else:
                    events |= mask
            if reading and (events & selectors.EVENT_READ or (tls and self.sock.pending())):
                self._read()
            if events & selectors.EVENT_WRITE and pending:
                pending = self._write(pending)
                if not pending and current is not None:
                    current.done.set()
                    current = None
            if self.dead is not None and current is not None:
                current.error = self.dead
                current.done.set()
                current, pending = None, b""

    def _read(self) -> None:
        try:
            data = self.sock.recv(CHUNK)
        except (ssl.SSLWantReadError, ssl.SSLWantWriteError, BlockingIOError):
            return
        except (ssl.SSLZeroReturnError, ssl.SSLEOFError):
            data = b""
        except OSError as e:
            self._break(f"the link was reset: {e.strerror or e}", sending=True)
            return
        if not data:
            self._break(f"{self.peer} closed the link")
            return
        self._received(data)

    def _received(self, data: bytes) -> None:
        try:
            lines = self.lines.feed(data)
        except LinkBroken as e:
            self._break(f"{self.peer} sent {e}")
            return
        self.backlog.extend(lines)
        self._take_backlog()

    def _take_backlog(self) -> None:
        """Take the lines received while the inbox has room (it holds at most ``inbox``)."""
        while self.backlog and self.broken is None and len(self.inbox) < self.options.inbox:
            self._take(self.backlog.popleft())

    def _take(self, line: bytes) -> None:
        self.last_heard = time.monotonic()
        try:
            body = self._open(line) if self.secret else decode(line)
        except LinkBroken as e:
            self._break(str(e))
            return
        except BadLine as e:
            self._deliver(e)
            return
        kind = body.get("link")
        if kind is None:
            self._deliver(body)
        elif kind == "error":
            self._break(f"{self.peer} ended the link: {said(body.get('reason'))}")
        elif kind != "heartbeat":
            self._deliver(BadLine(quote_line(line, f"unknown link line '{kind}'")))

    def _deliver(self, item: dict[str, Any] | BadLine) -> None:
        with self.cond:
            self.inbox.append(item)
            self.cond.notify_all()

    def _write(self, pending: bytes) -> bytes:
        try:
            n = self.sock.send(pending)
        except (ssl.SSLWantReadError, ssl.SSLWantWriteError, BlockingIOError):
            return pending
        except OSError as e:
            # a reset is a reset whichever end of the socket notices it first
            said = "the link was reset: " if isinstance(e, ConnectionResetError) else ""
            self._break(f"{said}cannot send to {self.peer}: {e.strerror or e}", sending=True)
            return b""
        return pending[n:]

    def _break(self, reason: str, sending: bool = False) -> None:
        """End receiving (and sending, if ``sending``) for ``reason``; the first reason stays."""
        with self.cond:
            if self.broken is None:
                self.broken = reason
            if sending and self.dead is None:
                self.dead = reason
                for out in self.outbox:
                    out.error = reason
                    out.done.set()
                self.outbox.clear()
            self.cond.notify_all()

    # -- the caller's side

    def send(self, body: Mapping[str, Any], sealed: bool = True) -> None:
        """Send one object, written within ``send_timeout`` seconds, or :class:`LinkBroken`.

        ``sealed=False``: without a MAC even with a secret, for the one line
        an end that cannot trust the other any more still sends, the error
        line saying why (the other end reads it as the end of the link only).
        """
        out = _Out(body, sealed)
        timeout = self.options.send_timeout
        deadline = time.monotonic() + timeout
        late = (f"could not send to {self.peer} within {timeout:g} s (the send time-out): "
                "it does not read")
        with self.cond:
            while self.dead is None and len(self.outbox) >= OUTBOX:
                if not self.cond.wait(max(0.0, deadline - time.monotonic())):
                    break
            if self.dead is not None:
                raise LinkBroken(f"the link is closed: {self.dead}")
            if len(self.outbox) >= OUTBOX:
                self._break(late, sending=True)
                raise LinkBroken(late)
            self.outbox.append(out)
        try:
            self.wake_w.send(b"\0")
        except OSError:
            pass        # the wake-up pipe is full: the thread is awake already
        if not out.done.wait(max(0.0, deadline - time.monotonic())):
            self._break(late, sending=True)
            raise LinkBroken(late)
        if out.error is not None:
            raise LinkBroken(f"the link is closed: {out.error}")

    def receive(self, timeout: float | None) -> dict[str, Any] | None:
        """The next message; None after ``timeout`` s; :class:`LinkBroken` or :class:`BadLine`.

        Messages that came before the link broke are still given first.
        Heartbeats are no messages; no line at all for ``liveness`` seconds
        breaks the link.
        """
        deadline = None if timeout is None else time.monotonic() + timeout
        with self.cond:
            while True:
                if self.inbox:
                    item = self.inbox.popleft()
                    if isinstance(item, BadLine):
                        raise item
                    return item
                if self.broken is not None:
                    raise LinkBroken(self.broken)
                now = time.monotonic()
                silent = now - self.last_heard
                if silent >= self.options.liveness:
                    self.broken = (f"no line from {self.peer} for {silent:.1f} s: no heartbeat "
                                   f"within the liveness time-out of {self.options.liveness:g} s")
                    raise LinkBroken(self.broken)
                if deadline is not None and now >= deadline:
                    return None
                wait = self.options.liveness - silent
                self.cond.wait(wait if deadline is None else min(wait, deadline - now))

    def close(self) -> None:
        """Stop the thread and close the socket (what was sent is written already)."""
        self.stopping = True
        try:
            self.wake_w.send(b"\0")
        except OSError:
            pass
        if self.thread is not None and self.thread is not threading.current_thread():
            self.thread.join(timeout=1.0)
        _end_gracefully(self.sock)
        for s in (self.sock, self.wake_r, self.wake_w):
            try:
                s.close()
            except OSError:
                pass
