"""The command line as a real process per command, without paying for the
interpreter's start-up and imports each time.

Most tests that run ``mcl2pnml`` want what a user gets: a process of its own,
its exit status, what it prints on each stream, a traceback if there is one.
Starting a fresh interpreter for each of the suite's ~500 commands costs a
quarter of a second of imports per command, most of the suite's time. So a
server per test worker imports the command's modules once and forks a child
per command: the child gets the caller's three standard streams (passed over a
Unix socket), its working directory, environment and arguments, runs the
package's own ``__main__`` as ``python -m mcl2pnml`` does, and its exit
status (or the signal that ended it) goes back to the caller. Only what
happens at import differs; tests/project/test_layers.py and tests/commands/test_install.py
start fresh interpreters for that, and ``MCL2PNML_TEST_FRESH=1`` makes every
test do so.

    python tests/support/forkcli.py serve SOCKET     # the server (helpers.run_cli starts it)
    python -S tests/support/forkcli.py run ARGS...   # a client: ``mcl2pnml ARGS`` through the
                                             # server named by $MCL2PNML_FORKSERVER
"""
from __future__ import annotations

import array
import json
import os
import signal
import socket
import struct
import sys

#: Where a client finds the server.
ENV = "MCL2PNML_FORKSERVER"
#: A request's size bound: arguments, directory and environment as JSON.
MAX_REQUEST = 1 << 20
STATUS = struct.Struct("!ii")   # (pid, 0) first, then (0, returncode as subprocess says it)


# -- the server ---------------------------------------------------------------------

def _preload() -> None:
    """Import every module a command may import, the libraries its functions import
    when they run (sympy, Dask, jsonschema: most of a second each, per command
    otherwise), build the parsers that do not depend on the environment and load the
    installed templates, before any fork."""
    import ast
    import importlib
    import pkgutil
    from pathlib import Path

    import mcl2pnml
    import mcl2pnml.analysis as analysis   # installed under mcl2pnml from its own folder
    later: set[str] = set()
    for package in (mcl2pnml, analysis):
        for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
            if not info.name.endswith("__main__"):
                try:
                    module = importlib.import_module(info.name)
                except Exception:   # an optional extra (pymavlink...): imported when used
                    continue
                if str(module.__file__).endswith(".py"):    # not the compiled loops
                    later |= _imported_when_run(Path(module.__file__), ast)
    for name in sorted(later):
        try:
            importlib.import_module(name)
        except Exception:       # an optional extra, or a module only some platforms have
            pass
    from mcl2pnml.language import parser, template_parser
    for module in (parser, template_parser):
        for name in dir(module):
            built = getattr(module, name)
            if callable(built) and hasattr(built, "cache_info") and not _needs_args(built):
                built()
    from mcl2pnml.language.library import ENV, default_library
    if not os.environ.get(ENV):
        default_library()       # a command whose environment names templates loads its own


def _imported_when_run(path: Path, ast) -> set[str]:
    """The modules the functions of the module at ``path`` import when they run."""
    tree = ast.parse(path.read_bytes())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for inner in ast.walk(node):
                if isinstance(inner, ast.Import):
                    found |= {alias.name for alias in inner.names}
                elif isinstance(inner, ast.ImportFrom) and inner.level == 0 and inner.module:
                    found.add(inner.module)
    return found


def _needs_args(function) -> bool:
    import inspect
    try:
        return any(p.default is p.empty and p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
                   for p in inspect.signature(function).parameters.values())
    except (TypeError, ValueError):
        return True


def _receive(conn: socket.socket) -> tuple[dict, list[int]]:
    fds = array.array("i")
    data, ancillary, _flags, _addr = conn.recvmsg(MAX_REQUEST, socket.CMSG_LEN(3 * fds.itemsize))
    for level, kind, payload in ancillary:
        if level == socket.SOL_SOCKET and kind == socket.SCM_RIGHTS:
            fds.frombytes(payload[:len(payload) - len(payload) % fds.itemsize])
    return json.loads(data), list(fds)


def _command(request: dict, fds: list[int]) -> int:
    """In the forked child: become ``python -m mcl2pnml ARGS`` and return its status."""
    import atexit
    import runpy
    import traceback

    os.setpgid(0, 0)    # a caller's timeout ends the command and what it started
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGCHLD):   # SIGPIPE stays ignored, as Python has it
        signal.signal(sig, signal.SIG_DFL if sig != signal.SIGINT else signal.default_int_handler)
    for target, fd in enumerate(fds):
        os.dup2(fd, target)
        os.close(fd)
    os.chdir(request["cwd"])
    os.environ.clear()
    os.environ.update(request["env"])
    from mcl2pnml.language.library import ENV, default_library
    if os.environ.get(ENV):     # templates of its own: not the server's library
        default_library.cache_clear()
    sys.path[0] = os.getcwd()       # as ``python -m`` puts it
    # the streams as a fresh interpreter opens them on these descriptors
    sys.stdin = open(0, closefd=False)
    sys.stdout = open(1, "w", closefd=False)
    sys.stderr = open(2, "w", closefd=False, errors="backslashreplace", buffering=1)
    sys.argv = ["mcl2pnml", *request["args"]]
    code = 0
    try:
        runpy.run_module("mcl2pnml", run_name="__main__", alter_sys=True)
    except SystemExit as stop:
        if stop.code is None:
            code = 0
        elif isinstance(stop.code, int):
            code = stop.code
        else:
            print(stop.code, file=sys.stderr)
            code = 1
    except BaseException:   # noqa: BLE001  (what the interpreter does: print it, exit 1)
        traceback.print_exc()
        code = 1
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:   # a closed pipe: the interpreter would not say more either
            pass
    return code & 0xFF


