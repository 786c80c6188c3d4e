"""`mcl2pnml campaign --scheduler`: however the scheduler fails, the campaign ends, within
its bound, with one message, exit status 2 and nothing written.

The scheduler is a real one (`dask scheduler`, `dask worker`: processes of their own,
tests/support/dask_cluster.py), frozen (SIGSTOP) or killed (SIGKILL) mid-run, or left without
a worker; where a real one cannot misbehave on demand, a fake peer on loopback: a port
that accepts and says nothing, one that trickles a plausible handshake a byte at a time,
ones that answer something else than Dask. Addresses and outputs that could not work
are refused before anything is reached or run. The bounds asserted on wall time are
the deadline given plus a generous margin: a loaded machine must not fail them, a hang
must.
"""
from __future__ import annotations

import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Iterator

import pytest

from dask_cluster import free_port, started
from helpers import ROOT, one_error, run_cli
from mcl2pnml.commands.fly import CampaignOptions, campaign
from mcl2pnml.campaign import SchedulerTimeouts
from mcl2pnml.core.errors import Mcl2PnmlError

pytest.importorskip("distributed", reason="Dask's distributed is not installed "
                    "(pip install -e '.[test]' installs it)")

SAUCE = ROOT / "examples" / "sauce.mcl"
MODEL = ROOT / "examples" / "sauce.model.json"
#: Seconds added to a deadline for what a loaded machine may take besides (a start, a
#: close): a campaign that hangs overruns it, one that keeps its deadline never does.
MARGIN = 30.0
#: Runs enough for a campaign to be still flying when the scheduler is stopped.
MANY = 500_000


def _alone(out) -> str:
    """Standard error is exactly one message: no traceback, no line of Dask's."""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    assert "Traceback" not in out.stderr and "distributed" not in out.stderr, out.stderr
    return lines[0]


# -- fake peers ------------------------------------------------------------------------

@contextmanager
def peer(answer: Callable[[socket.socket, threading.Event], None]) -> Iterator[str]:
    """A TCP server on loopback whose every connection ``answer`` serves (until the block
    ends, which closes them all); its address."""
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(0.1)
    stop, accepted = threading.Event(), []

    def serve():
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except OSError:     # the accept's time-out, to look at stop again
                continue
            accepted.append(conn)
            threading.Thread(target=_quietly, args=(answer, conn, stop), daemon=True).start()
    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    finally:
        stop.set()
        thread.join(10)
        for conn in accepted:
            conn.close()
        server.close()


def _quietly(answer, conn, stop) -> None:
    try:
        answer(conn, stop)
    except OSError:     # the client went away: what it should do
        pass


def _silent(conn, stop):
    stop.wait()


def _trickle(conn, stop):
    """A length and frames that Dask's framing would take, a byte every 0.2 s: only a
    deadline over the whole handshake (not a time-out per read) stops waiting for it."""
    message = struct.pack("Q", 1) + struct.pack("Q", 100) + b"\x80" * 100
    for byte in struct.pack("Q", len(message)) + message:
        conn.send(bytes([byte]))
        if stop.wait(0.2):
            return


def _dask_then_silent(conn, stop):
    """Dask's handshake, as a scheduler writes it, then nothing: the probe passes, and
    the client's registration is what waits."""
    from distributed.protocol.core import dumps
    from distributed.protocol.utils import pack_frames
    message = pack_frames(dumps({"compression": None, "python": tuple(sys.version_info)[:3],
                                 "pickle-protocol": 5}))
    conn.sendall(struct.pack("Q", len(message)) + message)
    stop.wait()


def _saying(data: bytes):
    def answer(conn, stop):
        conn.sendall(data)
        stop.wait()
    return answer


