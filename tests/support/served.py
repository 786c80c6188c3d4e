"""``mcl2pnml ARGS`` started in the background as a process of its own, forked from the
tests' command server (tests/support/forkcli.py) instead of a fresh interpreter.

What :class:`subprocess.Popen` gives a test that waits for a command while doing something
else (a flight the test disturbs mid-run): ``pid``, ``poll``, ``wait`` with a bound,
``kill``; the command's standard streams are the files given. A fresh interpreter would
import the command's modules again for each run (half a second of CPU each); under
``MCL2PNML_TEST_FRESH=1`` it is one all the same.
"""
from __future__ import annotations

import array
import json
import os
import signal
import socket
import subprocess
import sys

import forkcli


class Served:
    """A command running through the server: its process id, and its status once it ended."""

    def __init__(self, args, cwd, stdout, stderr):
        self.args = [str(a) for a in args]
        self.returncode: int | None = None
        self._fresh: subprocess.Popen | None = None
        path = forkcli.server()
        if path is None:
            self._fresh = subprocess.Popen([sys.executable, "-m", "mcl2pnml", *self.args],
                                           cwd=cwd, stdin=subprocess.DEVNULL, stdout=stdout,
                                           stderr=stderr)
            self.pid = self._fresh.pid
            return
        self._conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self._conn.connect(path)
        request = json.dumps({"args": self.args, "cwd": os.path.abspath(cwd),
                              "env": dict(os.environ)}).encode()
        with open(os.devnull, "rb") as null:
            fds = [null.fileno(), stdout.fileno(), stderr.fileno()]
            self._conn.sendmsg([request], [(socket.SOL_SOCKET, socket.SCM_RIGHTS,
                                            array.array("i", fds))])
        self.pid = self._status(None)

    def _status(self, timeout: float | None) -> int:
        """The server's next word: the command's process id, then its exit status."""
        self._conn.settimeout(timeout)
        data = b""
        while len(data) < forkcli.STATUS.size:
            more = self._conn.recv(forkcli.STATUS.size - len(data))
            if not more:
                raise ConnectionError("the command's server ended without its status")
            data += more
        first, code = forkcli.STATUS.unpack(data)
        return first or code

    def poll(self) -> int | None:
        try:
            return self.wait(0)
        except subprocess.TimeoutExpired:
            return None

    def wait(self, timeout: float | None = None) -> int:
        if self.returncode is None:
            if self._fresh is not None:
                self.returncode = self._fresh.wait(timeout)
                return self.returncode
            try:
                self.returncode = self._status(timeout if timeout is None or timeout > 0
                                               else 1e-6)
            except (socket.timeout, BlockingIOError):
                raise subprocess.TimeoutExpired(self.args, timeout) from None
            self._conn.close()
        return self.returncode

    def kill(self) -> None:
        """SIGKILL to the command and what it started (its process group)."""
        if self._fresh is not None:
            self._fresh.kill()
        elif self.returncode is None:
            try:
                os.killpg(self.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
