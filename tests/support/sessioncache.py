"""Results computed once per test session, shared by every xdist worker.

Some tests start from a costly fixed thing (a pool of certified missions, say) that each
worker running one of them built again: up to four times a suite. :func:`shared` keeps
it in a file of the session's temporary folder (the one the workers' folders are in),
named by a digest of what builds it: the first worker to ask computes it, holding a
lock, and the others wait for it and read it back. The folder is the session's own, so
nothing is read from an earlier run.
"""
from __future__ import annotations

import fcntl
import hashlib
import os
import pickle
from pathlib import Path
from typing import Callable, TypeVar

T = TypeVar("T")


def folder(tmp_path_factory) -> Path:
    """The session's folder for shared results: beside the workers' own folders under
    xdist, in the session's folder without it."""
    base = tmp_path_factory.getbasetemp()
    root = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    out = root / "shared-results"
    out.mkdir(exist_ok=True)
    return out


def shared(tmp_path_factory, name: str, key: object, compute: Callable[[], T]) -> T:
    """``compute()``, or what a worker of this session computed for the same ``name`` and
    ``key`` (whose ``repr`` names what builds it), read back from its file."""
    digest = hashlib.sha256(f"{name}\n{key!r}".encode()).hexdigest()[:24]
    path = folder(tmp_path_factory) / f"{name}-{digest}.pickle"
    with open(path.with_suffix(".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)      # another worker computing it: wait for it
        if path.exists():
            return pickle.loads(path.read_bytes())
        value = compute()
        temporary = path.with_suffix(f".{os.getpid()}.tmp")
        temporary.write_bytes(pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL))
        os.replace(temporary, path)
        return value