def _handle(conn: socket.socket) -> None:
    """In a child of the server: run the command in a grandchild, report its status."""
    request, fds = _receive(conn)
    pid = os.fork()
    if pid == 0:
        conn.close()
        os._exit(_command(request, fds))
    for fd in fds:
        os.close(fd)
    conn.sendall(STATUS.pack(pid, 0))
    _, status = os.waitpid(pid, 0)
    code = os.waitstatus_to_exitcode(status)    # -N for signal N, as subprocess says
    conn.sendall(STATUS.pack(0, code))


def serve(path: str) -> None:
    _preload()
    signal.signal(signal.SIGCHLD, signal.SIG_IGN)    # handlers are reaped by the kernel
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(path)
    listener.listen(16)
    print("ready", flush=True)
    while True:
        conn, _ = listener.accept()
        if os.fork() == 0:
            listener.close()
            signal.signal(signal.SIGCHLD, signal.SIG_DFL)   # so that waitpid sees the command
            try:
                _handle(conn)
            finally:
                os._exit(0)
        conn.close()


# -- a client -----------------------------------------------------------------------

def call(path: str, args: list[str], cwd: str, env: dict, fds: list[int],
         timeout: float | None = None) -> int:
    """Run ``mcl2pnml ARGS`` through the server at ``path`` on the descriptors ``fds``
    (standard input, output, error); its exit status, -N if signal N ended it.
    Past ``timeout`` seconds the command is killed and TimeoutError raised."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as conn:
        conn.settimeout(timeout)
        conn.connect(path)
        request = json.dumps({"args": args, "cwd": cwd, "env": env}).encode()
        conn.sendmsg([request], [(socket.SOL_SOCKET, socket.SCM_RIGHTS, array.array("i", fds))])
        pid = None
        try:
            while True:
                data = b""
                while len(data) < STATUS.size:
                    more = conn.recv(STATUS.size - len(data))
                    if not more:
                        raise ConnectionError("the command's server ended without its status")
                    data += more
                first, code = STATUS.unpack(data)
                if first:
                    pid = first
                else:
                    return code
        except socket.timeout:
            if pid is not None:
                try:
                    os.killpg(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            raise TimeoutError(f"mcl2pnml {' '.join(args)} ran past {timeout} s") from None


_server: tuple | None = None


def server() -> str | None:
    """The socket of this process's server, started on first use (and ended with
    this process); ``None`` under ``MCL2PNML_TEST_FRESH=1``."""
    global _server
    if os.environ.get("MCL2PNML_TEST_FRESH") == "1":
        return None
    if _server is None or _server[0].poll() is not None:
        import atexit
        import select
        import shutil
        import subprocess
        import tempfile

        folder = tempfile.mkdtemp(prefix="mcl2pnml-cli-")
        path = os.path.join(folder, "socket")
        proc = subprocess.Popen([sys.executable, os.path.abspath(__file__), "serve", path],
                                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                start_new_session=True)
        ready, _, _ = select.select([proc.stdout], [], [], 120)
        if not ready or proc.stdout.readline() != b"ready\n":
            proc.kill()
            raise RuntimeError("the command server did not start within 120 s")

        def stop(proc=proc, folder=folder):
            proc.kill()
            proc.wait()
            shutil.rmtree(folder, ignore_errors=True)
        atexit.register(stop)
        _server = (proc, path)
    return _server[1]


def run(args, cwd=None, env=None, timeout: float | None = None, text: bool = True):
    """``mcl2pnml ARGS`` as ``subprocess.run([python, -m, mcl2pnml, ...],
    capture_output=True, text=text)`` gives it: through the server, or in a fresh
    interpreter under ``MCL2PNML_TEST_FRESH=1``. ``text=False``: the streams' bytes, with
    no decoding and no newline translation."""
    import io
    import subprocess
    import tempfile

    args = [str(a) for a in args]
    command = [sys.executable, "-m", "mcl2pnml", *args]
    path = server()
    if path is None:
        return subprocess.run(command, capture_output=True, text=text, cwd=cwd, env=env,
                              timeout=timeout)
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err, \
            open(os.devnull, "rb") as null:
        try:
            code = call(path, args, os.path.abspath(cwd or os.getcwd()),
                        dict(os.environ if env is None else env),
                        [null.fileno(), out.fileno(), err.fileno()], timeout)
        except TimeoutError:
            raise subprocess.TimeoutExpired(command, timeout) from None
        texts = []
        for stream in (out, err):
            stream.seek(0)
            texts.append(io.TextIOWrapper(stream).read() if text   # as text=True decodes
                         else stream.read())
    return subprocess.CompletedProcess(command, code, *texts)


def main(argv: list[str]) -> int:
    if argv[:1] == ["serve"] and len(argv) == 2:
        serve(argv[1])
        return 0
    if argv[:1] == ["run"]:
        code = call(os.environ[ENV], argv[1:], os.getcwd(), dict(os.environ), [0, 1, 2])
        if code < 0:    # end as the command ended
            signal.signal(-code, signal.SIG_DFL)
            os.kill(os.getpid(), -code)
        return code
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
