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
``-o``), which is the shell's to redirect. tests/runtime/test_resume.py fills
the disk at the last moment and fails a PNML half-way: the old file
stays, and no partial or temporary file is left.

A temporary file is named ``.NAME.mcl2pnml-PID-RANDOM.tmp``: hidden, next to
its target NAME, recognisably ours, with the writer's process id. A writer
killed outright (SIGKILL, the OOM killer, a power cut) cannot remove its
own; the next write of the same target removes those whose process is
gone, and nothing else (another name, a live process's, a file that is not
a regular file). For tests only: with ``MCL2PNML_WRITE_KILL=1`` in the
environment, the process kills itself (SIGKILL) once an output is whole in
its temporary file, before it is moved into place, as a kill at that
moment would.

Every input is read through here too (:func:`read_bytes`, :func:`read_text`,
:func:`open_regular`), and only a regular file is read: a FIFO would block
the command for ever, a device may never end, a directory is no input.
And an output must not be an input of the same command, nor another of its
outputs (:func:`check_outputs`): writing it would destroy what is read. A read
may be bounded (``limit``): the size is checked before a byte is read, and no
more than the limit is read, so that a file of gigabytes is refused at once
with one message naming the option that raises the limit.
"""
from __future__ import annotations

import os
import re
import signal
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO, Iterable, Iterator

from mcl2pnml.core.errors import EXCERPT_WIDTH, Location, Mcl2PnmlError
from mcl2pnml.core.settings import Quoted, SettingError

#: The test hook: kill the process once an output is whole in its temporary file.
KILL_BEFORE_REPLACE = "MCL2PNML_WRITE_KILL"
#: What marks a temporary file as ours, between the target's name and the writer's pid.
TEMP_MARK = ".mcl2pnml-"
#: A temporary file keeps this many bytes of its target's name (a name has at most 255).
TEMP_NAME_KEPT = 100


@contextmanager
def atomic_writer(path: str | Path) -> Iterator[BinaryIO]:
    """A binary file that appears at ``path`` only if the block completes.

    For outputs written as a stream (a PNML of 200 MB is never held in memory
    whole); on any exception the temporary file is removed. A failure of the
    file system (no such directory, no permission, disk full) is reported as
    an :class:`~mcl2pnml.core.errors.Mcl2PnmlError` naming the file.

    A device or a FIFO at ``path`` (``-o /dev/null``, ``-o /dev/stdout``) is
    written into, never replaced: moving a file onto ``/dev/null`` would put a
    regular file in the device's place for every process of the machine.
    """
    path = Path(path)
    if _special(path):
        try:
            with open(path, "wb") as f:
                yield f
        except OSError as e:
            raise Mcl2PnmlError(f"cannot write: {e.strerror or e}", Location(str(path))) \
                from None
        return
    directory = path.parent if str(path.parent) else Path(".")
    tmp = None
    try:
        directory.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(path)
        fd, tmp = tempfile.mkstemp(prefix=_temp_prefix(path.name), suffix=".tmp", dir=directory)
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            # mkstemp makes the file private (0600): give it the mode a plain
            # open() would, or the one of the file it replaces
            os.fchmod(f.fileno(), _mode_for(path))
            os.fsync(f.fileno())
        if os.environ.get(KILL_BEFORE_REPLACE):
            os.kill(os.getpid(), signal.SIGKILL)
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


def _special(path: Path) -> bool:
    """Is there a character device or a FIFO at ``path``?"""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return False
    return stat.S_ISCHR(mode) or stat.S_ISFIFO(mode)


def _kept(name: str) -> str:
    """The part of a target's name its temporary file keeps: at most TEMP_NAME_KEPT
    bytes, so that the temporary's name stays within the file system's 255."""
    return name.encode("utf-8", "surrogateescape")[:TEMP_NAME_KEPT].decode("utf-8", "ignore")


def _temp_prefix(name: str) -> str:
    return f".{_kept(name)}{TEMP_MARK}{os.getpid()}-"


def _temp_pattern(name: str) -> re.Pattern[str]:
    """Our temporary files for a target ``name``; group 1 is the writer's pid.

    The random part is mkstemp's (lower-case letters, digits, ``_``).
    """
    return re.compile(re.escape(f".{_kept(name)}{TEMP_MARK}")
                      + r"([1-9][0-9]{0,9})-[a-z0-9_]+\.tmp")


def _alive(pid: int) -> bool:
    """Is there a process ``pid``? In doubt (another user's, a pid out of range), yes."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError, OSError):
        return True
    return True


def remove_stale_temporaries(path: str | Path) -> list[Path]:
    """Remove the temporary files of writes of ``path`` whose writer is dead; the removed.

    Only names of our pattern for this very target, only regular files, only
    when the pid they carry is no live process (a pid reused since by another
    process keeps its file: that is the safe side). Not our own pid's either:
    a temporary of this process is a write in progress.
    """
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    pattern, removed = _temp_pattern(path.name), []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if match is None:
            continue
        pid = int(match.group(1))
        if pid == os.getpid() or _alive(pid):
            continue
        try:
            if not entry.is_file(follow_symlinks=False):
                continue
            os.unlink(entry.path)
            removed.append(Path(entry.path))
        except OSError:
            pass     # gone already, or not ours to remove: leave it
    return removed


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


_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
          (stat.S_ISSOCK, "a socket"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"))


def _not_regular(mode: int) -> str | None:
    """What a file of this mode is, when it is not a regular file."""
    if stat.S_ISREG(mode):
        return None
    return next((kind for test, kind in _KINDS if test(mode)), "not a regular file")


def open_regular(path: str | Path, what: str | None = None, flags: int = os.O_RDONLY) -> int:
    """A descriptor of the regular file at ``path``, or one error naming it.

    A FIFO, a device, a socket or a directory is refused before it is read:
    reading a FIFO blocks until someone writes, a device may never end. The
    type is checked before opening (opening a FIFO may block, a tape device
    may rewind) and again on the descriptor, opened without blocking, so
    that a file swapped in between is caught too.
    """
    cannot = f"cannot read the {what}" if what else "cannot read"

    def refused(kind: str) -> Mcl2PnmlError:
        return Mcl2PnmlError(f"{cannot}: this is {kind}, not a regular file",
                             Location(str(path)))
    try:
        kind = _not_regular(os.stat(path).st_mode)
        if kind is not None:
            raise refused(kind)
        fd = os.open(path, flags | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as e:
        raise Mcl2PnmlError(f"{cannot}: {e.strerror or e}", Location(str(path))) from None
    kind = _not_regular(os.fstat(fd).st_mode)
    if kind is not None:
        os.close(fd)
        raise refused(kind)
    return fd


def mib(size: int) -> str:
    """A size as the limits' messages give it: ``4.0 MiB``."""
    return f"{size / 2**20:,.1f} MiB"


def _read(path: str | Path, what: str | None, limit: int | None = None,
          option: str | None = None) -> bytes:
    """The bytes of the regular file at ``path``; with ``limit``, at most that many.

    The size is checked on the open descriptor before anything is read, so that a
    file of gigabytes costs nothing to refuse; and no more than ``limit`` + 1 bytes
    are read, since a file may grow after the check, and some regular files (those
    of /proc) say they are empty. ``option`` is the one that raises the limit.
    """
    the = f" the {what}" if what else ""

    def too_large(size: int | None) -> Mcl2PnmlError:
        is_ = f"it is {mib(size)}, over" if size is not None else "it is over"
        raise_it = f" ({option} to raise it)" if option else ""
        return Mcl2PnmlError(f"cannot read{the}: {is_} the limit of {mib(limit)}{raise_it}",
                             Location(str(path)))
    fd = open_regular(path, what)
    try:
        with os.fdopen(fd, "rb") as f:
            if limit is None:
                return f.read()
            size = os.fstat(f.fileno()).st_size
            if size > limit:
                raise too_large(size)
            data = f.read(limit + 1)
            if len(data) > limit:
                raise too_large(None)
            return data
    except OSError as e:
        reason = e.strerror or str(e)
        raise Mcl2PnmlError(f"cannot read{the}: {reason}", Location(str(path))) from None


def read_text(path: str | Path, what: str, limit: int | None = None,
              option: str | None = None) -> str:
    """A UTF-8 text file, or one error naming it: "FILE: cannot read the WHAT: why", or
    where its first byte that is not UTF-8 is (:func:`decode_text`).

    ``limit``: a file of more bytes is refused before it is read, the message
    naming ``option`` as the way to raise the limit (:func:`_read`).
    """
    data = _read(path, what, limit, option)
    return decode_text(data, str(path), f"a {what}")


def read_bytes(path: str | Path, what: str | None = None, limit: int | None = None,
               option: str | None = None) -> bytes:
    """A file's bytes; a file that cannot be read, or is no regular file, or is over
    ``limit`` bytes (:func:`read_text`), is one error naming it."""
    return _read(path, what, limit, option)


def same_file(a: str | Path, b: str | Path) -> bool:
    """Do ``a`` and ``b`` name one file: the same resolved path, or (both existing) the
    same inode, through a hard link, a symbolic link or a bind mount."""
    try:
        if Path(a).resolve() == Path(b).resolve():
            return True
    except (OSError, RuntimeError):   # a symbolic link loop: compare what exists
        pass
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def _identity(path: Path) -> tuple[Path | None, tuple[int, int] | None]:
    """What :func:`same_file` compares, found once: the resolved path, and the device
    and inode where the file exists."""
    try:
        resolved = path.resolve()
    except (OSError, RuntimeError):   # a symbolic link loop: the inode may still say
        resolved = None
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return resolved, None
    return resolved, (st.st_dev, st.st_ino)


def check_outputs(outputs: Iterable[tuple[str, str | Path | None]],
                  inputs: Iterable[tuple[str, str | Path | None]] = (),
                  instead: str = "give another file") -> None:
    """Refuse an output that is an input of the same command, or another of its outputs.

    ``outputs`` are (setting, path) pairs (``("output", ...)``, ``("log_path",
    ...)``), ``inputs`` (what it is, path) pairs (``("the mission", ...)``); None is
    a setting not given. Writing an output that is also an input destroys the
    input (``compile s.mcl -o s.mcl``); two outputs in one file keep the last.
    One :class:`~mcl2pnml.core.settings.SettingError` naming the setting, ending
    with ``instead`` (what to do about it); the other output it clashes with is
    :class:`~mcl2pnml.core.settings.Quoted`, for the CLI to name as its option.
    Files are compared as :func:`same_file` does, each looked up once, so that
    thousands of outputs (a counterexample's files per property) cost a moment.
    """
    # each file's resolved path and inode -> (what it is or its setting, an input?)
    seen: dict[tuple[str, object], tuple[str, bool]] = {}

    def keys(path: Path) -> list[tuple[str, object]]:
        resolved, inode = _identity(path)
        return [key for key in (("path", resolved), ("inode", inode)) if key[1] is not None]
    for what, p in inputs:
        for key in keys(Path(p)) if p is not None else ():
            seen.setdefault(key, (what, True))
    for setting, p in outputs:
        if p is None:
            continue
        path = Path(p)
        found = keys(path)
        clashes = [seen[key] for key in found if key in seen]
        clash = next((c for c in clashes if c[1]), clashes[0] if clashes else None)
        if clash is not None and clash[1]:
            raise SettingError(setting, f"'{path}' is {clash[0]}, which this command reads: "
                                        f"writing there would destroy it; {instead}")
        if clash is not None:
            raise SettingError(setting, (f"'{path}' is also the file of ", Quoted(clash[0]),
                                         ": give each output a file of its own"))
        for key in found:
            seen.setdefault(key, (setting, False))


def json_fault(error: ValueError | RecursionError) -> str:
    """Why ``json.loads`` refused a text, in the words of a message.

    Besides bad JSON (:class:`json.JSONDecodeError`, which has its own
    position), ``json.loads`` raises a bare ValueError for an integer past
    Python's 4,300 digits, and RecursionError for arrays or objects nested
    thousands deep: an input file of ours must give a message for those too.
    """
    if isinstance(error, RecursionError):
        return "arrays or objects nested too deeply"
    msg = getattr(error, "msg", None)
    if msg:
        return msg
    return "a number of more than 4,300 digits" if "digits" in str(error) else str(error)


def decode_text(data: bytes, filename: str, what: str) -> str:
    """A source as text; not UTF-8, or binary, is an error located at the first bad
    byte, with the line shown as far as it can be. ``what`` names the kind of
    file with its article: "an MCL", "a TINA"."""
    def at(offset: int, message: str) -> Mcl2PnmlError:
        before = data[:offset]
        line = before.count(b"\n") + 1
        start = before.rfind(b"\n") + 1
        end = data.find(b"\n", offset)
        # the line as far as its excerpt can show (a window around the fault, marked as
        # cut): a file of megabytes on one line is not turned into text whole
        end = min(end if end >= 0 else len(data), offset + 16 * EXCERPT_WIDTH)
        text = data[start:end]
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
        raise at(e.start, f"not UTF-8 text: byte 0x{data[e.start]:02x} ({e.reason}); save "
                          "the file as UTF-8") from None
