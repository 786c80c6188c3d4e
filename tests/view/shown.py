"""Pages ``mcl2pnml show`` writes, made once per test run for all its test processes.

Several modules open the same page (the paper's mission's, in six modules' tests):
each ran ``show`` again, 2.5 core-seconds for the paper's mission, in each xdist
worker. A page is kept in a folder the workers share, under the digest of the
command's arguments and of the files they name, made by the first worker that asks
for it while the others wait on its lock, written under a name of its own then
renamed, so that a worker never reads half a page; the command's exit status is
checked where it ran.
"""
from __future__ import annotations

import fcntl
import hashlib
import os
from pathlib import Path

from helpers import run_cli
from sessioncache import folder as shared_folder    # the run's folder every worker sees


def shown(tmp_path_factory, name: str, *args) -> Path:
    """``mcl2pnml show ARGS -o NAME``'s page (to be read, not written to)."""
    digest = hashlib.sha256()
    for arg in args:
        path = Path(arg)
        if path.is_file():      # a file by its name and content, wherever a test wrote it
            digest.update(b"file\0" + path.name.encode() + b"\0" + path.read_bytes())
        else:
            digest.update(b"arg\0" + str(arg).encode())
        digest.update(b"\0")
    folder = shared_folder(tmp_path_factory) / f"shown-{digest.hexdigest()[:32]}"
    page = folder / name
    if page.is_file():
        return page
    folder.mkdir(exist_ok=True)
    with open(folder / f"{name}.lock", "w") as lock:
        # the workers that start together all want the paper's mission's page: one makes
        # it, the others wait for it instead of making it again
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not page.is_file():
            part = folder / f"{os.getpid()}-{name}"
            out = run_cli("show", *args, "-o", part)
            assert out.returncode == 0, out.stderr
            os.replace(part, page)
    return page
