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

Run:  python examples/bridges/bridge_server.py --port 7777 --middleware fake
"""
from __future__ import annotations

import argparse
import json
import socketserver
import threading
import time
from typing import Callable


class FakeMiddleware:
    """A vehicle that does whatever it is told, ``delay`` seconds later.

    It answers the commands of ``examples/bridges/sim_mapping.json``: each
    ``start_<primitive>`` with ``{"message": "status", "primitive": ...,
    "status": "done"}``; stop commands need no answer (the mapping lets
    mcl2pnml acknowledge them).
    """

    def __init__(self, reply: Callable[[dict], None], delay: float = 0.05):
        self.reply, self.delay = reply, delay

    def command(self, cmd: dict) -> None:
        name = cmd.get("command", "")
        if name.startswith("start_"):
            primitive = name[len("start_"):]
            threading.Timer(self.delay, self.reply,
                            [{"message": "status", "primitive": primitive,
                              "status": "done"}]).start()


MIDDLEWARES = {"fake": FakeMiddleware}


def serve(port: int, middleware: str = "fake", delay: float = 0.05,
          ready: threading.Event | None = None) -> socketserver.TCPServer:
    """Serve one connection at a time on ``port``; returns the server (serve_forever runs)."""

    class Handler(socketserver.StreamRequestHandler):
        def handle(self) -> None:
            lock = threading.Lock()

            def reply(message: dict) -> None:
                with lock:
                    try:
                        self.wfile.write(json.dumps(message).encode() + b"\n")
                        self.wfile.flush()
                    except OSError:
                        pass   # the mission has ended and hung up
            if middleware == "fake":
                mw = FakeMiddleware(reply, delay)
            elif middleware == "ros2":
                from ros2_bridge import Ros2Middleware
                mw = Ros2Middleware(reply)
            else:
                from moos_bridge import MoosMiddleware
                mw = MoosMiddleware(reply)
            for line in self.rfile:
                mw.command(json.loads(line))

    socketserver.TCPServer.allow_reuse_address = True
    server = socketserver.ThreadingTCPServer(("127.0.0.1", port), Handler)   # port 0: any
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    if ready is not None:
        ready.set()
    return server


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, default=7777)
    parser.add_argument("--middleware", choices=["fake", "ros2", "moos"], default="fake")
    parser.add_argument("--delay", type=float, default=1.0)
    args = parser.parse_args()
    serve(args.port, args.middleware, args.delay)
    print(f"bridge ({args.middleware}) on port {args.port}; Ctrl-C to stop")
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
