"""The fake autopilot of tests/support/fake_autopilot.py on a serial line: a pseudo-terminal.

``mcl2pnml run --vehicle mavlink --connect serial:/dev/pts/N:115200`` opens
the terminal's slave end with pyserial, as it would open a USB autopilot's
``/dev/ttyACM0``; the fake speaks on the master end. The fake serves a
socket it accepts from a listener; here the listener hands it an adapter
that reads and writes the master's descriptor with a socket's calls
(``recv`` with its time-out, ``sendall``, ``shutdown``), so that the fake
itself is the one the TCP tests fly against.

The slave end is kept open by the test and set raw from the start: bytes
the fake writes before the run opens the device are neither echoed nor
translated (pyserial sets it raw again when it opens it).
"""
from __future__ import annotations

import errno
import os
import select
import socket
import threading
import time
import tty
from unittest import mock

import fake_autopilot
from fake_autopilot import FakeAutopilot

#: The longest a write to the terminal may wait for the reader to take bytes (s): until
#: the run has opened the device, the fake's first messages fill the terminal's buffer
#: (a loaded machine may take seconds to start the command).
WRITE_WITHIN = 60.0


class PtyConnection:
    """The master end of a pseudo-terminal, with the calls the fake makes on its socket."""

    def __init__(self, master: int):
        self.master = master
        self.timeout: float | None = None
        self.closed = threading.Event()

    def settimeout(self, timeout: float | None) -> None:
        self.timeout = timeout

    def setsockopt(self, *args) -> None:
        """A socket option (TCP_NODELAY): a terminal has none."""

    def recv(self, size: int) -> bytes:
        # in slices, so that a shutdown from another thread ends the wait soon
        deadline = None if self.timeout is None else time.monotonic() + self.timeout
        while not select.select([self.master], [], [], 0.1)[0]:
            if self.closed.is_set():
                return b""
            if deadline is not None and time.monotonic() > deadline:
                raise socket.timeout("timed out")
        try:
            return os.read(self.master, size)
        except OSError as e:       # EIO: no slave end open any more
            if e.errno == errno.EIO:
                return b""
            raise

    def sendall(self, data: bytes) -> None:
        view, deadline = memoryview(data), time.monotonic() + WRITE_WITHIN
        while view:
            if self.closed.is_set():
                raise OSError(errno.EBADF, "closed")
            _, ready, _ = select.select([], [self.master], [], 0.1)
            if ready:
                view = view[os.write(self.master, view):]
            elif time.monotonic() > deadline:
                raise socket.timeout("the serial line took nothing")

    def shutdown(self, how: int) -> None:
        self.closed.set()

    def close(self) -> None:
        self.closed.set()


class PtyListener:
    """A listener whose one connection is the terminal's master end."""

    def __init__(self, master: int):
        self.connection = PtyConnection(master)

    def settimeout(self, timeout: float | None) -> None:
        """Accepting never waits: the terminal is there already."""

    def getsockname(self) -> tuple[str, int]:
        return ("pty", 0)

    def accept(self) -> tuple[PtyConnection, None]:
        return self.connection, None

    def shutdown(self, how: int) -> None:
        self.connection.closed.set()

    def close(self) -> None:
        self.connection.closed.set()


class _SocketModule:
    """The fake's ``socket`` while it is built: its listener is the terminal's."""

    def __init__(self, listener: PtyListener):
        self._listener = listener

    def create_server(self, *args, **kwargs) -> PtyListener:
        return self._listener

    def __getattr__(self, name: str):
        return getattr(socket, name)


class PtyAutopilot(FakeAutopilot):
    """:class:`FakeAutopilot` on a pseudo-terminal; ``address`` is ``serial:SLAVE:BAUD``."""

    def __init__(self, *args, baud: int = 115200, **kwargs):
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.device = os.ttyname(self.slave)
        with mock.patch.object(fake_autopilot, "socket", _SocketModule(PtyListener(self.master))):
            super().__init__(*args, **kwargs)
        self.address = f"serial:{self.device}:{baud}"

    def close(self) -> None:
        super().close()
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass
