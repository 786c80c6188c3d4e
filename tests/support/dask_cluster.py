"""A real Dask cluster for the campaign tests: ``dask scheduler`` and ``dask worker``s, each a
process of its own on loopback, as a user starts them.

The scheduler takes a free port and logs to a file, which the tests read to
know what it has seen (a worker registered, a client connected); every wait
is bounded in wall seconds, generously (the machine may be loaded). Each
process leads a process group of its own, killed when the cluster's block
ends, whatever the ending (a scheduler frozen by SIGSTOP is killed as well).
"""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

#: Wall seconds for the scheduler to listen, and for its workers to register.
START_BOUND = 60.0
#: The ``dask`` command of the interpreter running the tests.
DASK = str(Path(sys.executable).with_name("dask"))


def free_port() -> int:
    """A TCP port on loopback that nothing listens on (just now)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@dataclass
class Cluster:
    """A running scheduler (its address, process and log) and its workers."""

    address: str
    scheduler: subprocess.Popen
    log: Path
    workers: list[subprocess.Popen] = field(default_factory=list)

    def count(self, text: str) -> int:
        """How many of the scheduler's log lines hold ``text``."""
        return sum(text in line for line in self.log.read_text(errors="replace").splitlines())

    def wait_for(self, text: str, times: int = 1, within: float = START_BOUND) -> None:
        """Until the scheduler has logged ``text`` ``times`` times (an AssertionError after
        ``within`` seconds)."""
        deadline = time.monotonic() + within
        while self.count(text) < times:
            assert time.monotonic() < deadline, f"the scheduler never said {text!r}: " \
                                                f"{self.log.read_text()[-2000:]}"
            assert self.scheduler.poll() is None, self.log.read_text()[-2000:]
            time.sleep(0.1)

    def signal(self, signum: int) -> None:
        os.killpg(self.scheduler.pid, signum)


def _start(*args: str, log) -> subprocess.Popen:
    return subprocess.Popen([DASK, *args], stdout=log, stderr=log, start_new_session=True)


@contextmanager
def started(folder: Path, workers: int = 2) -> Iterator[Cluster]:
    """A scheduler on a free port and ``workers`` single-threaded workers, each registered
    before the block runs; every process killed when it ends."""
    port = free_port()
    log = folder / f"scheduler-{port}.log"
    procs: list[subprocess.Popen] = []
    with open(log, "wb") as out, open(os.devnull, "wb") as null:
        try:
            procs.append(_start("scheduler", "--host", "127.0.0.1", "--port", str(port),
                                "--no-dashboard", log=out))
            cluster = Cluster(f"tcp://127.0.0.1:{port}", procs[0], log)
            cluster.wait_for("Scheduler at:")
            for _ in range(workers):
                # no nanny: a second process per worker that imports Dask again, and
                # restarts nothing a test asks of it (a killed worker's group is killed)
                procs.append(_start("worker", cluster.address, "--nthreads", "1",
                                    "--nworkers", "1", "--no-nanny", "--no-dashboard",
                                    "--local-directory", str(folder), log=null))
            cluster.workers = procs[1:]
            cluster.wait_for("Register worker", workers)
            yield cluster
        finally:
            for p in procs:
                if p.poll() is None:
                    os.killpg(p.pid, signal.SIGKILL)
                    p.wait(10)
