"""A command's settings as the library names them, and the one error of a setting that does not fit.

The library knows nothing of the command line: a setting that does not fit the
others (``workers`` with a ``scheduler``), at any layer (a ``connect`` address
that is none, an ``output`` that is an input), is a :class:`SettingError` naming
the setting as the commands' options dataclasses name it; the CLI shows it as its
own bad option, the setting mapped to the option a user typed (``--workers``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

from mcl2pnml.core.errors import visible


@dataclass(frozen=True)
class Quoted:
    """Another setting a :class:`SettingError`'s message names (``check_outputs``: "is
    also the file of ``log_path``"), which the CLI names as its option (``--log``)."""

    setting: str


class SettingError(Exception):
    """A setting that does not fit the others, named by ``setting`` (``max_memory``,
    ``connect``, ``output``), the one error of a setting the layers below the CLI raise.

    ``message`` is its text, or its pieces: text, and the :class:`Quoted` settings it
    names. Its ``message`` reads each setting by its name, as a library user knows it;
    :meth:`worded` reads them as the caller names them: the CLI shows it as its own
    bad option, in one line naming the option typed (``--max-memory``, ``-o``).
    """

    def __init__(self, setting: str, message: str | Sequence[str | Quoted]):
        self.setting = setting
        self.pieces = (message,) if isinstance(message, str) else tuple(message)
        self.message = self.worded(lambda quoted: quoted)
        super().__init__(self.message)

    def __reduce__(self):   # pickled whole (a campaign's worker raises it), not as its text
        return SettingError, (self.setting, self.pieces)

    def worded(self, name: Callable[[str], str]) -> str:
        """The message, each setting it quotes written ``name(setting)``; the text's
        control characters escaped, as it may quote a file's name."""
        return "".join(visible(piece, keep="\n") if isinstance(piece, str)
                       else name(piece.setting) for piece in self.pieces)


class UsageProblem(Exception):
    """Settings a command does not take together (``port`` without a live page), or one
    it needs missing: shown by the CLI as it shows its own usage errors."""

    def __init__(self, message: str):
        super().__init__(message)
        self.message = message


def parse_size(text: str, setting: str = "max_memory") -> int:
    """A size in bytes written ``4G``, ``500M``, ``64K`` or ``1000000`` (powers of 1024);
    one that is not is a :class:`SettingError` of ``setting``."""
    units = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}
    number, unit = text.strip().upper().rstrip("B"), ""
    if number and number[-1] in units:
        number, unit = number[:-1], number[-1]
    try:
        size = float(number) * units[unit]
    except ValueError:
        raise SettingError(setting, f"'{text}': a size is a number with K, M, G or T (4G, "
                                    "500M)") from None
    if size < 1:
        raise SettingError(setting, f"'{text}': a size is at least one byte")
    return int(size)


def size_or_none(size: int | str | None, setting: str) -> int | None:
    """``size`` in bytes: as given, read by :func:`parse_size` when written, or None."""
    return parse_size(size, setting) if isinstance(size, str) else size
