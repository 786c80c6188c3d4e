"""The facade: the thin library calls the commands, ``paper_repro``, ``bench``, tests and a
notebook use.

Each call strings the layers together the one way they go: MCL text is parsed and
checked, turned into its functional form (the paper's Algorithm 2) and compiled to one
net (section 2.4); a net is laid out (:mod:`mcl2pnml.view`) and saved in a format of the
table (:mod:`mcl2pnml.io.formats`), or loaded from one; analysed
(:mod:`mcl2pnml.analysis`); run against a vehicle (:mod:`mcl2pnml.runtime`); or shown as
a token-game page. What a command decides and prints is :mod:`mcl2pnml.commands`',
which import this module, never the reverse. A setting that does not fit is a
:class:`~mcl2pnml.core.settings.SettingError` naming the setting.

Heavy modules are imported by the call that needs them, each saying what it costs at
start-up (``python -X importtime -m mcl2pnml --version``), so that ``--version`` and
``check`` load none of numpy (0.1-0.3 s with the analysis), lark (40 ms), lxml (15 ms),
the runtime (0.1 s), graphviz or the certificates' proofs (0.2 s).
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, Callable, Mapping, NamedTuple, Sequence

from mcl2pnml.core.bounds import (MAX_CERTIFICATE_SIZE, MAX_CHAIN_STATES, MAX_CHECK_STATES,
                                  MAX_MISSION_SIZE,
                                  MAX_PROPERTIES_SIZE, MAX_PROPERTY_ATOMS, MAX_TOKENS,
                                  MAX_TOKENS_TEXT, natural_at_most)
from mcl2pnml.core.errors import (Location, Mcl2PnmlError, did_you_mean, line_of, source_lines,
                                  visible)
from mcl2pnml.core.files import atomic_write_text, read_text
from mcl2pnml.core.jsontext import load_json
from mcl2pnml.core.memory import Budget, check_load, guard, release
from mcl2pnml.core.net import Net
from mcl2pnml.core.payloads import MissionPlace
from mcl2pnml.core.settings import SettingError, parse_size, size_or_none
from mcl2pnml.core.timing import Assumptions
from mcl2pnml.io.formats import FORMATS, SUFFIXES, SaveOptions, reader_of
from mcl2pnml.runtime.options import RunOptions
from mcl2pnml.runtime.vehicles import offered

if TYPE_CHECKING:   # for the annotations only
    from mcl2pnml.analysis.report import Analysis
    from mcl2pnml.core.patterns import Property
    from mcl2pnml.language.functional import Instance
    from mcl2pnml.language.semantics import Checked
    from mcl2pnml.odds import Odds
    from mcl2pnml.runtime.engine import Run
    from mcl2pnml.runtime.vehicle_model import VehicleModel
    from mcl2pnml.timed_verdicts import TimedEnds


__all__ = [
    "check_file", "check_source", "warnings_of", "properties_of",
    "compile_file", "compile_source", "compile_checked", "functional_form", "load_net",
    "save_net", "save_queries", "to_pnml_bytes", "save_pnml", "template_net",
    "template_clusters", "templates", "validate_pnml", "analyze", "parse_marking",
    "run_mission", "RunOptions", "show_nets", "save_show_page", "Shown", "certify_file",
    "load_certificate", "check_certificate", "save_certificate", "check_properties",
    "timed_ends", "check_properties_timed", "parse_size", "instance_trees", "call_sites",
    "unflown", "pattern_ends", "simulated_primitives", "exact_odds", "Verdicts", "Certified",
    "call_labels",
]


#: How a net's nodes are placed unless told (``compile --layout``): graphviz dot up to
#: its limit, BFS layers above (:data:`mcl2pnml.view.layout.ENGINES`).
LAYOUT = "auto"
#: The format a net is written in unless told (``--format``).
FORMAT = "pnml"


# -- the language: MCL to a net (section 2.4) ---------------------------------------------

def check_file(path: str | Path, max_size: int | str | None = None) -> "Checked":
    """Parse and check an MCL file (``mcl2pnml check``): the resolved program the compiler
    takes, or one :class:`~mcl2pnml.core.errors.Mcl2PnmlError` giving every error of the
    file, each at its line and column.

    A file over ``max_size`` bytes (or as ``--max-mission-size`` takes it; default
    :data:`~mcl2pnml.core.bounds.MAX_MISSION_SIZE`) is refused before it is read: every
    command and call that reads a mission reads it here. In a notebook the mission shows
    its drawing, its warnings and its text (:mod:`mcl2pnml.notebook`).

    >>> mission = check_file("examples/sauce.mcl")
    >>> mission.summary()
    '4 primitives, 4 tasks, 1 function, 4 consts'
    """
    # lark, 40 ms: only a mission read
    from mcl2pnml.language.semantics import check_program
    from mcl2pnml.language.parser import parse_file
    return check_program(parse_file(path, None, mission_limit(max_size),
                                    "--max-mission-size"))


def mission_limit(max_size: int | str | None = None) -> int:
    """The largest mission read, in bytes: ``max_size`` (or as ``--max-mission-size``
    takes it, :func:`parse_size`), else :data:`~mcl2pnml.core.bounds.MAX_MISSION_SIZE`."""
    if max_size is None:
        return MAX_MISSION_SIZE
    return size_or_none(max_size, "max_mission_size")


def check_source(text: str, filename: str = "<mcl>") -> "Checked":
    """Parse and check MCL text, as :func:`check_file` a file; errors name ``filename``.

    >>> check_source("mission { Dive(); }", "dive.mcl")
    Traceback (most recent call last):
    ...
    mcl2pnml.core.errors.Mcl2PnmlError: dive.mcl:1:11: unknown task or function 'Dive'; ...
    """
    # lark, 40 ms: only a mission read
    from mcl2pnml.language.semantics import check_program
    from mcl2pnml.language.parser import parse
    return check_program(parse(text, filename))


def unflown(checked, vehicle: str, sim_primitives: Sequence[str | Path] = ()
            ) -> list[Mcl2PnmlError]:
    """Each primitive the checked mission's tasks call that ``vehicle`` (as ``run
    --vehicle`` names it, with the simulated primitives of ``sim_primitives``) does not
    offer: an error at its first call in a task, with what the vehicle offers. Empty when
    it offers them all, or answers for any (a script, a vehicle model), as ``run`` finds
    before it starts (section 2.1: the vehicle's side of the abstraction layer)."""
    offers = offered(vehicle, tuple(map(Path, sim_primitives)))
    if offers is None:
        return []
    first: dict[str, tuple[int, int]] = {}   # a primitive not offered -> its first call
    for task in checked.tasks.values():
        for call in task.primitives:
            at = (call.pos.line, call.pos.column)
            if call.name not in offers and at < first.get(call.name, (math.inf, 0)):
                first[call.name] = at
    lines = source_lines(checked.program.source)
    return [Mcl2PnmlError(f"--vehicle {visible(vehicle)} does not offer the primitive "
                          f"'{name}'" + did_you_mean(name, offers, "it offers"),
                          Location(checked.program.file, line, column, line_of(lines, line)))
            for name, (line, column) in sorted(first.items(), key=lambda item: item[1])]


def warnings_of(checked) -> list:
    """The warnings of a checked program (:mod:`mcl2pnml.language.lint`): valid MCL that
    does not do what it seems to say, each with its code, location and fix; those the
    source acknowledges (``// mcl: allow W001 because ...``) left out."""
    from mcl2pnml.language.lint import lint   # lark, 40 ms: only a mission read
    return lint(checked)


def compile_checked(checked, *, reduced: bool = False) -> Net:
    """One composed net (step 2); ``reduced``: every task the paper's reduced model (Fig. 3).

    Templates a user adds (``$MCL2PNML_TEMPLATE_PATH``) are first held to the interface
    contract (:mod:`mcl2pnml.certify.templates`): one that breaks it is refused with the
    run that shows it; the package's own are proven once and stored."""
    # lark, 40 ms: only a mission read
    from mcl2pnml.language.compiler import compile_checked as compile_
    _user_templates_proven()
    return compile_(checked, reduced=reduced)


def _user_templates_proven() -> None:
    from mcl2pnml.language.library import ENV   # lark, 40 ms: only a mission read
    if os.environ.get(ENV):
        # the proven templates, 0.2 s: only to certify
        from mcl2pnml.certify.templates import current
        current()


def properties_of(mission: str | Path, *, extra: str | Path | None = None,
                  reduced: bool = False,
                  max_memory: int | str | None = None, max_size: int | str | None = None,
                  max_atoms: int | None = None, checked=None,
                  max_mission_size: int | str | None = None
                  ) -> tuple[Net, tuple["Property", ...]]:
    """The compiled net of ``mission`` and its properties compiled to predicates on its
    places (:mod:`mcl2pnml.language.declared_properties`): those the mission declares, then those
    of ``extra`` (a side file of ``property`` declarations), each with its location.
    ``reduced``: on the reduced model (Fig. 3), where an atom on a primitive is an error.

    ``extra`` over ``max_size`` bytes (or as ``--max-properties-size`` takes it) is
    refused before it is read, and properties of more than ``max_atoms`` atoms in all
    once parsed, before they are checked (defaults: the limits of
    :mod:`mcl2pnml.core.bounds`). ``checked``: the mission already checked, not read
    again; else it is read within ``max_mission_size`` (:func:`check_file`)."""
    # lark, 40 ms: only a mission read
    from mcl2pnml.language.parser import parse_file
    from mcl2pnml.language.declared_properties import check_atoms, check_side_file, compile_properties
    max_size = size_or_none(max_size, "max_props_size")
    checked = check_file(mission, max_mission_size) if checked is None else checked
    side = None if extra is None else parse_file(
        extra, "properties file", MAX_PROPERTIES_SIZE if max_size is None else max_size,
        "--max-properties-size")
    sources = [checked.program] + ([side] if side is not None else [])
    check_atoms(sources, MAX_PROPERTY_ATOMS if max_atoms is None else max_atoms)
    if side is not None:
        check_side_file(side, checked.program)
    max_memory = size_or_none(max_memory, "max_memory")
    with guard(Budget(max_memory), f"compiling {mission}"):
        net = compile_checked(checked, reduced=reduced)
    return net, compile_properties(net, sources, reduced=reduced)


def compile_file(path: str | Path, *, reduced: bool = False,
                 max_memory: int | str | None = None, checked=None,
                 max_mission_size: int | str | None = None) -> Net:
    """The mission in ``path`` compiled to one net (``mcl2pnml compile``), within the
    memory budget; the net is named after the file. In a notebook it shows its drawing.

    >>> compile_file("examples/sauce.mcl")
    Net('sauce': 203 places, 218 transitions, 948 arcs)

    A mission's net is about as large as its text is long, but only the
    compiling tells how large: it runs under the budget's guard
    (:func:`mcl2pnml.core.memory.guard`; ``max_memory`` in bytes or as
    ``--max-memory`` takes it, default half the memory available), which
    stops it with one message instead of the kernel killing the process.
    ``checked``: the file already checked (:func:`check_file`), not read again; else it
    is read within ``max_mission_size``.
    """
    max_memory = size_or_none(max_memory, "max_memory")
    checked = check_file(path, max_mission_size) if checked is None else checked
    with guard(Budget(max_memory), f"compiling {path}"):
        return compile_checked(checked, reduced=reduced)


def compile_source(text: str, filename: str = "<mcl>", *, name: str | None = None,
                   reduced: bool = False) -> Net:
    """MCL text compiled to one net, as :func:`compile_file` compiles a file: errors name
    ``filename``; the net is called ``name``, else after ``filename`` as a file's is after
    the file (``survey.mcl``: ``survey``), else ``mission``. ``reduced``: every task the
    paper's reduced model (Fig. 3).

    >>> compile_source('''
    ...     primitive KeepDepth(depth);
    ...     task Dive(d) = AchieveGoal(KeepDepth(d)) timeout 60;
    ...     mission { Dive(10); }
    ... ''', name="dive")
    Net('dive': 29 places, 27 transitions, 114 arcs)
    """
    net = compile_checked(check_source(text, filename), reduced=reduced)
    if name is None and filename.startswith("<"):   # no file: <mcl>, <stdin>
        name = "mission"
    return net if name is None else net.renamed(name)


def functional_form(checked, *, functions: bool = False) -> list[str]:
    """Step 1, the paper's Algorithm 2: each function's body (if asked), then the mission."""
    # lark, 40 ms: only a mission read
    from mcl2pnml.language.functional import (format_node, function_expression,
                                              mission_expression)
    lines = []
    if functions:
        for name in checked.function_order:
            f = checked.functions[name]
            lines.append(f"{name}({', '.join(f.params)}) = "
                         f"{format_node(function_expression(f))}")
    lines.append(format_node(mission_expression(checked.mission)))
    return lines


# -- nets in files -------------------------------------------------------------------------

def load_net(path: str | Path, net_id: str | None = None,
             max_memory: int | str | None = None, lenient: bool = False,
             max_mission_size: int | str | None = None) -> Net:
    """A net from any file: a mission (``.mcl``, compiled) or a format of the table.

    A PNML file is read strictly (docs/pnml.md: refused, or read as the net other
    tools read), or with ``lenient`` the forgiving way, which no proof trusts.
    ``net_id`` chooses one net of a file that holds several (PNML). A net file
    that reading could not hold within ``max_memory`` (bytes, or as
    ``--max-memory`` takes it; default half the memory available) is refused
    before it is read (:func:`mcl2pnml.core.memory.check_load`).
    """
    if Path(path).suffix != ".mcl":
        max_memory = size_or_none(max_memory, "max_memory")
        # the strict PNML reading streams: its need is the net's, not a tree's
        check_load(path, Budget(max_memory),
                   streamed=not lenient and reader_of(path).name == "pnml")
        net = reader_of(path).read(path, net_id, lenient)
        release()   # the parsed file is freed: what the analysis may use is back
        return net
    if net_id is not None:
        raise SettingError("net_id", "a mission compiles to one net; leave out --net")
    if lenient:
        raise SettingError("lenient", "a mission is compiled, not read as PNML; leave out "
                                      "--lenient")
    return compile_file(path, max_memory=max_memory, max_mission_size=max_mission_size)


def save_net(net: Net, path: str | Path, fmt: str = FORMAT, *, layout: str = LAYOUT,
             title: str | None = None, mission: bool = False,
             clusters: Mapping[str, Sequence[str]] | None = None,
             expand: Sequence[str] | None = (), timing: "Assumptions | None" = None,
             note: Callable[[str], None] = lambda line: None,
             labels: Mapping[str, str] | None = None) -> Path:
    """Write ``net`` to ``path`` in format ``fmt`` (a name of the format table).

    ``layout`` places the nodes where the format keeps positions (PNML):
    ``auto``, ``dot``, ``layers`` or ``none``; with dot, the arcs' bend points
    too. ``mission``: a compiled mission, whose TINA file follows the
    executor's timing. A drawing (svg, png, dot) shows ``clusters`` as boxes
    (:func:`template_clusters` for a template), or a mission one call at a time: the
    calls ``expand`` names (by default its own net; None: every call), their callees
    shut, each box named by ``labels`` (:func:`call_labels`). ``timing``: what the vehicle is
    assumed to do, for the formats that write a mission's timed semantics (tapn). ``note`` hears
    what the format could not say of the net (PIPE's: the time-outs' delays).
    """
    form = FORMATS.get(fmt)
    if form is None:
        raise ValueError(f"unknown format {fmt!r}; known: {', '.join(FORMATS)}")
    drawn = _drawn(net, layout) if "positions" in form.options else None
    drawing = (_drawing(net, title, clusters, expand, labels) if "drawing" in form.options
               else None)
    said = form.write(net, path, SaveOptions(positions=drawn and drawn.positions,
                                            bends=drawn and drawn.bends, drawing=drawing,
                                            urgent=mission, timing=timing))
    for line in said:
        note(f"{Path(path).name} ({form.title}): {line}")
    return Path(path)


def save_pnml(net: Net, path: str | Path, layout_engine: str = LAYOUT) -> Path:
    """``net`` as PNML at ``path``, laid out by ``layout_engine`` (written whole or not at all)."""
    return save_net(net, path, "pnml", layout=layout_engine)


def save_queries(net: Net, path: str | Path, tool: str):
    """The compiled mission's properties for ``tool`` (verifypn or lola) in the Model Checking
    Contest's XML (:mod:`mcl2pnml.io.mccquery`), with the ids of its PNML; returns them."""
    from mcl2pnml.io.mccquery import write_queries as save   # 25 ms: only the contest's queries
    return save(net, path, tool)


def save_property_queries(properties, stem: str | Path):
    """A mission's properties in the Model Checking Contest's categories, one file each,
    ``STEM.LTLCardinality.xml`` and so on (:mod:`mcl2pnml.io.mccquery`); the files written."""
    # 25 ms: only the contest's queries
    from mcl2pnml.io.mccquery import write_property_queries as save
    return save(properties, stem)


def to_pnml_bytes(net: Net, layout_engine: str = LAYOUT) -> bytes:
    """``net`` as a PNML document, laid out by ``layout_engine``."""
    from mcl2pnml.io.pnml.writer import to_pnml as write   # lxml, 15 ms: only a PNML file
    drawn = _drawn(net, layout_engine)
    return write(net, drawn and drawn.positions, drawn and drawn.bends)


def _drawing(net: Net, title: str | None, clusters: Mapping[str, Sequence[str]] | None,
             expand: Sequence[str] | None, labels: Mapping[str, str] | None) -> str:
    """The DOT text of ``net``'s drawing (:func:`mcl2pnml.view.drawing.drawing`)."""
    from mcl2pnml.view.drawing import drawing   # graphviz, 0.03 s: only for a drawing
    return drawing(net, title, clusters=clusters, expand=expand, labels=labels).source


def call_labels(checked) -> dict[str, str]:
    """Each instance of the mission ``checked`` compiles to, named as MCL writes it
    (``Dive(Depth)``, ``task Dive(d)``: :func:`mcl2pnml.language.functional.call_labels`)."""
    # lark comes with the language's package, 40 ms: only a mission's drawing or page
    from mcl2pnml.language.functional import call_labels as labels
    return labels(checked)


def _drawn(net: Net, layout: str):
    """Node positions and arc bend points from ``layout``, in whole points (None for
    ``none``, which imports nothing of the view)."""
    if layout == "none":
        return None
    from mcl2pnml.view.layout import drawn_layout   # graphviz, 15 ms: only a layout
    return drawn_layout(net, layout).whole()


def validate_pnml(path: str | Path, grammar: str | Path | None = None,
                  net_id: str | None = None):
    """The verdict on a PNML file of our schema, of the official grammar when ``grammar``
    gives it (else ``$MCL2PNML_PNML_GRAMMAR``'s: :func:`mcl2pnml.io.pnml.grammar.find_grammar`)
    and of the reader's rules; and the net when it is valid."""
    # lxml, 15 ms: only a PNML file
    from mcl2pnml.io.pnml.grammar import validate
    from mcl2pnml.io.pnml.reader import read_pnml
    check_load(path, Budget())   # the schemas read the file whole too
    verdict = validate(path, grammar, net_id)
    return verdict, (read_pnml(path, net_id) if verdict.valid else None)


# -- the paper's nets ----------------------------------------------------------------------

def templates() -> list[tuple[str, str, str]]:
    """Every template: its names, its kind, its one-line description."""
    from mcl2pnml.language.library import default_library   # lark, 40 ms: only a mission read
    return [(", ".join(t.names), t.kind.value, t.doc) for t in default_library().unique()]


def template_net(name: str) -> Net:
    """Template ``name`` composed as the paper analyses it, from its M0."""
    from mcl2pnml.language.library import default_library   # lark, 40 ms: only a mission read
    return default_library().composed(name)


def template_clusters(name: str) -> dict[str, list[str]]:
    """The boxes of template ``name``'s drawing: the nodes each slot brings in (the
    primitive of a task, T1 and T2 of a structure), as Figs. 2 and 4 draw them."""
    from mcl2pnml.language.library import default_library   # lark, 40 ms: only a mission read
    return default_library().slots(name)


def pattern_ends(name: str, timeout: bool = True) -> tuple[tuple[str, ...], bool]:
    """The results a task of pattern ``name`` ends in, started and not aborted (aborted,
    every task ends ABORTED), with or without a ``timeout``, and whether it may instead
    run for ever: as the pattern's proof against the interface contract gives them
    (:mod:`mcl2pnml.certify.templates`, ``templates/proofs.json``; a user's pattern is
    proven when asked). ``KeepGoal`` without a time-out ends FAIL only."""
    # the proven templates, 0.2 s: only when a pattern's results are asked for
    from mcl2pnml.certify.templates import current
    row = current()[name if timeout else f"{name} without a time-out"]["results"][""]
    return tuple(row["ends"]), bool(row["stuck"])


# -- certificates (sections 2.3-2.5: proven from the parts) --------------------------------

class Certified(NamedTuple):
    """A mission's certificate, its net, and what the independent checker finds wrong with
    the pair (nothing: it holds); a notebook shows whether it holds."""

    certificate: dict[str, Any]
    net: Net
    problems: list[str]


def certify_file(mission: str | Path, abort_pending: bool = False,
                 max_mission_size: int | str | None = None) -> Certified:
    """The certificate of ``mission`` (``mcl2pnml certify``,
    :mod:`mcl2pnml.certify.certificate`): the mission proven 1-safe, free of deadlocks,
    ending properly and reusable from its parts (sections 2.3-2.5), without exploring;
    with its compiled net (``mission.A`` marked too if ``abort_pending``) and what the
    independent checker finds wrong with the pair (nothing: it holds).

    >>> certified = certify_file("examples/sauce.mcl")
    >>> certified.problems, certified.certificate["mission"]
    ([], 'sauce')
    """
    checked = check_file(mission, max_mission_size)
    net = compile_checked(checked)
    if abort_pending:
        net = net.with_initial({**net.initial, MissionPlace.A.id: 1})
    cert, problems = _certified(checked, net, abort_pending)
    return Certified(cert, net, problems)


def load_certificate(path: str | Path, max_size: int | str = MAX_CERTIFICATE_SIZE
                     ) -> dict[str, Any]:
    """A certificate read back and held to its schema (:mod:`mcl2pnml.certify.form`): a
    file over ``max_size`` bytes (checked before reading it), or that is not JSON, or not of
    the certificate's shape, is one error naming it, with the line and column or the JSON
    path of the fault."""
    from mcl2pnml.certify import form   # the certificate's schema: only a certificate read
    limit = size_or_none(max_size, "max_cert")
    text = read_text(path, "certificate", limit, "--max-certificate-size")
    cert = load_json(text, str(path), "a certificate")
    if not isinstance(cert, dict) or cert.get("format") != form.FORMAT:
        raise Mcl2PnmlError(f"not a certificate of format {form.FORMAT} (`mcl2pnml certify` "
                            "writes them)", Location(str(path), 1, 1))
    faults = form.shape_faults(cert)
    if faults:
        more = f" (and {len(faults) - 1} more)" if len(faults) > 1 else ""
        raise Mcl2PnmlError(f"the certificate is malformed at {faults[0]}{more}",
                            Location(str(path)))
    return cert


def check_certificate(net: Net, cert: dict[str, Any], *, shaped: bool = False) -> list[str]:
    """What the independent checker finds wrong with ``cert`` for ``net`` (nothing: it
    holds); ``shaped``: :func:`load_certificate` held it to its schema already."""
    # the proven templates, 0.2 s: only to certify
    from mcl2pnml.certify.recheck import check_certificate
    return check_certificate(net, cert, shaped=shaped)


def certificate_beside(file: Path) -> Path:
    """Where ``certify`` writes the certificate of ``file`` (a mission, or its net)."""
    return file.with_name(file.stem + ".cert.json")


def save_certificate(cert: dict[str, Any], path: str | Path) -> Path:
    atomic_write_text(path, json.dumps(cert, indent=2) + "\n")
    return Path(path)


# -- analysis ------------------------------------------------------------------------------

class Verdicts(list):
    """Each property's verdict, in order (a list of
    :class:`~mcl2pnml.analysis.checking.on_graph.Verdict`), which a notebook shows as one
    table."""


def analyze(net: Net, initial: dict[str, int] | None = None, **options: Any) -> "Analysis":
    """Invariants, siphons and reachable markings, and the paper's verdicts (bounded,
    1-safe, free of deadlocks, ends properly, reusable): ``mcl2pnml analyze``
    (:func:`mcl2pnml.analysis.report.analyze`, which says the options);
    ``max_memory`` may be written as ``--max-memory`` takes it (:func:`parse_size`).

    >>> facts = analyze(compile_file("examples/sauce.mcl")).facts
    >>> facts.states, facts.safe, facts.ends_properly, facts.reusable
    (1509, True, True, True)
    """
    from mcl2pnml.analysis.report import analyze as run   # numpy, 0.1 s: only to analyse
    options["max_memory"] = size_or_none(options.get("max_memory"), "max_memory")
    return run(net, initial, **options)


def check_properties(net: Net, properties, max_states: int = MAX_CHECK_STATES,
                     stubborn: bool = False, safe: bool = False) -> Verdicts:
    """Each property's :class:`mcl2pnml.analysis.checking.on_graph.Verdict` on ``net``'s runs, in order:
    holds, fails with a shortest counterexample, or unknown past ``max_states``; each
    searched on the fly (:mod:`mcl2pnml.analysis.checking.on_the_fly`), stopping at its first violation.
    ``stubborn``: with partial-order reduction, on a net ``safe`` says is proven 1-safe
    (else a P-invariant must prove it: :class:`~mcl2pnml.analysis.checking.on_the_fly.NotProvenSafe`).
    The properties are :func:`properties_of`'s.

    >>> net, properties = properties_of("examples/sauce.mcl", extra="examples/sauce.props")
    >>> [v.status.value for v in check_properties(net, properties)][:4]
    ['holds', 'holds', 'holds', 'holds']
    """
    # numpy, 0.1 s: only an analysis
    from mcl2pnml.analysis.checking.on_graph import check_properties
    return Verdicts(check_properties(net, properties, max_states, stubborn=stubborn, safe=safe))


def proven_safe_by_certificate(mission: Path, net: Net,
                               max_mission_size: int | str | None = None) -> bool:
    """Whether the mission's certificate, made now from its parts, holds for ``net``: the
    checker then proves it 1-safe (:mod:`mcl2pnml.certify`)."""
    _, problems = _certified(check_file(mission, max_mission_size), net)
    return not problems


def _certified(checked, net: Net, abort_pending: bool = False
               ) -> tuple[dict[str, Any], list[str]]:
    """The certificate of the checked mission, and what the independent checker finds
    wrong with it for ``net`` (nothing: it holds)."""
    # the proven templates, 0.2 s: only to certify
    from mcl2pnml.certify.certificate import certify
    from mcl2pnml.certify.recheck import check_certificate
    from mcl2pnml.certify.templates import current
    proofs = current()      # read once, for the certificate and its check
    cert = certify(checked, net_name=net.name, abort_pending=abort_pending, proofs=proofs)
    # checked as it will be read back: plain JSON
    return cert, check_certificate(net, json.loads(json.dumps(cert)), proofs)


def parse_marking(text: str, net: Net, where: str = "") -> dict[str, int]:
    """A marking written ``P,Q*2`` (``analyze --initial``): place -> tokens."""
    marking: dict[str, int] = {}
    for item in filter(None, (i.strip() for i in text.split(","))):
        place, _, count = item.partition("*")
        if count and not (count.isdigit() and count.isascii()):
            raise SettingError("initial", f"'{item[:40]}': a count is a natural number "
                                          "(P*2)")
        tokens = natural_at_most(count, MAX_TOKENS) if count else 1
        if tokens is None or marking.get(place, 0) + tokens > MAX_TOKENS:
            raise SettingError("initial", f"'{item[:40]}': too many tokens; a place holds "
                                          f"at most {MAX_TOKENS_TEXT}")
        marking[place] = marking.get(place, 0) + tokens
    unknown = sorted(p for p in marking if p not in net.place_index)
    if unknown:
        raise SettingError("initial", f"no place {', '.join(unknown)} in {where or net.name}"
                          + did_you_mean(unknown[0], net.place_index, "places"))
    return marking


# -- running -------------------------------------------------------------------------------

def _engine_for(mission: Path, net_id: str | None, lenient: bool = False,
                max_mission_size: int | str | None = None) -> Callable[[str], Any]:
    """How to build each engine for ``mission`` (the reference engine reads MCL only)."""
    def make(kind: str):
        from mcl2pnml.runtime.executor import PetriEngine   # the runtime, 30 ms: only a run
        if mission.suffix == ".mcl":
            checked = check_file(mission, max_mission_size)
            if kind == "reference":
                # the runtime, 30 ms: only a run
                from mcl2pnml.runtime.reference import ReferenceEngine
                return ReferenceEngine(checked)
            return PetriEngine(compile_checked(checked))
        if kind == "reference":
            raise SettingError("engine", "the reference engine reads MCL, not a net; give "
                                         "the .mcl file")
        from mcl2pnml.io.pnml.reader import read_pnml   # lxml, 15 ms: only a PNML file
        check_load(mission, Budget())
        return PetriEngine(read_pnml(mission, net_id, lenient))
    if lenient and mission.suffix == ".mcl":
        raise SettingError("lenient", "a mission is compiled, not read as PNML; leave out "
                                      "--lenient")
    return make


def run_mission(mission: str | Path, options: RunOptions | None = None, *,
                text: IO[str] | None = None, log_path: str | Path | None = None,
                note: Callable[[str], None] = lambda line: None, net_id: str | None = None,
                lenient: bool = False, max_mission_size: int | str | None = None) -> "Run":
    """Run ``mission`` (MCL, or a compiled PNML for the Petri-net engine) against a vehicle
    (``mcl2pnml run``; ``options`` as its options, :class:`RunOptions`: the simulated AUV
    by default); ``lenient``: a PNML read the forgiving way (docs/pnml.md).

    Returns the run (outcome, time, trace, safe stop); see
    :func:`mcl2pnml.runtime.session.run_session` for the rest.

    >>> run = run_mission("examples/sauce.mcl")
    >>> run.outcome.value, round(run.time, 1)
    ('OK', 55.4)
    """
    from mcl2pnml.runtime.session import run_session   # the runtime, 0.1 s: only a run
    mission = Path(mission)
    return run_session(mission, options or RunOptions(),
                       _engine_for(mission, net_id, lenient, max_mission_size), text=text,
                       log_path=Path(log_path) if log_path else None, note=note)


def simulated_primitives() -> list[tuple[str, str, str, str]]:
    """What each primitive of the simulated vehicle does (``run --vehicle sim``,
    docs/simulator.md): its name, its arguments, when it reports achieved and when failed,
    in words; the built-in ones and those installed packages add, by name."""
    # the simulator's table, 25 ms with the entry points: only when it is asked for
    from mcl2pnml.runtime.simprims import installed, table_rows
    return table_rows(installed())


# -- the token game ------------------------------------------------------------------------

@dataclass(frozen=True)
class Shown:
    """What the token-game page shows: its title, its nets with their labels (the first
    the one a recorded run plays on), and a mission's functional form (Algorithm 2):
    the mission's tree, then each function's, each node named after its instance."""

    title: str
    nets: list[tuple[Net, str]]
    trees: list[tuple[str, list["Instance"]]] = field(default_factory=list)
    #: The boxes of each net's drawing by its label: a template's slots (the primitive of
    #: Fig. 2's task, T1 and T2 of Fig. 4); a net without, each instance in its box.
    boxes: dict[str, dict[str, list[str]]] = field(default_factory=dict)
    #: A mission's calls named as MCL writes them (:func:`call_labels`): the page opens
    #: its nets one call at a time.
    labels: dict[str, str] | None = None
    #: Each net as the page draws it, made by the first page written: a run does not
    #: change it, so the pages of many runs of one mission (a counterexample's each,
    #: ``analyze --counterexamples``) lay the mission out and explore it once.
    drawn: list[dict[str, Any]] = field(default_factory=list, compare=False, repr=False)


def show_nets(what: str, *, with_run: bool = False, net_id: str | None = None,
              lenient: bool = False, max_mission_size: int | str | None = None) -> Shown:
    """The page's title, the nets it shows for ``what``, each with its label, and the tree.

    A mission: the mission and its reduced model (Fig. 3), and its
    functional form; a net file: the net; a pattern: the task with its
    primitive (Fig. 2) and the reduced task; a structure: as the paper
    analyses it. ``with_run``: a recorded run will be followed, which only a
    mission or its net can have.
    """
    path = Path(what)
    if net_id is not None and path.suffix.lower() not in SUFFIXES:
        raise SettingError("net_id", "only a net file (PNML) may hold several nets; leave "
                                     "out --net")
    if path.suffix == ".mcl" or path.suffix.lower() in SUFFIXES:
        if not path.is_file():
            raise SettingError("what", f"no file '{what}'")
        if path.suffix != ".mcl":
            return Shown(path.stem, [(load_net(path, net_id, lenient=lenient), "the net")])
        checked = check_file(path, max_mission_size)
        return Shown(path.stem, [(compile_checked(checked), "the mission"),
                                 (compile_checked(checked, reduced=True),
                                  "the mission, every task reduced (Fig. 3)")],
                     instance_trees(checked), labels=call_labels(checked))
    if with_run:
        raise SettingError("run_log", "a run is of a mission: give the mission's .mcl or "
                                      "its compiled net, not a template")
    # lark, 40 ms: only a mission read
    from mcl2pnml.language.library import default_library
    from mcl2pnml.language.template_parser import TemplateKind
    lib = default_library()
    template = lib.get(what)   # unknown: the error lists the templates
    if template.kind is TemplateKind.PATTERN:
        full, reduced = f"{what} with its primitive (Fig. 2)", "its reduced model (Fig. 3)"
        return Shown(what, [(lib.composed(what), full), (lib.composed(lib.reduced.name), reduced)],
                     boxes={full: lib.slots(what), reduced: lib.slots(lib.reduced.name)})
    label = f"{what}, as the paper analyses it"
    return Shown(what, [(lib.composed(what), label)], boxes={label: lib.slots(what)})


def save_show_page(path: str | Path, shown: Shown,
                   run_log: str | Path | None = None) -> Path:
    """The token-game page of ``shown``, following the run of ``run_log`` if given."""
    from mcl2pnml.view.show import check_run, read_run, save_page   # graphviz, 65 ms
    entries = None
    if run_log is not None:
        entries = read_run(run_log)
        check_run(shown.nets[0][0], entries, str(run_log))
    tree = drawn(shown)
    save_page(path, shown.title, shown.drawn, entries, tree)
    return Path(path)


def drawn(shown: Shown) -> dict[str, Any]:
    """The page's tree of the mission; its nets drawn into ``shown.drawn`` by the first
    page, which the pages after take as they are."""
    from mcl2pnml.view.show import tree_data, variant   # graphviz, 65 ms: only a page
    tree = tree_data(shown.trees)
    if not shown.drawn:
        shown.drawn.extend(variant(net, label, tree, shown.boxes.get(label), shown.labels)
                           for net, label in shown.nets)
    return tree


def instance_trees(checked) -> list[tuple[str, list["Instance"]]]:
    """The mission's functional form, then each function's, as the compiled net names their
    instances (:func:`mcl2pnml.language.functional.instances`): the page's tree, and
    where each instance of the net comes from."""
    # lark, 40 ms: only a mission read
    from mcl2pnml.language.functional import instance_trees as trees
    return trees(checked)


def call_sites(checked) -> dict:
    """Each instance of the checked mission's net, by name (``Goto-2``, ``while-1``), with
    its call as written or its structure's kind, and its line
    (:class:`mcl2pnml.timed_verdicts.Site`): where an answer about the net is in the MCL."""
    from mcl2pnml.timed_verdicts import Site   # numpy, 0.2 s: only timed
    return {i.name: Site(i.label, i.line) for _, tree in instance_trees(checked) for i in tree}


# -- time in the verdicts (docs/time.md) --------------------------------------------------

def timed_ends(net: Net, assumptions: "Assumptions | None" = None,
               max_states: int = MAX_CHECK_STATES,
               max_memory: int | str | None = None) -> "TimedEnds":
    """Whether every run of the compiled mission ``net`` ends under ``assumptions`` (the
    defaults of :class:`~mcl2pnml.core.timing.Assumptions` if None), its earliest and
    latest end times, and what a run that never ends waits for
    (:class:`mcl2pnml.timed_verdicts.TimedEnds`); past ``max_states`` zones or the
    memory budget (``max_memory``, as ``analyze --max-memory``), unknown, saying why.

    >>> ends = timed_ends(compile_source("primitive KeepDepth(d); "
    ...                                  "task Dive(d) = AchieveGoal(KeepDepth(d)) timeout 60; "
    ...                                  "mission { Dive(10); }"))
    >>> ends.always_ends, ends.earliest, ends.latest
    (True, Fraction(0, 1), Fraction(60, 1))
    """
    from mcl2pnml import timed_verdicts as timed   # numpy, 0.2 s: only timed
    return timed.ends(net, assumptions or Assumptions(), max_states,
                      Budget(size_or_none(max_memory, "max_memory")))


def check_properties_timed(net: Net, properties, assumptions: "Assumptions | None" = None,
                           max_states: int = MAX_CHECK_STATES,
                           max_memory: int | str | None = None) -> Verdicts:
    """Each property's :class:`mcl2pnml.analysis.checking.on_graph.Verdict` on the mission's time-divergent
    runs (docs/time.md); past ``max_states`` zones or the memory budget, unknown."""
    from mcl2pnml import timed_verdicts as timed   # numpy, 0.2 s: only timed
    return Verdicts(timed.check_properties_timed(
        net, properties, assumptions or Assumptions(), max_states,
        Budget(size_or_none(max_memory, "max_memory"))))


# -- the odds (docs/odds.md) --------------------------------------------------------------

def exact_odds(net: Net, vehicle_model: "str | Path | VehicleModel", properties: Sequence = (),
               max_states: int = MAX_CHAIN_STATES) -> "Odds":
    """The exact odds of the compiled mission ``net`` with a vehicle model (``mcl2pnml
    odds``, :mod:`mcl2pnml.odds`): the probability of each ending, the end time's
    distribution, and the probability that each of ``properties`` holds. The model is a
    file (docs/odds.md) or one loaded; one that models a primitive the mission does not
    use is refused. Past ``max_states`` instants of the chain, an error says so.

    >>> from mcl2pnml.runtime.vehicle_model import VehicleModel
    >>> net = compile_source("primitive KeepDepth(d); "
    ...                      "task Dive(d) = AchieveGoal(KeepDepth(d)) timeout 60; "
    ...                      "mission { Dive(10); }")
    >>> model = VehicleModel.from_json('''{"primitives": {"KeepDepth":
    ...     {"achieve": 0.9, "fail": 0.1, "after": {"fixed": 5}}}}''')
    >>> odds = exact_odds(net, model)
    >>> print(f"P(OK) = {odds.exact['OK']}, ends after {odds.mean} s on average")
    P(OK) = 9/10, ends after 5.0 s on average
    """
    # the chain's engine, vehicle model and solver: numpy, scipy, the runtime; only odds
    from mcl2pnml import odds as exact
    from mcl2pnml.runtime.executor import PetriEngine
    from mcl2pnml.runtime.vehicle_model import VehicleModel
    model = vehicle_model if isinstance(vehicle_model, VehicleModel) else \
        VehicleModel.load(vehicle_model)
    model.check_primitives(PetriEngine(net).primitives_used())
    return exact.odds_of(exact.chain_of(net, model, max_states, properties))
