"""Nets in the text formats of other Petri-net tools, written and read.

* :mod:`~mcl2pnml.io.tina`: TINA's ``.net`` (time Petri nets, LAAS-CNRS);
* :mod:`~mcl2pnml.io.lola`: LoLA's net format (P/T nets, Rostock).

PNML, the standard, lives in :mod:`mcl2pnml.io.pnml`. :func:`load_net` reads
any of them by the file's suffix.
"""
from __future__ import annotations

from pathlib import Path
from typing import Mapping

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.net import Net

#: Suffix -> what the file holds, for the messages that list them.
SUFFIXES = {".pnml": "PNML", ".xml": "PNML", ".net": "TINA", ".lola": "LoLA",
            ".llnet": "LoLA"}


def load_net(path: str | Path) -> Net:
    """A net from a PNML, TINA or LoLA file, chosen by its suffix."""
    path = Path(path)
    kind = SUFFIXES.get(path.suffix.lower())
    if kind == "PNML":
        from mcl2pnml.io.pnml.reader import load_pnml
        return load_pnml(path)
    if kind == "TINA":
        from mcl2pnml.io.tina import load_tina
        return load_tina(path)
    if kind == "LoLA":
        from mcl2pnml.io.lola import load_lola
        return load_lola(path)
    known = ", ".join(f"{s} ({k})" for s, k in SUFFIXES.items())
    raise Mcl2PnmlError(f"cannot tell the format of '{path.name}' from its suffix; known: "
                        f"{known}, and .mcl for missions", Location(str(path)))
