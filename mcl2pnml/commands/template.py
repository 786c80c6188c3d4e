"""``mcl2pnml template NAME``: the paper's net NAME written (a pattern fused with its
primitive, a structure with reduced tasks in its slots), or ``--list`` of them all."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mcl2pnml import pipeline
from mcl2pnml.commands.common import FORMAT
from mcl2pnml.core.errors import visible
from mcl2pnml.core.net import Net
from mcl2pnml.core.progress import Notes
from mcl2pnml.core.settings import UsageProblem
from mcl2pnml.io.formats import FORMATS


@dataclass(frozen=True)
class TemplateOptions:
    """``template``'s settings, by the names of its options (``--help`` says each)."""

    #: where the net goes (None: PNML to standard output, or NAME.suffix)
    output: Path | None = None
    fmt: str = FORMAT


@dataclass(frozen=True)
class TemplateList:
    """Every template: its names, its kind, its one-line description."""

    rows: tuple[tuple[str, str, str], ...]

    def lines(self) -> list[str]:
        width = max(len(names) for names, _, _ in self.rows)
        return [f"{names.ljust(width)}  {kind:<9}  {doc}" for names, kind, doc in self.rows]

    def as_json(self) -> dict[str, Any]:
        return {"templates": [{"names": n, "kind": k, "doc": d} for n, k, d in self.rows]}


@dataclass(frozen=True)
class TemplateOutcome:
    """A template's net, written to ``output``, or (None) to be printed as ``pnml``."""

    net: Net
    output: Path | None
    pnml: str | None = None

    def lines(self) -> list[str]:
        return []

    def as_json(self) -> dict[str, Any]:
        return {"net": self.net.name, "output": None if self.output is None
                else str(self.output)}


def templates() -> TemplateList:
    """``mcl2pnml template --list``."""
    return TemplateList(tuple(pipeline.templates()))


def template(name: str | None, options: TemplateOptions = TemplateOptions(), *,
             notes: Notes | None = None) -> TemplateOutcome:
    """``mcl2pnml template NAME`` with ``options``: PNML to standard output (the outcome's
    ``pnml``) unless a file or another format is asked for."""
    if name is None:
        raise UsageProblem("give a template NAME, or --list")
    notes = Notes() if notes is None else notes
    net = pipeline.template_net(name)
    if options.output is None and options.fmt == "pnml":
        return TemplateOutcome(net, None, pipeline.to_pnml_bytes(net).decode())
    output = options.output or Path(name + FORMATS[options.fmt].suffixes[0])
    pipeline.save_net(net, output, options.fmt, clusters=pipeline.template_clusters(name),
                      expand=None, note=notes)
    notes(f"wrote {visible(str(output))}: {net.summary()}")
    return TemplateOutcome(net, output)
