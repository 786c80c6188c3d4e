"""The link's opening within one deadline, against peers that trickle their bytes.

A peer that sends one byte every few seconds must not stretch the opening
of a link (connecting, TLS, the hellos) past its bound, as a time-out per
read would let it; and at the bridge server, a connection without the key
must never hold the one place a controller is served in (docs/faults.md,
"Trust and safety").
"""
from __future__ import annotations

import socket
import threading
import time

import pytest

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.runtime.bridge import TcpTransport
from mcl2pnml.runtime.engine import Outcome
from mcl2pnml.runtime.link import CONNECT_TIMEOUT, LinkOptions, encode

from helpers import run_cli
from test_bridge_safety import (FAST, GOTO, SIM_MAPPING, Peer, address, bridge_server,
                                certificate, run_bridge, secret_file, server,  # noqa: F401
                                with_secret)

#: What a bounded wait may take past its bound on a loaded machine (starting a process too).
MARGIN = 20.0
#: A hello as a controller or a bridge sends it.
HELLO = encode({"link": "hello", "protocol": 1, "auth": "hmac-sha256", "nonce": "1" * 32,
                "heartbeat": 0.05})


def trickle(sock: socket.socket, data: bytes, every: float, stop: threading.Event) -> None:
    """Send ``data`` a byte every ``every`` seconds until it is sent, ``stop`` is set, or the
    other end hangs up."""
    try:
        for i in range(len(data)):
            sock.sendall(data[i:i + 1])
            if stop.wait(every):
                return
    except OSError:
        pass        # the other end hung up on us: what it should do


def hung_up(sock: socket.socket, within: float) -> bool:
    """Does the other end close ``sock`` within ``within`` seconds (what it says before,
    an error line, read and dropped)?"""
    deadline = time.monotonic() + within
    try:
        while time.monotonic() < deadline:
            sock.settimeout(max(0.01, deadline - time.monotonic()))
            if not sock.recv(65536):
                return True
    except ConnectionResetError:
        return True
    except socket.timeout:
        return False
    return False


def run_against_a_trickling_bridge(tmp_path, every: float, *options):
    """``mcl2pnml run`` against a bridge that sends its hello a byte every ``every`` s:
    its result, the bridge's address, and the wall seconds it took."""
    mission = tmp_path / "goto.mcl"
    mission.write_text(GOTO)
    stop = threading.Event()
    peer = Peer(lambda conn, p: trickle(conn, HELLO, every, stop))
    start = time.monotonic()
    try:
        out = run_cli("run", mission, "--vehicle", f"bridge:{SIM_MAPPING}", "--connect",
                      peer.address, *options, timeout=CONNECT_TIMEOUT + 60)
    finally:
        stop.set()
    assert out.returncode == 2 and "Traceback" not in out.stderr, out.stderr
    return out, peer.address, time.monotonic() - start


@pytest.mark.timeout(90)
def test_a_bridge_trickling_its_hello_ends_the_run_within_the_opening_bound(tmp_path):
    out, at, elapsed = run_against_a_trickling_bridge(tmp_path, 3.0)
    assert (f"cannot connect to the vehicle's bridge at {at}: no hello from the "
            f"vehicle's bridge within {CONNECT_TIMEOUT:g} s (the bound on opening the link)"
            in out.stderr), out.stderr
    assert elapsed < CONNECT_TIMEOUT + MARGIN, elapsed


@pytest.mark.timeout(90)
def test_the_commands_time_limit_bounds_the_opening_too(tmp_path):
    out, _, elapsed = run_against_a_trickling_bridge(tmp_path, 0.5, "--max-time", "2")
    assert "within 2 s (the bound on opening the link)" in out.stderr, out.stderr
    assert elapsed < 2.0 + MARGIN, elapsed


@pytest.mark.timeout(60)
def test_the_opening_never_waits_past_the_runs_time_limit():
    stop = threading.Event()
    peer = Peer(lambda conn, p: trickle(conn, HELLO, 0.5, stop))
    options = LinkOptions(**{**FAST.__dict__, "connect_timeout": 30.0, "max_time": 2.0})
    start = time.monotonic()
    try:
        with pytest.raises(Mcl2PnmlError, match=r"no hello from the vehicle's bridge within "
                                                 r"2 s \(the bound on opening the link\)"):
            TcpTransport(peer.address, options).open()
    finally:
        stop.set()
    assert time.monotonic() - start < 2.0 + MARGIN


