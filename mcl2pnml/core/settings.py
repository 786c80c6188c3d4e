"""A command's settings as the library names them, and the one error of a setting that does not fit.

The library knows nothing of the command line: a setting that does not fit the
others (``workers`` with a ``scheduler``) is a :class:`SettingError` naming the
setting as the commands' options dataclasses name it; the CLI shows it as its own
bad option, the setting mapped to the option a user typed (``--workers``).
"""
from __future__ import annotations

from mcl2pnml.core.errors import OptionError


class SettingError(OptionError):
    """A setting that does not fit the others, named by ``setting`` (``max_memory``).

    An :class:`~mcl2pnml.core.errors.OptionError` too, so that whatever catches the
    errors of options catches it: its ``option`` is the setting's name until the CLI
    names the option.
    """

    def __init__(self, setting: str, message: str):
        super().__init__(setting, message)
        self.setting = setting


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
