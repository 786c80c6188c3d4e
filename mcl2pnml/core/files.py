"""Files are written whole or not at all.

Every output goes to a temporary file in the target's directory and is moved
into place with ``os.replace`` (atomic on POSIX) only once it is complete, so
an error or a kill half-way never leaves a half-written PNML, report or log.

Every file the command writes goes through here: ``compile -o`` (PNML by
a stream, dot as text, SVG and PNG as graphviz's bytes), ``template -o``,
``run --log`` (written once the run is over: a run that ends in an error
leaves none). Two outputs do not, by their nature: ``run --journal``,
which is appended to a flushed line at a time so that a killed run can be
resumed (:mod:`mcl2pnml.runtime.journal`; a torn last line is dropped on resume),
and what goes to standard output (``--json``, ``template`` without
``-o``), which is the shell's to redirect. tests/test_resume.py fills
the disk at the last moment and fails a PNML half-way: the old file
stays, and no partial or temporary file is left.
"""
from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO, Iterator

from mcl2pnml.core.errors import Location, Mcl2PnmlError


@contextmanager
def atomic_writer(path: str | Path) -> Iterator[BinaryIO]:
    """A binary file that appears at ``path`` only if the block completes.

    For outputs written as a stream (a PNML of 200 MB is never held in memory
    whole); on any exception the temporary file is removed. A failure of the
    file system (no such directory, no permission, disk full) is reported as
    an :class:`~mcl2pnml.core.errors.Mcl2PnmlError` naming the file.
    """
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    tmp = None
    try:
        directory.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            # mkstemp makes the file private (0600): give it the mode a plain
            # open() would, or the one of the file it replaces
            os.fchmod(f.fileno(), _mode_for(path))
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException as e:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass
        if isinstance(e, OSError):
            reason = e.strerror or str(e)
            raise Mcl2PnmlError(f"cannot write: {reason}", Location(str(path))) from None
        raise


def _mode_for(path: Path) -> int:
    """The permissions of the file at ``path``, or those of a new file under the umask."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    with atomic_writer(path) as f:
        f.write(data)
    return Path(path)


def atomic_write_text(path: str | Path, text: str) -> Path:
    return atomic_write_bytes(path, text.encode("utf-8"))


def read_text(path: str | Path, what: str) -> str:
    """A UTF-8 text file, or one error naming it: "FILE: cannot read the WHAT: why"."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        reason = getattr(e, "strerror", None) or str(e)
        raise Mcl2PnmlError(f"cannot read the {what}: {reason}", Location(str(path))) from None


def read_bytes(path: str | Path) -> bytes:
    """A file's bytes; a file that cannot be read is one error naming it."""
    try:
        return Path(path).read_bytes()
    except OSError as e:
        raise Mcl2PnmlError(f"cannot read: {e.strerror}", Location(str(path))) from None


def decode_text(data: bytes, filename: str, what: str) -> str:
    """A source as text; not UTF-8, or binary, is an error located at the first bad
    byte, with the line shown as far as it can be. ``what`` names the kind of
    file with its article: "an MCL", "a TINA"."""
    def at(offset: int, message: str) -> Mcl2PnmlError:
        before = data[:offset]
        line = before.count(b"\n") + 1
        start = before.rfind(b"\n") + 1
        end = data.find(b"\n", offset)
        text = data[start:end if end >= 0 else len(data)]
        # the line as far as it can be shown: undecodable bytes as U+FFFD,
        # control bytes as '?', so that the caret still lands under the fault
        shown = "".join(c if c.isprintable() or c == "\t" else "?"
                        for c in text.decode("utf-8", errors="replace"))
        col = len(data[start:offset].decode("utf-8", errors="replace")) + 1
        return Mcl2PnmlError(message, Location(filename, line, col, shown))
    if b"\x00" in data:
        raise at(data.index(b"\x00"), f"this is not {what} text file (a NUL byte: binary?)")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise at(e.start, f"not UTF-8 text: byte 0x{data[e.start]:02x} cannot start a "
                          "character here") from None