@pytest.mark.timeout(60)
def test_keyless_connections_trickling_never_keep_the_controller_out(server, tmp_path):
    key = secret_file(tmp_path)
    s = server(secret=key.read_bytes().strip(),
               options=LinkOptions(**{**FAST.__dict__, "connect_timeout": 3.0}))
    stop = threading.Event()
    # one trickles its hello; two send a hello at once and trickle the first line, which
    # no one without the key can MAC
    keyless = [(HELLO, b""), (b"", HELLO), (b"", HELLO)]
    socks, threads = [], []
    for i, (trickled, at_once) in enumerate(keyless):
        sock = socket.create_connection(s.server_address[:2], timeout=5)
        sock.sendall(at_once)
        line = encode({"seq": 1, "body": "{}", "mac": "0" * 64})
        threads.append(threading.Thread(target=trickle, args=(sock, trickled or line, 0.5,
                                                              stop), daemon=True))
        threads[-1].start()
        socks.append(sock)
    try:
        result = run_bridge(address(s), with_secret(key), max_time=20.0)
        assert result.outcome is Outcome.OK, result.waiting
        assert s.served[0].commands[0]["command"] == "start_GoToWayPoint"
        # and each keyless one is dropped at the opening's deadline, however it trickles
        for sock in socks:
            assert hung_up(sock, 3.0 + MARGIN)
    finally:
        stop.set()
        for sock in socks:
            sock.close()
    assert len(s.served) == 1


@pytest.mark.timeout(60)
def test_connections_opening_at_once_are_capped(server):
    s = server(options=LinkOptions(**{**FAST.__dict__, "connect_timeout": 20.0}))
    socks = [socket.create_connection(s.server_address[:2], timeout=5)
             for _ in range(bridge_server.OPENING)]
    try:
        # the first ones have their places (the server sent its hello) before one more comes
        for sock in socks:
            sock.settimeout(10)
            assert sock.recv(65536).startswith(b'{"link":"hello"')
        extra = socket.create_connection(s.server_address[:2], timeout=10)
        with extra:
            said = extra.recv(65536)
            assert said.startswith(encode({"link": "error", "reason": (
                f"busy: {bridge_server.OPENING} connections are opening already")}))
            assert hung_up(extra, MARGIN)
    finally:
        for sock in socks:
            sock.close()
    # their places are given back: a controller is served
    assert run_bridge(address(s)).outcome is Outcome.OK


@pytest.mark.timeout(60)
def test_a_tls_handshake_trickled_is_dropped_at_the_opening_deadline(server, tmp_path):
    from mcl2pnml.runtime.link import server_tls
    cert, key = certificate(tmp_path, "bridge")
    s = server(tls=server_tls(cert, key),
               options=LinkOptions(**{**FAST.__dict__, "connect_timeout": 2.0}))
    stop = threading.Event()
    sock = socket.create_connection(s.server_address[:2], timeout=5)
    # the start of a TLS record of a ClientHello, a byte every half second
    sender = threading.Thread(target=trickle, args=(sock, b"\x16\x03\x01\x02\x00" + b"\1" * 512,
                                                    0.5, stop), daemon=True)
    sender.start()
    try:
        assert hung_up(sock, 2.0 + MARGIN)
    finally:
        stop.set()
        sock.close()
    tls = LinkOptions(**{**FAST.__dict__, "tls_ca": cert})
    assert run_bridge(address(s), tls).outcome is Outcome.OK


@pytest.mark.timeout(60)
def test_a_resolver_that_does_not_answer_is_within_the_opening_bound(monkeypatch):
    answered = threading.Event()

    def silent(*args, **kwargs):        # a name server that never answers (until the end)
        answered.wait(60)
        raise socket.gaierror("no answer")
    monkeypatch.setattr(socket, "getaddrinfo", silent)
    options = LinkOptions(**{**FAST.__dict__, "connect_timeout": 1.0})
    start = time.monotonic()
    try:
        with pytest.raises(Mcl2PnmlError, match=r"cannot connect to the vehicle's bridge at "
                                                 r"vehicle\.invalid:7777: no answer within 1 s"):
            TcpTransport("vehicle.invalid:7777", options).open()
    finally:
        answered.set()
    assert time.monotonic() - start < 1.0 + MARGIN
