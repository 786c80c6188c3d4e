"""The vehicle side of a bridge: JSON-lines commands in, middleware messages out.

``mcl2pnml run MISSION.mcl --vehicle bridge:MAPPING.json --connect HOST:PORT``
connects to this server, on the vehicle's computer. The server passes each
command (as the mapping file wrote it) to a *middleware* and each message of
the middleware back, one JSON object per line. Three middlewares:

* ``fake``: answers every command itself, after a delay (``--delay``), as a
  vehicle that always succeeds; for trying a mapping file without a vehicle
  (the tests use it);
* ``ros2``: publishes commands on ROS 2 topics and forwards status topics
  (needs ``rclpy``; see ``ros2_bridge.py``);
* ``moos``: posts commands to a MOOSDB and forwards its mail (needs
  ``pymoos``; see ``moos_bridge.py``).

The link is :mod:`mcl2pnml.runtime.link`'s (mcl2pnml must be installed on
the vehicle's computer too): hellos, a heartbeat every ``--heartbeat``
seconds both ways, a line-length cap, and, with ``--secret FILE`` (the same
file as ``mcl2pnml run --secret``), every line authenticated both ways;
``--tls-cert``/``--tls-key`` add TLS, ``--tls-ca`` also requires the
controller's certificate. Who may command the vehicle:

* **one client at a time**: a second connection is refused with an
  ``{"link": "error", "reason": ...}`` line and closed; a connection takes
  the place only once it has opened (TLS, its hello and, with ``--secret``,
  a first line MAC'd with the key), within one deadline of ``connect_timeout``
  (10 s) however slowly it sends; at most ``OPENING`` (8) connections open at
  once, a ninth is dropped at once, so one without the key, trickling its
  hello, never keeps the controller out;
* the server listens on the loopback interface unless ``--host`` says
  otherwise; on any other interface, anyone who can reach the port can
  command the vehicle unless ``--secret`` (or ``--tls-ca``) is given;
* a line that is not a JSON object is answered with an error line and
  dropped; a line too long, a bad MAC, a silent or closed client end the
  client's link, never the server. When the controller's link is lost, the
  middleware's ``link_lost`` stops what it was told to do (the failsafe).

Run:  python examples/bridges/bridge_server.py --port 7777 --middleware fake
"""
from __future__ import annotations

import argparse
import socket
import socketserver
import sys
import threading
import time
from pathlib import Path
from typing import Callable

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.settings import SettingError
from mcl2pnml.runtime.link import (HEARTBEAT, LIVENESS, MAX_LINE, SEND_TIMEOUT, BadLine,
                                   Deadline, Link, LinkBroken, LinkOptions, Side, encode,
                                   read_secret, server_tls, tls_handshake)


class FakeMiddleware:
    """A vehicle that does whatever it is told, ``delay`` seconds later.

    It answers the commands of ``examples/bridges/sim_mapping.json``: each
    ``start_<primitive>`` with ``{"message": "status", "primitive": ...,
    "status": "done"}``; stop commands need no answer (the mapping lets
    mcl2pnml acknowledge them). ``commands`` lists what it was told.
    """

    def __init__(self, reply: Callable[[dict], None], delay: float = 0.05):
        self.reply, self.delay = reply, delay
        self.commands: list[dict] = []
        self.timers: list[threading.Timer] = []

    def command(self, cmd: dict) -> None:
        self.commands.append(cmd)
        name = cmd.get("command", "")
        if isinstance(name, str) and name.startswith("start_"):
            primitive = name[len("start_"):]
            timer = threading.Timer(self.delay, self.reply,
                                    [{"message": "status", "primitive": primitive,
                                      "status": "done"}])
            timer.daemon = True
            self.timers.append(timer)
            timer.start()

    def link_lost(self) -> None:
        """The controller is gone: nothing it asked for goes on."""
        for timer in self.timers:
            timer.cancel()


MIDDLEWARES = {"fake": FakeMiddleware}


