"""`show --live`: the server's connections are bounded, and the log followed is the one file.

Served in this process (:func:`mcl2pnml.view.show.serve_live`) with short
bounds: a silent connection, or one trickling its request, is closed and its
thread ends; connections beyond the cap are closed at once, so idle ones
cannot grow the server's threads; a log swapped for a symbolic link to
another file (or for another file) stops the following, and nothing of the
other file reaches the page.
"""
from __future__ import annotations

import json
import os
import select
import socket
import threading
import time
import urllib.request
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import pytest

from mcl2pnml.language.compiler import compile_checked
from mcl2pnml.pipeline import check_source
from mcl2pnml.view.show import LiveLog, serve_live

from test_link_deadlines import hung_up, trickle

#: What a bounded wait may take past its bound on a loaded machine.
MARGIN = 20.0
IDLE, REQUEST, CONNECTIONS = 1.0, 3.0, 4

GOTO = """
primitive GoToWayPoint(waypoint);
task Go(wp) = AchieveGoal(GoToWayPoint(wp)) timeout 60;
mission { Go((1.0, 2.0, 3.0)); }
"""
LINES = [{"t": 0, "action": "enable", "primitive": "GoToWayPoint", "args": [[1.0, 2.0, 3.0]]},
         {"t": 1, "event": "on", "primitive": "GoToWayPoint"}]
SECRET = "root:x:0:0:SECRET-LINE-OF-ANOTHER-FILE"


@pytest.fixture(scope="module")
def net():
    return compile_checked(check_source(GOTO, "goto.mcl"))


@contextmanager
def served(net, log: Path, idle: float = IDLE) -> Iterator[str]:
    """``serve_live`` on ``log`` in a thread, with short bounds; its URL; stopped after."""
    stop, urls = threading.Event(), []
    got = threading.Event()
    thread = threading.Thread(target=serve_live, daemon=True, kwargs=dict(
        html="<!doctype html><title>live</title>", log=LiveLog(net, log), linger=60,
        ready=lambda url: (urls.append(url), got.set()), max_seconds=120, idle=idle,
        request=REQUEST, connections=CONNECTIONS, stop=stop))
    thread.start()
    assert got.wait(MARGIN)
    try:
        yield urls[0]
    finally:
        stop.set()
        thread.join(MARGIN)


def server_threads() -> int:
    """The threads serving a connection (socketserver names them by their function)."""
    return sum("process_request_thread" in t.name for t in threading.enumerate())


def connect(url: str) -> socket.socket:
    host, port = url.split("/")[2].split(":")
    return socket.create_connection((host, int(port)), timeout=MARGIN)


def log_answer(url: str, start: int = 0) -> dict:
    with urllib.request.urlopen(f"{url}log?from={start}", timeout=MARGIN) as answer:
        return json.loads(answer.read())


@pytest.mark.timeout(90)
def test_idle_and_trickling_connections_are_closed_and_their_threads_end(net, tmp_path):
    with served(net, tmp_path / "run.jsonl") as url:
        silent = connect(url)
        trickler = connect(url)
        stop = threading.Event()
        # a byte every half second: never silent for IDLE
        threading.Thread(target=trickle, args=(trickler, b"GET /" + b"x" * 1000, IDLE / 2, stop),
                         daemon=True).start()
        try:
            assert hung_up(silent, IDLE + MARGIN)
            assert hung_up(trickler, REQUEST + MARGIN)
        finally:
            stop.set()
            silent.close()
            trickler.close()
        deadline = time.monotonic() + MARGIN
        while server_threads() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert server_threads() == 0
        assert log_answer(url)["entries"] == []          # and it serves on


@pytest.mark.timeout(90)
def test_idle_connections_past_the_cap_are_closed_at_once(net, tmp_path):
    # idle connections the server keeps for long: those it closes are the ones past its cap
    with served(net, tmp_path / "run.jsonl", idle=120.0) as url:
        socks = [connect(url) for _ in range(CONNECTIONS * 3)]
        closed: set[socket.socket] = set()
        try:
            deadline = time.monotonic() + MARGIN
            while len(closed) < len(socks) - CONNECTIONS and time.monotonic() < deadline:
                ready, _, _ = select.select([s for s in socks if s not in closed], [], [],
                                            max(0.0, deadline - time.monotonic()))
                for s in ready:
                    try:
                        if not s.recv(65536):
                            closed.add(s)
                    except ConnectionResetError:
                        closed.add(s)
            assert len(closed) == len(socks) - CONNECTIONS
            assert server_threads() == CONNECTIONS      # one a connection kept, no more
        finally:
            for s in socks:
                s.close()


def write_log(path: Path, entries: list[dict]) -> None:
    path.write_text("".join(json.dumps(e) + "\n" for e in entries))


def other_file(tmp_path: Path) -> Path:
    """A file the page must never see a byte of (a line of /etc/passwd, a JSON line)."""
    secret = tmp_path / "secret.txt"
    secret.write_text(json.dumps({"t": 2, "note": SECRET}) + "\n" + SECRET + "\n")
    return secret


@pytest.mark.timeout(90)
@pytest.mark.parametrize("swap", ["symlink", "rename"])
def test_a_log_swapped_while_followed_stops_the_following_unquoted(net, tmp_path, swap):
    log = tmp_path / "run.jsonl"
    write_log(log, LINES[:1])
    secret = other_file(tmp_path)
    with served(net, log) as url:
        first = log_answer(url)
        assert first["entries"] == LINES[:1] and first["error"] is None
        swapped = tmp_path / "swapped"
        if swap == "symlink":
            os.symlink(secret, swapped)
        else:
            swapped.write_text(secret.read_text())
        os.replace(swapped, log)
        with urllib.request.urlopen(f"{url}log?from=1", timeout=MARGIN) as answer:
            body = answer.read().decode()
        got = json.loads(body)
        assert got["done"] and "was replaced by another file while it was followed" \
            in got["error"], got
        assert "SECRET" not in body and got["entries"] == []


@pytest.mark.timeout(60)
def test_a_log_that_is_a_symbolic_link_is_not_followed(net, tmp_path):
    log = tmp_path / "run.jsonl"
    os.symlink(other_file(tmp_path), log)
    with served(net, log) as url:
        with urllib.request.urlopen(f"{url}log?from=0", timeout=MARGIN) as answer:
            body = answer.read().decode()
        got = json.loads(body)
        assert "the run log is a symbolic link" in got["error"], got
        assert "SECRET" not in body