GARBAGE = {
    # Dask would read 2^64-1 as the length of what follows, and allocate it
    "ones": _saying(b"\xff" * 64),
    "http": _saying(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n"),
    # Dask's framing, right to the byte, around what is not Dask's handshake
    "framed-noise": _saying(struct.pack("Q", 24) + struct.pack("QQ", 1, 8) + b"\xc1" * 8),
}


def _campaign(*options, timeout: float = 300):
    return run_cli("campaign", SAUCE, "--vehicle-model", MODEL, "--runs", 10, *options,
                   timeout=timeout)


#: Peers that keep the handshake waiting: a port that accepts and says nothing, one that
#: trickles a plausible opening, one that shakes hands and then says nothing (the probe
#: passes; the client's registration is what waits).
WAITING = {"silent": _silent, "trickle": _trickle, "handshake-then-silent": _dask_then_silent}


@pytest.mark.parametrize("kind", sorted(WAITING))
def test_a_peer_that_keeps_the_handshake_waiting_ends_it_at_its_deadline(tmp_path, kind):
    table = tmp_path / "runs.csv"
    with peer(WAITING[kind]) as address:
        start = time.monotonic()
        out = _campaign("--scheduler", address, "--scheduler-timeout", "1", "--table", table)
        took = time.monotonic() - start
    one_error(out, address, "did not complete Dask's handshake within 1 s")
    _alone(out)
    assert took < 1 + MARGIN, took
    assert not table.exists()


@pytest.mark.parametrize("said", sorted(GARBAGE))
def test_a_port_that_answers_something_else_is_refused_before_dask_reads_it(said):
    with peer(GARBAGE[said]) as address:
        out = _campaign("--scheduler", address, "--scheduler-timeout", "20")
    one_error(out, f"{address} is not a Dask scheduler")
    _alone(out)


def test_a_library_call_ends_at_its_deadline_and_leaves_no_thread_behind():
    """The same bound from the facade (a notebook's call), and nothing left running: a
    deadline that abandons Dask's handshake leaves no thread to hold the process."""
    before = set(threading.enumerate())
    with peer(_silent) as address:
        start = time.monotonic()
        with pytest.raises(Mcl2PnmlError, match="did not complete Dask's handshake"):
            campaign(SAUCE, CampaignOptions(MODEL, runs=10, scheduler=address,
                                            scheduler_timeout=SchedulerTimeouts(1, 5)))
        assert time.monotonic() - start < 1 + MARGIN
    deadline = time.monotonic() + MARGIN    # the peer's own threads, ending
    while set(threading.enumerate()) - before and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not set(threading.enumerate()) - before, threading.enumerate()


def test_a_call_from_a_running_event_loop_keeps_its_deadline():
    """A notebook runs an event loop: the campaign runs on a loop of its own beside it,
    and keeps its deadline there too."""
    import asyncio

    async def notebook():
        with peer(_silent) as address:
            with pytest.raises(Mcl2PnmlError, match="within 1 s"):
                campaign(SAUCE, CampaignOptions(MODEL, runs=10, scheduler=address,
                                                scheduler_timeout=SchedulerTimeouts(1, 5)))
    # on a thread of its own: the browser tests' driver keeps a loop running in the main
    # thread of the worker they ran on, where asyncio.run would refuse to start one
    failed: list[BaseException] = []

    def kernel() -> None:
        try:
            asyncio.run(notebook())
        except BaseException as e:   # noqa: BLE001 (said by the test, in its thread)
            failed.append(e)
    start = time.monotonic()
    thread = threading.Thread(target=kernel)
    thread.start()
    thread.join(60)
    assert not thread.is_alive() and not failed, failed
    assert time.monotonic() - start < 1 + MARGIN


@pytest.mark.parametrize("address", ["http://127.0.0.1:8786", "127.0.0.1", "", "tcp://",
                                     "tcp://127.0.0.1:", "tcp://127.0.0.1:99999",
                                     "tcp://127.0.0.1:port", "tcp://127.0.0.1:8786/path"])
def test_a_malformed_address_is_refused_as_the_option_is_read(address):
    out = _campaign("--scheduler", address)
    one_error(out, "Invalid value for '--scheduler'")
    _alone(out)


@pytest.mark.parametrize("bounds", ["0", "5,", "x", "1,2,3", "nan", "1e9"])
def test_a_bad_scheduler_timeout_is_refused(bounds):
    one_error(_campaign("--scheduler-timeout", bounds), "Invalid value for '--scheduler-timeout'")


# -- outputs ---------------------------------------------------------------------------

@pytest.mark.parametrize("option,name,said", [
    ("--plot", "runs.csv", "has no suffix of a format it is written in: .png, .svg, .pdf"),
    ("--table", "runs.png", "has no suffix of a format it is written in: .csv, .parquet"),
    ("--plot", "missing/runs.png", "the folder of"),
    ("--table", "missing/runs.csv", "does not exist"),
])
def test_an_output_that_could_not_be_written_is_refused_before_any_run(
        tmp_path, option, name, said):
    """Refused before the scheduler is reached: given one where nothing listens, the
    message is the output's, not the scheduler's, and nothing is written."""
    out = _campaign("--scheduler", f"tcp://127.0.0.1:{free_port()}", option, tmp_path / name)
    one_error(out, f"Invalid value for {option}", said)
    _alone(out)
    assert not (tmp_path / name).exists()


def test_an_output_that_is_an_input_is_refused(tmp_path):
    model = tmp_path / "m.model.json"
    model.write_bytes(MODEL.read_bytes())
    plot = tmp_path / "m.svg"
    plot.symlink_to(model)
    out = run_cli("campaign", SAUCE, "--vehicle-model", model, "--plot", plot)
    one_error(out, "Invalid value for --plot", "the vehicle model, which this command reads")
    assert model.read_bytes() == MODEL.read_bytes()


# -- a real scheduler, failing mid-run -----------------------------------------------------

def _flying(cluster, table: Path, bounds: str) -> subprocess.Popen:
    """The command in a process of its own (its signals are the test's), once the
    scheduler has its client and a moment to hand out batches."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "mcl2pnml", "campaign", str(SAUCE), "--vehicle-model",
         str(MODEL), "--runs", str(MANY), "--scheduler", cluster.address,
         "--scheduler-timeout", bounds, "--table", str(table)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        cluster.wait_for("Receive client connection")
    except BaseException:
        proc.kill()
        proc.communicate()
        raise
    time.sleep(1)
    return proc


def _ended(proc: subprocess.Popen, within: float):
    try:
        stdout, stderr = proc.communicate(timeout=within)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        pytest.fail(f"the campaign did not end within {within:g} s")
    return subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr)


def test_a_frozen_scheduler_ends_the_campaign_after_the_silence_bound(tmp_path):
    table = tmp_path / "runs.csv"
    with started(tmp_path, workers=1) as cluster:
        proc = _flying(cluster, table, "10,3")
        cluster.signal(signal.SIGSTOP)
        out = _ended(proc, 3 + MARGIN)
    one_error(out, cluster.address, "answered nothing for 3 s", "nothing was written")
    _alone(out)
    assert out.stdout == "" and not table.exists()


def test_a_killed_scheduler_is_one_message(tmp_path):
    table = tmp_path / "runs.csv"
    with started(tmp_path, workers=1) as cluster:
        proc = _flying(cluster, table, "2,60")
        cluster.signal(signal.SIGKILL)
        out = _ended(proc, 2 + MARGIN)      # Dask's reconnection, for the handshake's bound
    one_error(out, cluster.address, "was lost after", "nothing was written")
    _alone(out)
    assert out.stdout == "" and not table.exists()


def test_a_scheduler_without_a_worker_ends_the_campaign_after_the_silence_bound(tmp_path):
    with started(tmp_path, workers=0) as cluster:
        start = time.monotonic()
        out = _campaign("--scheduler", cluster.address, "--scheduler-timeout", "10,2",
                        "--table", tmp_path / "runs.csv")
        took = time.monotonic() - start
    one_error(out, "had no worker for 2 s")
    _alone(out)
    assert took < 2 + MARGIN and not (tmp_path / "runs.csv").exists()


def test_sigterm_stops_a_campaign_with_its_cluster_closed(tmp_path):
    """SIGTERM (kill, timeout, a service stopped) stops a campaign on its local cluster as
    Ctrl-C does: the cluster's worker processes closed, nothing written, exit 143 (128 +
    the signal, as a shell says a process it ended)."""
    psutil = pytest.importorskip("psutil")
    table = tmp_path / "runs.csv"
    proc = subprocess.Popen(
        [sys.executable, "-m", "mcl2pnml", "campaign", str(SAUCE), "--vehicle-model",
         str(MODEL), "--runs", str(MANY), "--workers", "1", "--table", str(table)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + MARGIN * 2
        children: list = []
        while len(children) < 2 and time.monotonic() < deadline:   # the nanny's worker
            children = psutil.Process(proc.pid).children(recursive=True)
            time.sleep(0.2)
        assert children, "the local cluster never started"
        time.sleep(1)
        proc.send_signal(signal.SIGTERM)
        out = _ended(proc, MARGIN)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert out.returncode == 128 + signal.SIGTERM, out.stderr
    assert out.stderr.strip() == "mcl2pnml: interrupted", out.stderr
    assert not table.exists()
    _, alive = psutil.wait_procs(children, timeout=MARGIN)
    assert not alive, alive


# a coroutine as Dask's can be: it swallows its cancellation and goes on waiting
STUBBORN = """
import asyncio, sys
import mcl2pnml.campaign as campaign
from mcl2pnml.runtime.interrupts import Interrupted
campaign.STOP_BOUND = campaign.CLOSE_BOUND = 0.5