class BridgeServer(socketserver.ThreadingTCPServer):
    """The server: its options, the one client it serves, the commands its middlewares got."""

    daemon_threads = True
    allow_reuse_address = True

    def __init__(self, address: tuple[str, int], middleware: str, delay: float,
                 options: LinkOptions, secret: bytes | None, tls):
        # the family of the address given: an IPv6 host needs an IPv6 socket
        self.address_family = socket.getaddrinfo(address[0], address[1],
                                                 type=socket.SOCK_STREAM)[0][0]
        self.middleware, self.delay = middleware, delay
        self.options, self.secret, self.tls = options, secret, tls
        self.busy = threading.Lock()                # the one controller served
        self.opening = threading.BoundedSemaphore(OPENING)
        self.served: list[FakeMiddleware] = []     # the middlewares made, in order
        super().__init__(address, Handler)

    def free(self) -> bool:
        """Is no controller served (waiting :data:`RECONNECT_GRACE` for one closing)?"""
        if not self.busy.acquire(timeout=RECONNECT_GRACE):
            return False
        self.busy.release()
        return True

    def make_middleware(self, reply: Callable[[dict], None]):
        if self.middleware == "fake":
            return FakeMiddleware(reply, self.delay)
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        if self.middleware == "ros2":
            from ros2_bridge import Ros2Middleware
            return Ros2Middleware(reply)
        from moos_bridge import MoosMiddleware
        return MoosMiddleware(reply)


#: Seconds a new connection waits for the one being served to finish closing.
RECONNECT_GRACE = 1.0
#: Connections at most in their opening at once (the TLS handshake, the hellos, the first
#: authenticated line, each within the link's opening deadline); one more is dropped at once.
OPENING = 8


class Handler(socketserver.BaseRequestHandler):
    """One connection: refused if another is served, else its commands to the middleware.

    The one place (a controller at a time) is taken only once the connection
    has opened: its hello, and with ``--secret`` its first line, MAC'd with the
    key, all within one deadline (the link's ``connect_timeout``). Until then it
    holds one of :data:`OPENING` places, so a connection that trickles its bytes
    or has no key never keeps the controller out.
    """

    server: BridgeServer

    def handle(self) -> None:
        server = self.server
        if not server.opening.acquire(blocking=False):
            _drop(self.request, f"busy: {OPENING} connections are opening already")
            return
        try:
            link = self.open()
        finally:
            server.opening.release()
        if link is None:
            return
        # a controller reconnecting right after its link dropped may find the bridge
        # still closing the old one (its failsafe, the socket): it waits that long
        if not server.busy.acquire(timeout=RECONNECT_GRACE):
            link.refuse(BUSY)
            link.close()
            return
        try:
            self.serve(link)
        finally:
            server.busy.release()
            link.close()

    def open(self) -> Link | None:
        """The link opened within its deadline (TLS, hellos, the first authenticated line);
        None, the other end told why, if it is not."""
        server, sock = self.server, self.request
        deadline = Deadline.after(server.options.opening)
        if server.tls is not None:
            try:
                sock = tls_handshake(sock, server.tls, deadline, server_side=True)
            except (OSError, ValueError) as e:
                print(f"bridge: TLS refused {self.client_address}: {e}", file=sys.stderr)
                return None
        link = Link(sock, Side.BRIDGE, server.options, server.secret,
                    peer="the mission's controller")
        try:
            if not server.free():      # told at once: no hello to wait for
                raise LinkBroken(BUSY)
            link.handshake(deadline)
            if server.secret is not None:
                link.authenticated(deadline)
        except LinkBroken as e:
            print(f"bridge: {e}", file=sys.stderr)
            link.refuse(str(e))
            link.close()
            return None
        return link

    def serve(self, link: Link) -> None:
        link.start()

        def reply(message: dict) -> None:
            try:
                link.send(message)
            except LinkBroken:
                pass     # the controller is gone: link_lost has stopped the middleware
        mw = self.server.make_middleware(reply)
        self.server.served.append(mw)
        try:
            while True:
                try:
                    command = link.receive(None)
                except BadLine as e:        # answered, and the link goes on
                    reply({"link": "error", "reason": f"not a JSON object: {e}"})
                    continue
                try:
                    mw.command(command)
                except Exception as e:      # the middleware's own failure: said, not fatal
                    reply({"link": "error", "reason": f"cannot carry out {command!r}: "
                                                      f"{type(e).__name__}: {e}"})
        except LinkBroken as e:
            print(f"bridge: {e}", file=sys.stderr)
            try:        # the controller is told why (unauthenticated: it may not share our key)
                link.send({"link": "error", "reason": str(e)}, sealed=False)
            except LinkBroken:
                pass    # it is gone
        finally:
            lost = getattr(mw, "link_lost", None)
            if lost is not None:
                lost()


