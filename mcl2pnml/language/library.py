"""The template library: every ``*.pnt`` file of ``templates/``, loaded and composed.

Adding a file adds a pattern or a structure, with no code change (the
paper's section 5 asks for a language that grows this way). The library is
the package's own ``templates/`` directory (installed as
``mcl2pnml.templates``), plus the directories listed in the environment
variable ``MCL2PNML_TEMPLATE_PATH`` (separated by ``os.pathsep``), whose
files may add templates or replace ours of the same name.

:meth:`Library.composed` builds the net the paper analyses for a template:

* a primitive or the reduced task: its own net;
* a pattern: fused with one primitive per slot, on the primitive's interface
  places (the task of Fig. 2 with the primitive of Fig. 1);
* a structure: fused with one reduced task per slot, on its control places
  (the sequence of Fig. 4 with two reduced tasks).

Subordinate nets enter at rest: their start places B and A unmarked, so
that the composed net starts from the paper's M0 (``{B, A, MTX, T1_MTX,
T2_MTX}`` for the sequence).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

from mcl2pnml.core.compose import glue, prefixed
from mcl2pnml.core.errors import Mcl2PnmlError, did_you_mean
from mcl2pnml.core.net import Marking, Net
from mcl2pnml.language.template_parser import Template, TemplateKind, load_template

ENV = "MCL2PNML_TEMPLATE_PATH"
SUFFIX = ".pnt"


def source_places(net: Net) -> frozenset[str]:
    """Places no transition of the net writes to: its inputs from outside."""
    written = {a.target for a in net.arcs if a.target in net.place_index}
    return frozenset(p.id for p in net.places if p.id not in written)


#: The control places a caller marks: the paper's M0 has them, a net at rest does not.
START = ("B", "A")


def at_rest(net: Net) -> Net:
    """The net with its start places B and A unmarked: ready to be called."""
    start = {p.id for p in net.places if p.interface in START}
    return net.with_initial({p: n for p, n in net.initial.items() if p not in start})


def template_dirs() -> list[Path]:
    dirs = [Path(str(resources.files("mcl2pnml.templates")))]
    extra = os.environ.get(ENV, "")
    dirs.extend(Path(d) for d in extra.split(os.pathsep) if d)
    return dirs


@dataclass(frozen=True)
class Library:
    """Templates by name (and alias), with the one primitive and reduced task."""

    templates: dict[str, Template]
    primitive: Template
    reduced: Template

    @classmethod
    def load(cls, dirs: list[Path] | None = None) -> "Library":
        files: dict[str, Path] = {}
        for d in dirs if dirs is not None else template_dirs():
            if not d.is_dir():
                raise Mcl2PnmlError(f"template directory '{d}' does not exist (from ${ENV})")
            for f in sorted(d.glob(f"*{SUFFIX}")):
                files[f.name] = f  # a later directory replaces a file of the same name
        primitives = [f for f in files.values() if _kind_of(f) == "primitive"]
        if len(primitives) != 1:
            raise Mcl2PnmlError(f"the template library needs exactly one primitive template, "
                                f"found {len(primitives)}: {', '.join(map(str, primitives))}")
        primitive = load_template(primitives[0])
        interface = tuple(p.id for p in primitive.net.places if p.interface is not None)
        templates: dict[str, Template] = {}
        for f in files.values():
            t = primitive if f == primitives[0] else load_template(f, interface)
            for name in t.names:
                if name in templates:
                    raise Mcl2PnmlError(f"template name '{name}' is used by both "
                                        f"{templates[name].source} and {t.source}")
                templates[name] = t
        reduced = [t for t in set(templates.values()) if t.kind is TemplateKind.REDUCED]
        if len(reduced) != 1:
            raise Mcl2PnmlError("the template library needs exactly one reduced task template, "
                                f"found {len(reduced)}")
        return cls(templates, primitive, reduced[0])

    def get(self, name: str) -> Template:
        try:
            return self.templates[name]
        except KeyError:
            raise Mcl2PnmlError(f"unknown template '{name}'"
                                + did_you_mean(name, self.templates, "templates")) from None

    def unique(self) -> list[Template]:
        """Each template once, in a stable order: primitive, patterns, reduced, structures."""
        order = {k: i for i, k in enumerate(TemplateKind)}
        seen = {id(t): t for t in self.templates.values()}
        return sorted(seen.values(), key=lambda t: (order[t.kind], t.name.lower()))

    def slots(self, name: str) -> dict[str, list[str]]:
        """The nodes each slot of template ``name`` brings into :meth:`composed`, its
        fusion places included: the primitive of a task (Fig. 2), T1 and T2 of a
        structure (Fig. 4); the boxes of the template's drawing."""
        t = self.get(name)
        if t.kind is TemplateKind.PATTERN:
            prim = self.primitive.net
            return {("primitive " + slot if slot else "primitive"):
                    [f"{slot}_{n.id}" if slot else n.id for n in (*prim.places, *prim.transitions)]
                    for slot in t.primitives}
        if t.kind is TemplateKind.STRUCTURE:
            child = self.reduced.net
            return {slot: [f"{slot}_{n.id}" for n in (*child.places, *child.transitions)]
                    for slot in t.children}
        return {}

    def composed(self, name: str, children: tuple[Net, ...] | None = None) -> Net:
        """The net the paper analyses for template ``name``, from the paper's M0;
        ``children``: a structure's child in each slot (default: the reduced task)."""
        t = self.get(name)
        if t.kind is TemplateKind.PATTERN:
            parts = [prefixed(at_rest(self.primitive.net), slot) for slot in t.primitives]
        elif t.kind is TemplateKind.STRUCTURE:
            children = children or (self.reduced.net,) * len(t.children)
            parts = [prefixed(at_rest(child), slot) for slot, child in zip(t.children, children)]
        else:
            parts = []
        net = glue([t.net, *parts], name=name)
        return net.with_initial(Marking(net.initial))


def _kind_of(path: Path) -> str | None:
    """The first word of a template's header, read cheaply (comments skipped)."""
    try:
        for line in path.read_text(encoding="utf-8").splitlines():
            words = line.split("#", 1)[0].split()
            if words:
                return words[0]
    except (OSError, UnicodeDecodeError):
        return None
    return None


@lru_cache(maxsize=1)
def default_library() -> Library:
    """The library of the installed package (and $MCL2PNML_TEMPLATE_PATH), loaded once."""
    return Library.load()