async def stubborn():
    print("waiting", flush=True)
    while True:
        try:
            await asyncio.sleep(3600)
        except asyncio.CancelledError:
            pass

try:
    campaign._stoppable(stubborn)
except Interrupted as e:
    sys.exit(128 + e.signum)
"""


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP],
                         ids=lambda s: signal.Signals(s).name)
def test_a_stop_ends_the_campaign_even_if_its_tasks_swallow_their_cancellation(signum):
    """Dask's tasks can swallow a cancellation (a stop while a local cluster started hung
    so): the stop waits a bound for them, then leaves them, and the process ends
    interrupted by the signal."""
    # the signal at its default in the child, as a shell starts it: a test worker can
    # ignore SIGINT, and an ignored signal is inherited (and rightly left ignored)
    proc = subprocess.Popen([sys.executable, "-c", STUBBORN], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signum, signal.SIG_DFL))
    try:
        assert proc.stdout.readline() == "waiting\n", proc.stderr.read()
        proc.send_signal(signum)
        out = _ended(proc, MARGIN)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert out.returncode == 128 + signum, out.stderr
    assert out.stderr == "", out.stderr     # nothing said of what was left behind


def test_a_bounded_wait_leaves_a_task_that_swallows_its_cancellation(monkeypatch):
    """The campaign's deadlines on Dask hold where ``asyncio.wait_for`` would wait, after
    its timeout, for a task that does not end when cancelled; and so does the closing of
    its loop, where ``asyncio.run``'s would wait for it."""
    import asyncio
    import mcl2pnml.campaign as module
    monkeypatch.setattr(module, "CLOSE_BOUND", 0.2)
    still: list[bool] = []

    async def stubborn():
        while True:
            try:
                await asyncio.sleep(3600)
            except asyncio.CancelledError:
                still.append(True)

    async def deadline():
        start = time.monotonic()
        with pytest.raises(asyncio.TimeoutError):
            await module._within(stubborn(), 0.2)
        assert time.monotonic() - start < MARGIN
        await asyncio.sleep(0)      # the cancellation is thrown in at the task's next step
        assert still, "the task was not cancelled"

    async def cancelled():
        waiting = asyncio.ensure_future(module._within(stubborn(), 3600))
        await asyncio.sleep(0.2)
        waiting.cancel()
        with pytest.raises(asyncio.CancelledError):
            await asyncio.wait_for(waiting, MARGIN)
    def cases():
        for case in (deadline, cancelled):
            loop = asyncio.new_event_loop()
            start = time.monotonic()
            try:
                loop.run_until_complete(case())
            finally:
                module._close_loop(loop)
            assert time.monotonic() - start < MARGIN
    # in a thread of its own: one that already runs a loop (Playwright's sync API keeps one
    # running in the thread that holds the tests' browser) may not run another
    pool = ThreadPoolExecutor(1)
    try:    # the cases' failure raised here; not ended within the bound: a TimeoutError
        pool.submit(cases).result(timeout=3 * MARGIN)
    finally:
        pool.shutdown(wait=False)