#: Why a connection is refused while a controller is served.
BUSY = "busy: this bridge serves one client at a time, and one is connected"


def _drop(sock: socket.socket, reason: str) -> None:
    """Tell a connection why it is dropped (one line, bounded in time), before it is closed."""
    try:
        sock.settimeout(1.0)
        sock.sendall(encode({"link": "error", "reason": reason}))
    except OSError:
        pass        # it is gone already


def serve(port: int, middleware: str = "fake", delay: float = 0.05,
          ready: threading.Event | None = None, *, host: str = "127.0.0.1",
          options: LinkOptions | None = None, secret: bytes | None = None,
          tls=None) -> BridgeServer:
    """Serve one connection at a time on ``host:port`` (port 0: any); serve_forever runs."""
    server = BridgeServer((host, port), middleware, delay, options or LinkOptions(), secret,
                          tls)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    if ready is not None:
        ready.set()
    return server


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default="127.0.0.1",
                        help="the interface to listen on (default: loopback only)")
    parser.add_argument("--port", type=int, default=7777)
    parser.add_argument("--middleware", choices=["fake", "ros2", "moos"], default="fake")
    parser.add_argument("--delay", type=float, default=1.0)
    parser.add_argument("--secret", type=Path, help="the shared secret's file (mode 600)")
    parser.add_argument("--tls-cert", type=Path, help="this server's certificate (PEM)")
    parser.add_argument("--tls-key", type=Path, help="its private key (PEM)")
    parser.add_argument("--tls-ca", type=Path,
                        help="require a client certificate signed by this authority")
    parser.add_argument("--heartbeat", type=float, default=HEARTBEAT)
    parser.add_argument("--liveness", type=float, default=LIVENESS)
    parser.add_argument("--send-timeout", type=float, default=SEND_TIMEOUT)
    parser.add_argument("--max-line", type=int, default=MAX_LINE)
    args = parser.parse_args(argv)
    try:
        secret = read_secret(args.secret) if args.secret else None
        tls = None
        if args.tls_cert or args.tls_key or args.tls_ca:
            if not (args.tls_cert and args.tls_key):
                parser.error("TLS needs both --tls-cert and --tls-key")
            tls = server_tls(args.tls_cert, args.tls_key, args.tls_ca)
        options = LinkOptions(heartbeat=args.heartbeat, liveness=args.liveness,
                              send_timeout=args.send_timeout, max_line=args.max_line)
        server = serve(args.port, args.middleware, args.delay, host=args.host,
                       options=options, secret=secret, tls=tls)
    except (Mcl2PnmlError, OSError) as e:
        print(f"bridge: {e}", file=sys.stderr)
        return 2
    except SettingError as e:   # a key or certificate file refused: named as our option
        print(f"bridge: --{e.setting.replace('_', '-')}: {e.message}", file=sys.stderr)
        return 2
    print(f"bridge ({args.middleware}) on {args.host} port {server.server_address[1]}"
          f"{', authenticated' if secret else ''}{', TLS' if tls else ''}; Ctrl-C to stop",
          flush=True)
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
