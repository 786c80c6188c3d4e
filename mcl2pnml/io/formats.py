"""The format table: every file format a net is read from or written to.

* PNML (ISO/IEC 15909-2), the standard, in :mod:`mcl2pnml.io.pnml`;
* TINA's ``.net`` (time Petri nets, LAAS-CNRS), :mod:`mcl2pnml.io.tina`;
* LoLA's net format (P/T nets, Rostock), :mod:`mcl2pnml.io.lola`;
* graphviz's DOT, and the SVG and PNG it renders, :mod:`mcl2pnml.io.dot`: a
  drawing written, which the view draws (:mod:`mcl2pnml.view.drawing`);
* TAPAAL's timed-arc nets (write only: a compiled mission under its timed
  semantics, for verifydtapn), :mod:`mcl2pnml.io.tapn`.

Each :class:`Format` names the module and functions that implement it, named
after one pattern in every module of :mod:`mcl2pnml.io`: ``read_X(path)``,
``parse_X(text or bytes)``, ``write_X(net, path, **options)`` and ``to_X(net)``
(text or bytes; a drawing's ``to_svg``/``to_png`` take the drawing's DOT text),
imported only when the format is used (graphviz, lark and lxml are not
loaded for a format that does not need them). Adding a format is one new
module of ``mcl2pnml.io`` and one entry in :data:`FORMATS`: ``compile
--format``, ``template --format``, ``analyze`` and ``show`` take it from
here.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Callable, Mapping, Sequence

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.net import Net
from mcl2pnml.core.settings import SettingError
from mcl2pnml.core.timing import Assumptions


@dataclass(frozen=True)
class SaveOptions:
    """What a writer may be told besides the net; each format takes what it can say."""

    #: node id -> (x, y), PNML's ``<graphics>`` (a layout, computed by the caller)
    positions: Mapping[str, tuple[float, float]] | None = None
    #: a compiled mission: what the vehicle does not fire fires at once (TINA's [0,0])
    urgent: bool = False
    #: (source, target) of an arc -> its bend points, PNML's arc ``<graphics>``
    bends: Mapping[tuple[str, str], Sequence[tuple[float, float]]] | None = None
    #: a drawing's DOT text, drawn by the caller (:mod:`mcl2pnml.view.drawing`), as the
    #: positions are laid out by it: io writes a drawing, never makes one
    drawing: str | None = None
    #: a compiled mission's timed semantics: what the vehicle is assumed to do (None: the
    #: writer's own default; a timed-arc net's is acknowledgements at once, reports 1 s apart)
    timing: Assumptions | None = None


@dataclass(frozen=True)
class Format:
    """One file format: its names, what it can say, and where it is implemented."""

    #: the name ``--format`` takes
    name: str
    #: what the file holds, in messages ("PNML", "TINA")
    title: str
    #: suffixes it is recognised by; the first is the one it is written with
    suffixes: tuple[str, ...]
    #: what it can say of our nets, for the help
    says: str
    #: the module implementing it
    module: str
    #: its reader, ``read_X(path) -> Net`` (None: write-only)
    reader: str | None = None
    #: its writer, ``write_X(net, path, **options)``
    writer: str | None = None
    #: the :class:`SaveOptions` fields its writer takes
    options: tuple[str, ...] = ()
    #: a file may hold several nets, one chosen by its id (``--net``)
    several: bool = False
    #: its reader has a forgiving reading besides the strict one (``--lenient``)
    lenient: bool = False

    def _function(self, name: str) -> Callable:
        return getattr(importlib.import_module(self.module), name)

    def read(self, path: str | Path, net_id: str | None = None, lenient: bool = False) -> Net:
        """The net of ``path``; ``net_id`` chooses one where a file holds several;
        ``lenient``: the reader's forgiving reading (docs/pnml.md), never a proof's."""
        given = {}
        if lenient:
            if not self.lenient:
                raise SettingError("lenient", f"a {self.title} file has one reading; leave "
                                              "out --lenient")
            given["lenient"] = True
        if net_id is None:
            return self._function(self.reader)(path, **given)
        if not self.several:
            raise SettingError("net_id", f"a {self.title} file holds one net; leave out --net")
        return self._function(self.reader)(path, net_id, **given)

    def write(self, net: Net, path: str | Path, options: SaveOptions = SaveOptions()) -> list[str]:
        """Write ``net`` to ``path``, whole or not at all; returns what the format could
        not say of it, in words (a writer that says nothing of it returns nothing)."""
        given = {f.name: getattr(options, f.name) for f in fields(options)}
        said = self._function(self.writer)(net, path, **{k: given[k] for k in self.options})
        return said if isinstance(said, list) else []


FORMATS: dict[str, Format] = {f.name: f for f in (
    Format("pnml", "PNML", (".pnml", ".xml"),
           "PNML (ISO/IEC 15909-2), with time-outs and bindings as toolspecific data",
           "mcl2pnml.io.pnml", "read_pnml", "write_pnml", ("positions", "bends"), several=True,
           lenient=True),
    Format("tina", "TINA", (".net",), "TINA's .net: a time Petri net, time-outs as intervals",
           "mcl2pnml.io.tina", "read_tina", "write_tina", ("urgent",)),
    Format("lola", "LoLA", (".lola", ".llnet"), "LoLA's net format (untimed)",
           "mcl2pnml.io.lola", "read_lola", "write_lola"),
    Format("pipe", "PIPE", (".xml",),
           "PIPE's own dialect of PNML, with the layout (untimed: the time-outs' delays "
           "in a note on the canvas)", "mcl2pnml.io.pipe", None, "write_pipe",
           ("positions", "bends")),
    Format("tapn", "TAPAAL timed-arc", (".tapn",),
           "TAPAAL's timed-arc PNML for verifydtapn: a mission under its timed semantics "
           "(time-outs, acknowledgements, report gaps in token ages), queries beside it",
           "mcl2pnml.io.tapn", None, "write_tapn", ("timing",)),
    Format("dot", "DOT", (".dot",), "graphviz's DOT source of the drawing",
           "mcl2pnml.io.dot", None, "write_dot", ("drawing",)),
    Format("svg", "SVG", (".svg",), "the drawing as SVG", "mcl2pnml.io.dot", None, "write_svg",
           ("drawing",)),
    Format("png", "PNG", (".png",), "the drawing as PNG", "mcl2pnml.io.dot", None, "write_png",
           ("drawing",)),
)}

#: Suffix -> the format that reads it.
READERS: dict[str, Format] = {s: f for f in FORMATS.values() if f.reader for s in f.suffixes}
#: Suffix -> what the file holds, for the messages that list them.
SUFFIXES: dict[str, str] = {s: f.title for s, f in READERS.items()}


def reader_of(path: str | Path) -> Format:
    """The format that reads ``path``, told by its suffix."""
    path = Path(path)
    fmt = READERS.get(path.suffix.lower())
    if fmt is None:
        known = ", ".join(f"{s} ({k})" for s, k in SUFFIXES.items())
        raise Mcl2PnmlError(f"cannot tell the format of '{path.name}' from its suffix; known: "
                            f"{known}, and .mcl for missions", Location(str(path)))
    return fmt


def read_net(path: str | Path, net_id: str | None = None, lenient: bool = False) -> Net:
    """A net from a file of any format that has a reader, chosen by its suffix."""
    return reader_of(path).read(path, net_id, lenient)
