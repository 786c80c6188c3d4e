"""Reading PNML: the strict reading by default, the forgiving one when asked.

The strict reading (:mod:`mcl2pnml.io.pnml.strict`) is the one every proof rests
on: a file is read as exactly the net verifypn reads, or refused at its line and
column (docs/pnml.md). The forgiving one (:mod:`mcl2pnml.io.pnml.lenient`, the
CLI's ``--lenient``) reads other tools' dialects as they mean them.
"""
from __future__ import annotations

from pathlib import Path

from mcl2pnml.core.net import Net
from mcl2pnml.io.pnml.lenient import parse_lenient, read_lenient
from mcl2pnml.io.pnml.source import XmlError, read_file
from mcl2pnml.io.pnml.strict import parse_strict, read_strict

__all__ = ["XmlError", "load_pnml", "parse_pnml", "read_file", "read_pnml"]


def parse_pnml(data: bytes, filename: str = "<input>", net_id: str | None = None,
               lenient: bool = False) -> Net:
    """Read one P/T net from PNML bytes: strictly, or with ``lenient`` the forgiving way.
    Raises :class:`~mcl2pnml.core.errors.PnmlError` (or several)."""
    if lenient:
        return parse_lenient(data, filename, net_id)
    return parse_strict(data, filename, net_id)


def read_pnml(path: str | Path, net_id: str | None = None, lenient: bool = False) -> Net:
    """Read one P/T net from a PNML file: strictly, as a stream (the proofs' reading), or
    with ``lenient`` the forgiving way."""
    if lenient:
        return read_lenient(path, net_id)
    return read_strict(path, net_id)


#: The library's documented name of :func:`read_pnml` (``from mcl2pnml import load_pnml``).
load_pnml = read_pnml
