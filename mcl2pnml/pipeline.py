"""The pipeline facade: the few calls that the CLI, ``paper_repro``, ``bench`` and tests use.

Each call strings the layers together the one way they go: MCL text is
parsed and checked, turned into its functional form (the paper's
Algorithm 2) and compiled to one net (section 2.4); a net is laid out
(:mod:`mcl2pnml.view`) and saved in a format of the table
(:mod:`mcl2pnml.io.formats`), or loaded from one; analysed
(:mod:`analysis`); run against a vehicle (:mod:`mcl2pnml.runtime`); or
shown as a token-game page. The layers below never import this module.

Heavy modules (numpy, lxml, graphviz, numba) are imported by the call that
needs them, so that ``mcl2pnml --version`` and ``mcl2pnml check`` start
fast.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, Callable, Mapping, Sequence

from mcl2pnml.core.errors import OptionError
from mcl2pnml.core.net import Net
from mcl2pnml.io.formats import FORMATS, SaveOptions, reader_of

if TYPE_CHECKING:
    from mcl2pnml.core.patterns import Property
    from mcl2pnml.core.timing import Assumptions
    from mcl2pnml.language.functional import Instance
    from mcl2pnml.campaign import SchedulerTimeouts
    from mcl2pnml.odds import Odds
    from mcl2pnml.runtime.session import RunOptions


def __getattr__(name: str) -> Any:
    # the run's options come with the runtime, which only `run` needs: a command that
    # does not run a mission does not pay for importing it
    if name == "RunOptions":
        from mcl2pnml.runtime.session import RunOptions
        return RunOptions
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

__all__ = [
    "check_file", "check_source", "warnings_of", "properties_of", "compile_file", "compile_source", "functional_form",
    "load_net", "save_net", "save_queries", "to_pnml_bytes", "save_pnml", "template_net", "template_clusters", "templates",
    "validate_pnml", "analyze", "parse_marking", "run_mission", "RunOptions", "show_nets", "save_show_page", "serve_show_live",
    "Shown", "save_reachability_json", "analyze_file", "AnalyzeOutcome", "compile_mission",
    "certify_command",
]


# -- the language: MCL to a net (section 2.4) ---------------------------------------------

def check_file(path: str | Path, max_size: int | str | None = None):
    """Parse and check an MCL file: the resolved program the compiler takes.

    A file over ``max_size`` bytes (or as ``--max-mission-size`` takes it; default
    :data:`~mcl2pnml.core.bounds.MAX_MISSION_SIZE`) is refused before it is read: every
    command and call that reads a mission reads it here."""
    from mcl2pnml.language.semantics import check_program
    from mcl2pnml.language.parser import parse_file
    return check_program(parse_file(path, None, mission_limit(max_size), "--max-mission-size"))


def mission_limit(max_size: int | str | None = None) -> int:
    """The largest mission read, in bytes: ``max_size`` (or as ``--max-mission-size``
    takes it, :func:`parse_size`), else :data:`~mcl2pnml.core.bounds.MAX_MISSION_SIZE`."""
    from mcl2pnml.core.bounds import MAX_MISSION_SIZE
    if max_size is None:
        return MAX_MISSION_SIZE
    return parse_size(max_size, "--max-mission-size") if isinstance(max_size, str) else max_size


def check_source(text: str, filename: str = "<mcl>"):
    """Parse and check MCL text; errors name ``filename``."""
    from mcl2pnml.language.semantics import check_program
    from mcl2pnml.language.parser import parse
    return check_program(parse(text, filename))


def warnings_of(checked) -> list:
    """The warnings of a checked program (:mod:`mcl2pnml.language.lint`): valid MCL that
    does not do what it seems to say, each with its code, location and fix; those the
    source acknowledges (``// mcl: allow W001 because ...``) left out."""
    from mcl2pnml.language.lint import lint
    return lint(checked)


def compile_checked(checked, *, reduced: bool = False) -> Net:
    """One composed net (step 2); ``reduced``: every task the paper's reduced model (Fig. 3).

    Templates a user adds (``$MCL2PNML_TEMPLATE_PATH``) are first held to the interface
    contract (:mod:`mcl2pnml.certify.templates`): one that breaks it is refused with the
    run that shows it; the package's own are proven once and stored."""
    from mcl2pnml.language.compiler import compile_checked as compile_
    _user_templates_proven()
    return compile_(checked, reduced=reduced)


def _user_templates_proven() -> None:
    import os

    from mcl2pnml.language.library import ENV
    if os.environ.get(ENV):
        from mcl2pnml.certify.templates import current
        current()


def properties_of(mission: Path, *, extra: Path | None = None, reduced: bool = False,
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
    from mcl2pnml.core.bounds import MAX_PROPERTIES_SIZE, MAX_PROPERTY_ATOMS
    from mcl2pnml.language.parser import parse_file
    from mcl2pnml.language.declared_properties import check_atoms, check_side_file, compile_properties
    if isinstance(max_size, str):
        max_size = parse_size(max_size, "--max-properties-size")
    checked = check_file(mission, max_mission_size) if checked is None else checked
    side = None if extra is None else parse_file(
        extra, "properties file", MAX_PROPERTIES_SIZE if max_size is None else max_size,
        "--max-properties-size")
    sources = [checked.program] + ([side] if side is not None else [])
    check_atoms(sources, MAX_PROPERTY_ATOMS if max_atoms is None else max_atoms)
    if side is not None:
        check_side_file(side, checked.program)
    from mcl2pnml.core.memory import Budget, guard
    if isinstance(max_memory, str):
        max_memory = parse_size(max_memory)
    with guard(Budget(max_memory), f"compiling {mission}"):
        net = compile_checked(checked, reduced=reduced)
    return net, compile_properties(net, sources, reduced=reduced)


def compile_file(path: str | Path, *, reduced: bool = False,
                 max_memory: int | str | None = None, checked=None,
                 max_mission_size: int | str | None = None) -> Net:
    """The mission in ``path`` compiled to one net, within the memory budget.

    A mission's net is about as large as its text is long, but only the
    compiling tells how large: it runs under the budget's guard
    (:func:`mcl2pnml.core.memory.guard`; ``max_memory`` in bytes or as
    ``--max-memory`` takes it, default half the memory available), which
    stops it with one message instead of the kernel killing the process.
    ``checked``: the file already checked (:func:`check_file`), not read again; else it
    is read within ``max_mission_size``.
    """
    from mcl2pnml.core.memory import Budget, guard
    if isinstance(max_memory, str):
        max_memory = parse_size(max_memory)
    checked = check_file(path, max_mission_size) if checked is None else checked
    with guard(Budget(max_memory), f"compiling {path}"):
        return compile_checked(checked, reduced=reduced)


def compile_source(text: str, filename: str = "<mcl>", *, reduced: bool = False) -> Net:
    return compile_checked(check_source(text, filename), reduced=reduced)


def functional_form(checked, *, functions: bool = False) -> list[str]:
    """Step 1, the paper's Algorithm 2: each function's body (if asked), then the mission."""
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
        from mcl2pnml.core.memory import Budget, check_load, release
        if isinstance(max_memory, str):
            max_memory = parse_size(max_memory)
        # the strict PNML reading streams: its need is the net's, not a tree's
        check_load(path, Budget(max_memory),
                   streamed=not lenient and reader_of(path).name == "pnml")
        net = reader_of(path).read(path, net_id, lenient)
        release()   # the parsed file is freed: what the analysis may use is back
        return net
    if net_id is not None:
        raise OptionError("--net", "a mission compiles to one net; leave out --net")
    if lenient:
        raise OptionError("--lenient", "a mission is compiled, not read as PNML; leave out "
                                       "--lenient")
    return compile_file(path, max_memory=max_memory, max_mission_size=max_mission_size)


def save_net(net: Net, path: str | Path, fmt: str = "pnml", *, layout: str = "auto",
             title: str | None = None, mission: bool = False,
             clusters: Mapping[str, Sequence[str]] | None = None,
             expand: Sequence[str] | None = (), timing: "Assumptions | None" = None,
             note: Callable[[str], None] = lambda line: None) -> Path:
    """Write ``net`` to ``path`` in format ``fmt`` (a name of the format table).

    ``layout`` places the nodes where the format keeps positions (PNML):
    ``auto``, ``dot``, ``layers`` or ``none``; with dot, the arcs' bend points
    too. ``mission``: a compiled mission, whose TINA file follows the
    executor's timing. A drawing (svg, png, dot) shows ``clusters`` as boxes
    (None: a mission's calls, :func:`template_clusters` for a template) and
    opens those ``expand`` names (None: all). ``timing``: what the vehicle is assumed to
    do, for the formats that write a mission's timed semantics (tapn). ``note`` hears
    what the format could not say of the net (PIPE's: the time-outs' delays).
    """
    form = FORMATS.get(fmt)
    if form is None:
        raise ValueError(f"unknown format {fmt!r}; known: {', '.join(FORMATS)}")
    drawn = _drawn(net, layout) if "positions" in form.options else None
    drawing = _drawing(net, title, clusters, expand) if "drawing" in form.options else None
    said = form.write(net, path, SaveOptions(positions=drawn and drawn.positions,
                                            bends=drawn and drawn.bends, drawing=drawing,
                                            urgent=mission, timing=timing))
    for line in said:
        note(f"{Path(path).name} ({form.title}): {line}")
    return Path(path)


def save_timed_queries(net: Net, net_path: str | Path, timing: "Assumptions | None" = None,
                       properties=()):
    """The queries verifydtapn checks a mission's timed-arc net (``compile --format tapn``)
    against, written beside it (an end always reached, a dead state that is not an end, the
    safety its clocks rest on, the properties a state formula says; :mod:`mcl2pnml.io.tapn`);
    returns each file, its query and the k-bound to give verifydtapn."""
    from mcl2pnml.io.tapn import write_queries as save
    return save(net, net_path, timing, properties)


def timed_query_paths(net: Net, net_path: str | Path, timing: "Assumptions | None" = None,
                      properties=()) -> list[Path]:
    """The files :func:`save_timed_queries` would write, to check them as outputs first."""
    from mcl2pnml.io.tapn import query_paths
    return query_paths(net, net_path, timing, properties)


def save_deadline(net: Net, path: str | Path, seconds, timing: "Assumptions | None" = None):
    """A mission's timed-arc net with an observer of time ``seconds`` at ``path``, and
    beside it the query "some run has no result at that time" (:mod:`mcl2pnml.io.tapn`);
    returns the net's file, the query's, and the k-bound to give verifydtapn."""
    from mcl2pnml.io.tapn import write_deadline as save
    return save(net, path, seconds, timing)


def save_pnml(net: Net, path: str | Path, layout_engine: str = "auto") -> Path:
    """``net`` as PNML at ``path``, laid out by ``layout_engine`` (written whole or not at all)."""
    return save_net(net, path, "pnml", layout=layout_engine)


def save_queries(net: Net, path: str | Path, tool: str = "verifypn"):
    """The compiled mission's properties for ``tool`` (verifypn or lola) in the Model Checking
    Contest's XML (:mod:`mcl2pnml.io.mccquery`), with the ids of its PNML; returns them."""
    from mcl2pnml.io.mccquery import write_queries as save
    return save(net, path, tool)


def save_property_queries(properties, stem: str | Path):
    """A mission's properties in the Model Checking Contest's categories, one file each,
    ``STEM.LTLCardinality.xml`` and so on (:mod:`mcl2pnml.io.mccquery`); the files written."""
    from mcl2pnml.io.mccquery import write_property_queries as save
    return save(properties, stem)


def to_pnml_bytes(net: Net, layout_engine: str = "auto") -> bytes:
    """``net`` as a PNML document, laid out by ``layout_engine``."""
    from mcl2pnml.io.pnml.writer import to_pnml as write
    drawn = _drawn(net, layout_engine)
    return write(net, drawn and drawn.positions, drawn and drawn.bends)


def _drawing(net: Net, title: str | None, clusters: Mapping[str, Sequence[str]] | None,
             expand: Sequence[str] | None) -> str:
    """The DOT text of ``net``'s drawing (:func:`mcl2pnml.view.drawing.drawing`)."""
    from mcl2pnml.view.drawing import drawing   # graphviz, 0.03 s: only for a drawing
    return drawing(net, title, clusters=clusters, expand=expand).source


def _drawn(net: Net, layout: str):
    """Node positions and arc bend points from ``layout``, in whole points (None for
    ``none``, which imports nothing of the view)."""
    if layout == "none":
        return None
    from mcl2pnml.view.layout import drawn_layout
    return drawn_layout(net, layout).whole()


def validate_pnml(path: str | Path, grammar: str | Path | None = None,
                  net_id: str | None = None):
    """The verdict on a PNML file of our schema, of the official grammar when ``grammar``
    gives it (or it is found: :func:`mcl2pnml.io.pnml.grammar.find_grammar`) and of the
    reader's rules; and the net when it is valid."""
    from mcl2pnml.core.memory import Budget, check_load
    from mcl2pnml.io.pnml.grammar import validate
    from mcl2pnml.io.pnml.reader import read_pnml
    check_load(path, Budget())   # the schemas read the file whole too
    verdict = validate(path, grammar, net_id)
    return verdict, (read_pnml(path, net_id) if verdict.valid else None)


# -- the paper's nets ----------------------------------------------------------------------

def templates() -> list[tuple[str, str, str]]:
    """Every template: its names, its kind, its one-line description."""
    from mcl2pnml.language.library import default_library
    return [(", ".join(t.names), t.kind.value, t.doc) for t in default_library().unique()]


def template_net(name: str) -> Net:
    """Template ``name`` composed as the paper analyses it, from its M0."""
    from mcl2pnml.language.library import default_library
    return default_library().composed(name)


def template_clusters(name: str) -> dict[str, list[str]]:
    """The boxes of template ``name``'s drawing: the nodes each slot brings in (the
    primitive of a task, T1 and T2 of a structure), as Figs. 2 and 4 draw them."""
    from mcl2pnml.language.library import default_library
    return default_library().slots(name)


# -- certificates (sections 2.3-2.5: proven from the parts) --------------------------------

def certify_file(mission: str | Path, abort_pending: bool = False,
                 max_mission_size: int | str | None = None
                 ) -> tuple[dict[str, Any], Net, list[str]]:
    """The certificate of ``mission`` (:mod:`mcl2pnml.certify.certificate`), its compiled
    net (with ``mission.A`` marked too if ``abort_pending``), and what the independent
    checker finds wrong with the pair (nothing: it holds)."""
    from mcl2pnml.core.payloads import MissionPlace
    checked = check_file(mission, max_mission_size)
    net = compile_checked(checked)
    if abort_pending:
        net = net.with_initial({**net.initial, MissionPlace.A.id: 1})
    cert, problems = _certified(checked, net, abort_pending)
    return cert, net, problems


#: The largest certificate read, unless raised (``--max-certificate-size``): a 10,000-call
#: survey's is 3.3 MB; read as JSON, a file takes about fifteen times its size in memory.
MAX_CERTIFICATE = 16 * 2**20


def load_certificate(path: str | Path, max_size: int | str = MAX_CERTIFICATE
                     ) -> dict[str, Any]:
    """A certificate read back and held to its schema (:mod:`mcl2pnml.certify.form`): a
    file over ``max_size`` bytes (checked before reading it), or that is not JSON, or not of
    the certificate's shape, is one error naming it, with the line and column or the JSON
    path of the fault."""
    from mcl2pnml.certify import form
    from mcl2pnml.core.errors import Location, Mcl2PnmlError
    from mcl2pnml.core.files import read_text
    from mcl2pnml.core.jsontext import load_json
    limit = parse_size(max_size, "--max-certificate-size") if isinstance(max_size, str) \
        else max_size
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
    from mcl2pnml.certify.recheck import check_certificate
    return check_certificate(net, cert, shaped=shaped)


def certificate_beside(file: Path) -> Path:
    """Where ``certify`` writes the certificate of ``file`` (a mission, or its net)."""
    return file.with_name(file.stem + ".cert.json")


def certified_facts(net: Net, cert_path: Path, max_size: int | str = MAX_CERTIFICATE
                    ) -> tuple[dict[str, Any] | None, list[str]]:
    """What a certificate proves of ``net``, as ``analyze`` reports it, if it holds for
    ``net``; else None and what the checker found. The facts are the checker's: the ends
    are the ones it derived (the certificate must say exactly those to hold)."""
    cert = load_certificate(cert_path, max_size)
    problems = check_certificate(net, cert, shaped=True)
    if problems:
        return None, problems
    facts = {"bounded": True, "safe": True, "deadlock_free": True, "ends_properly": True,
             "final_always_reachable": True, "reusable": True,
             "certificate": {"file": str(cert_path), "holds": True,
                             "ends": cert["conclusion"]["ends"]}}
    return facts, []


def save_certificate(cert: dict[str, Any], path: str | Path) -> Path:
    from mcl2pnml.core.files import atomic_write_text
    atomic_write_text(path, json.dumps(cert, indent=2) + "\n")
    return Path(path)


# -- analysis ------------------------------------------------------------------------------

def analyze(net: Net, initial: dict[str, int] | None = None, **options: Any) -> dict[str, Any]:
    """Invariants, siphons and reachable markings (:func:`mcl2pnml.analysis.report.analyze`);
    ``max_memory`` may be written as ``--max-memory`` takes it (:func:`parse_size`)."""
    from mcl2pnml.analysis.report import analyze as run
    if isinstance(options.get("max_memory"), str):
        options["max_memory"] = parse_size(options["max_memory"])
    return run(net, initial, **options)


def check_properties(net: Net, properties, max_states: int = 1_000_000,
                     stubborn: bool = False, safe: bool = False) -> list:
    """Each property's :class:`mcl2pnml.analysis.checking.on_graph.Verdict` on ``net``'s runs, in order:
    holds, fails with a shortest counterexample, or unknown past ``max_states``; each
    searched on the fly (:mod:`mcl2pnml.analysis.checking.on_the_fly`), stopping at its first violation.
    ``stubborn``: with partial-order reduction, on a net ``safe`` says is proven 1-safe
    (else a P-invariant must prove it: :class:`~mcl2pnml.analysis.checking.on_the_fly.NotProvenSafe`)."""
    from mcl2pnml.analysis.checking.on_graph import check_properties
    return check_properties(net, properties, max_states, stubborn=stubborn, safe=safe)


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
    from mcl2pnml.certify.certificate import certify
    from mcl2pnml.certify.recheck import check_certificate
    from mcl2pnml.certify.templates import current
    proofs = current()      # read once, for the certificate and its check
    cert = certify(checked, net_name=net.name, abort_pending=abort_pending, proofs=proofs)
    # checked as it will be read back: plain JSON
    return cert, check_certificate(net, json.loads(json.dumps(cert)), proofs)


#: How many failing properties ``analyze`` explains, unless told (``--max-counterexamples``):
#: each costs its replay on both engines, at times a search of the engines' own runs, and
#: four files, so that thousands of failing properties would take minutes to hours.
MAX_COUNTEREXAMPLES = 100


def witnesses(mission: Path, net: Net, verdicts, most: int | None = None,
              timing: "Assumptions | None" = None,
              max_mission_size: int | str | None = None) -> list:
    """For each verdict, its :class:`~mcl2pnml.counterexample.Witness` when it fails
    (the counterexample in the mission's terms, the vehicle script that replays a violation
    on both engines, or why none does), else None. ``net`` is ``mission``'s compiled net.
    ``most``: only the first ``most`` failing verdicts are explained, the others' are None,
    and cost nothing."""
    from mcl2pnml.counterexample import witness
    checked = check_file(mission, max_mission_size)
    out, left = [], most
    for v in verdicts:
        if v.shape is None or left == 0:
            out.append(None)
            continue
        out.append(witness(net, checked, v.property, v.transitions, shape=v.shape.value,
                           loop=v.loop, timing=timing))
        left = None if left is None else left - 1
    return out


def verdicts_json(verdicts, witnesses=None) -> list[dict[str, Any]]:
    """Verdicts as ``analyze --json`` prints them: each failing one with its counterexample
    as the checker found it, ``explained`` saying whether its witness was computed (given
    here, ``analyze --explain``), and the witness's parts when it was."""
    out = []
    for k, v in enumerate(verdicts):
        w = witnesses[k] if witnesses else None
        cex = None if v.shape is None else {
            "shape": v.shape.value, "transitions": list(v.transitions),
            "loop": v.loop, "markings": [dict(m) for m in v.markings],
            "explained": w is not None}
        if cex is not None and w is not None:
            cex["mission"] = w.run.lines()
            cex["vehicle_script"] = None if w.replayed is None else w.replayed.script
            cex["replayed"] = None if w.replayed is None else {
                "same_run": w.replayed is w.run, "mission": w.replayed.lines(),
                "transitions": [s.transition for s in w.replayed.steps],
                "detail": w.replay.detail}
            cex["why_not"] = w.why_not
        out.append({"name": v.property.name, "text": v.property.text,
                    "location": v.property.location.prefix() if v.property.location else None,
                    "status": v.status.value, "states": v.states, "reason": v.reason,
                    "counterexample": cex})
    return out


#: What ``analyze`` says under a counterexample it did not explain, unasked.
EXPLAIN_HINT = ("  (--explain: this run in the mission's terms, and a vehicle script that "
                "replays it on both engines)")


def witness_text(v, w, hint: bool = False) -> list[str]:
    """A verdict as ``analyze --properties`` prints it: the firing sequence, the same run in
    the mission's terms, and the vehicle script that replays a violation, or why none does;
    without a witness, ``hint``: how to ask for it (:data:`EXPLAIN_HINT`)."""
    where = v.property.location.prefix() if v.property.location else "-"
    line = f"property {v.property.name} ({where}): {v.status.value}"
    if v.reason:
        line += f" ({v.reason}, {v.states:,} states)"
    out = [line]
    if v.shape is None:
        return out
    out.append(f"  counterexample ({v.shape.value}):")
    for k, t in enumerate(v.transitions, 1):
        loop = "  <- the cycle starts here" if v.loop is not None and k == v.loop + 1 else ""
        out.append(f"  {k:4}. {t}{loop}")
    if v.loop is not None:
        out.append(f"  then again from step {v.loop + 1}, forever")
    if w is None:
        return out + [EXPLAIN_HINT] * hint
    out.append("  in the mission's terms (step numbers in brackets):")
    out += [f"  {line}" for line in w.run.lines()]
    if w.replayed is not None and w.replayed is not w.run:
        out.append(f"  a vehicle script cannot lead the engines along it: {w.why_not}")
        out.append(f"  a run the engines take that violates it too ({w.replayed.shape}, "
                   f"{len(w.replayed.steps)} firings):")
        out += [f"  {line}" for line in w.replayed.lines()]
    if w.replayed is not None:
        out.append("  vehicle script (run --vehicle; both engines reach the violation): "
                   + json.dumps(w.replayed.script))
        if w.replayed.loop is not None:
            from mcl2pnml.counterexample import CYCLE_REPEATS
            out.append(f"  (the cycle's replies {CYCLE_REPEATS} times over: a vehicle that goes "
                       "on answering so keeps the mission in the cycle forever)")
    else:
        out.append(f"  no vehicle script replays it: {w.why_not}")
    return out


def make_folder(folder: Path) -> Path:
    """``folder`` made if missing (with its parents), or one error naming it."""
    from mcl2pnml.core.errors import Location, Mcl2PnmlError
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise Mcl2PnmlError(f"cannot make the folder: {e.strerror or e}",
                            Location(str(folder))) from None
    return folder


def witness_files(folder: Path, name: str) -> dict[str, Path]:
    """The files :func:`save_witness` may write for the property ``name`` in ``folder``,
    by what they hold: every one, so that they can be checked against the inputs before
    anything is written."""
    return {kind: folder / f"{name}.{suffix}" for kind, suffix in
            (("text", "txt"), ("script", "vehicle.json"), ("log", "log"), ("page", "html"))}


def save_witness(folder: Path, mission: Path, v, w, shown: "Shown | None" = None) -> list[Path]:
    """A failing property's files in ``folder``: NAME.txt (:func:`witness_text`),
    NAME.vehicle.json (the script, if any), NAME.log (the run as ``run --log`` writes it:
    the replayed run if any, else the counterexample) and NAME.html (``show``'s page
    following that run step by step). ``shown``: the mission's page content
    (:func:`show_nets`), when the caller writes several and has it already."""
    from mcl2pnml.core.files import atomic_write_text
    make_folder(folder)
    files = witness_files(folder, v.property.name)
    written = [files["text"]]
    atomic_write_text(files["text"], "\n".join(witness_text(v, w)) + "\n")
    run = w.replayed or w.run
    if w.replayed is not None:
        written.append(files["script"])
        atomic_write_text(files["script"], w.replayed.script_json())
    atomic_write_text(files["log"], "".join(json.dumps(e) + "\n" for e in run.run_log()))
    save_show_page(files["page"], shown or show_nets(str(mission), with_run=True), files["log"])
    return [*written, files["log"], files["page"]]


def parse_size(text: str, option: str = "--max-memory") -> int:
    """A size in bytes written ``4G``, ``500M``, ``64K`` or ``1000000`` (powers of 1024)."""
    units = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}
    number, unit = text.strip().upper().rstrip("B"), ""
    if number and number[-1] in units:
        number, unit = number[:-1], number[-1]
    try:
        size = float(number) * units[unit]
    except ValueError:
        raise OptionError(option, f"'{text}': a size is a number with K, M, G or T (4G, 500M)")
    if size < 1:
        raise OptionError(option, f"'{text}': a size is at least one byte")
    return int(size)


def parse_marking(text: str, net: Net, where: str = "") -> dict[str, int]:
    """A marking written ``P,Q*2`` (``analyze --initial``): place -> tokens."""
    from mcl2pnml.core.bounds import MAX_TOKENS, MAX_TOKENS_TEXT, natural_at_most
    from mcl2pnml.core.errors import did_you_mean
    marking: dict[str, int] = {}
    for item in filter(None, (i.strip() for i in text.split(","))):
        place, _, count = item.partition("*")
        if count and not (count.isdigit() and count.isascii()):
            raise OptionError("--initial", f"'{item[:40]}': a count is a natural number (P*2)")
        tokens = natural_at_most(count, MAX_TOKENS) if count else 1
        if tokens is None or marking.get(place, 0) + tokens > MAX_TOKENS:
            raise OptionError("--initial", f"'{item[:40]}': too many tokens; a place holds "
                                           f"at most {MAX_TOKENS_TEXT}")
        marking[place] = marking.get(place, 0) + tokens
    unknown = sorted(p for p in marking if p not in net.place_index)
    if unknown:
        raise OptionError("--initial", f"no place {', '.join(unknown)} in {where or net.name}"
                          + did_you_mean(unknown[0], net.place_index, "places"))
    return marking


def analysis_text(result: dict[str, Any]) -> str:
    from mcl2pnml.analysis.report import render_text
    return render_text(result)


# -- the commands' decisions, for the CLI to print ---------------------------------------

def warned(mission: Path, checked, strict: bool = False,
           note: Callable[[str], None] = lambda line: None) -> list:
    """The mission's warnings (:func:`warnings_of`), each line handed to ``note`` (the CLI's
    standard error); with ``strict``, one or more refuse the mission (exit 2), before
    anything is written."""
    from mcl2pnml.core.errors import Mcl2PnmlError
    from mcl2pnml.language.lint import shown
    found = warnings_of(checked)
    for line in shown(found):
        note(line)
    if strict and found:
        n = len(found)
        raise Mcl2PnmlError(f"{mission}: {n} warning{'s' * (n != 1)}, which --strict makes "
                            "errors (fix them, or acknowledge one that is meant with "
                            "// mcl: allow CODE because ... on the line before it)")
    return found


def properties_lines(compiled) -> list[str]:
    """``check --properties``: each property compiled to place formulas, its pattern's
    (P, S, the bound) then its scope's (Q, R)."""
    from mcl2pnml.core.patterns import describe
    out = []
    for prop in compiled:
        scope = prop.scope
        q = f": Q = {describe(scope.q)}" if scope.q is not None else ""
        r = "" if scope.r is None else f"{'; ' if q else ': '}R = {describe(scope.r)}"
        out += [f"property {prop.name} ({prop.location.prefix()}): {prop.text}",
                f"  {prop.pattern.value}: P = {describe(prop.p)}"
                + (f"; S = {describe(prop.s)}" if prop.s is not None else "")
                + (f"; at most {prop.bound} times" if prop.bound is not None else ""),
                f"  {scope.kind.value}{q}{r}"]
    return out or ["no properties"]


def compile_timing(fmt: str, ack_within: str | None, report_gap: str | None
                   ) -> "Assumptions | None":
    """What the vehicle is assumed to do, for a format that says it (tapn; supervisor steps
    urgent, not first: the timed-arc tools' semantics); refused for any other."""
    from fractions import Fraction

    from mcl2pnml.core.timing import Assumptions, seconds_option
    if fmt == "tapn":
        return Assumptions(
            ack_within=Fraction(0) if ack_within is None
            else seconds_option(ack_within, "--ack-within"),
            report_gap=Fraction(1) if report_gap is None
            else seconds_option(report_gap, "--report-gap"), priority=False)
    if ack_within is not None or report_gap is not None:
        raise OptionError("--ack-within" if ack_within is not None else "--report-gap",
                          "only a timed-arc net (--format tapn) says what the vehicle is "
                          f"assumed to do, not {fmt}")
    return None


def compile_mission(mission: Path, output: Path | None = None, fmt: str = "pnml", *,
                    layout_engine: str = "auto", expand: str = "", queries: Path | None = None,
                    tool: str = "verifypn", max_memory: str | None = None,
                    ack_within: str | None = None, report_gap: str | None = None,
                    properties: str | None = None, max_props_size=None, max_atoms=None,
                    strict: bool = False, max_mission_size: int | str | None = None,
                    note: Callable[[str], None] = lambda line: None) -> list[Path]:
    """``mcl2pnml compile``, its options by their names: the net and what goes beside it
    (the queries, the properties' files, a timed-arc net's queries), every output checked
    against the inputs and each other before anything is written; each line said handed to
    ``note``. Returns the files written."""
    from mcl2pnml.core.files import check_outputs
    from mcl2pnml.io.mccquery import property_query_files
    output = output or mission.with_suffix(FORMATS[fmt].suffixes[0])
    if queries is not None and queries.resolve() == output.resolve():
        raise OptionError("--queries", "the queries go in a file of their own, not the net's")
    if expand and "drawing" not in FORMATS[fmt].options:
        raise OptionError("--expand", f"only a drawing has boxes to open, not {fmt}: "
                                      "--format svg, png or dot")
    timing = compile_timing(fmt, ack_within, report_gap)
    stem = output.with_suffix("") if output.suffix else output
    extra = None if properties is None else properties_file(mission, properties)
    inputs = [("the mission", mission), ("the properties file (--properties)", extra)]
    outputs = [("-o", output), ("--queries", queries)]
    check_outputs(outputs + [("--properties", path) for path in
                             (property_query_files(stem).values() if properties is not None
                              else ())], inputs)
    checked = check_file(mission, max_mission_size)   # its warnings before anything is written
    warned(mission, checked, strict, note)
    net, props = _compiled_with_properties(mission, checked, properties, extra, max_memory,
                                           max_props_size, max_atoms)
    if timing is not None:   # the queries beside the net: none of them an input
        check_outputs(outputs + [("-o", path) for path in
                                 timed_query_paths(net, output, timing, props)], inputs)
    opened = None if expand == "all" else tuple(n for n in expand.split(",") if n)
    save_net(net, output, fmt, layout=layout_engine, title=mission.name, mission=True,
             expand=opened, timing=timing, note=note)
    note(f"wrote {output}: {net.summary()}")
    return [output, *_saved_beside(net, output, timing, queries, tool, props, stem, note)]


def _compiled_with_properties(mission: Path, checked, properties: str | None,
                              extra: Path | None, max_memory, max_size, max_atoms):
    """The compiled net, and with ``--properties`` the properties, at least one."""
    if properties is None:
        return compile_file(mission, max_memory=max_memory, checked=checked), ()
    net, props = properties_of(mission, extra=extra, max_memory=max_memory, max_size=max_size,
                               max_atoms=max_atoms, checked=checked)
    if not props:
        raise OptionError("--properties", f"{mission} declares no property, and there is no "
                                          f"{properties or mission.with_suffix('.props')} "
                                          "beside it")
    return net, props


def _saved_beside(net: Net, output: Path, timing, queries: Path | None, tool: str, props,
                  stem: Path, note: Callable[[str], None]) -> list[Path]:
    """What ``compile`` writes beside the net: a timed-arc net's queries, the Model
    Checking Contest's queries, the properties in its categories."""
    written = []
    if timing is not None:
        note(f"timed semantics: {timing.words()}")
        for path, query, bound in save_timed_queries(net, output, timing, props):
            note(f"wrote {path}: {query.description} (verifydtapn -k {bound} {output} {path})")
            written.append(Path(path))
    if queries is not None:
        saved = save_queries(net, queries, tool)
        note(f"wrote {queries}: {', '.join(p.id for p in saved)} (for {tool})")
        written.append(queries)
    for path, qs in save_property_queries(props, stem) if props else ():
        note(f"wrote {path}: {len(qs)} {'query' if len(qs) == 1 else 'queries'}")
        written.append(Path(path))
    return written


def certify_command(mission: Path, output: Path | None = None, net_file: Path | None = None,
                    net_id: str | None = None, abort_pending: bool = False,
                    max_cert: int | str = MAX_CERTIFICATE,
                    note: Callable[[str], None] = lambda line: None,
                    max_mission_size: int | str | None = None
                    ) -> tuple[dict[str, Any], Net, list[str]]:
    """``mcl2pnml certify``: the mission certified and its certificate written (only if it
    holds), or with ``net_file`` a certificate re-checked against that net; the certificate,
    the net and what the checker finds wrong (nothing: it holds)."""
    from mcl2pnml.core.files import check_outputs
    if net_file is not None:
        if output is not None:
            raise OptionError("-o", "--check writes nothing")
        cert = load_certificate(mission, max_cert)
        net = load_net(net_file, net_id, max_mission_size=max_mission_size)
        return cert, net, check_certificate(net, cert, shaped=True)
    if net_id is not None:
        raise OptionError("--net", "only --check reads a net file")
    if mission.suffix != ".mcl":
        raise OptionError("MISSION", f"'{mission}' is not a mission (.mcl); to re-check a "
                                     "certificate, add --check NET.pnml")
    output = output or mission.with_name(mission.stem + ".cert.json")
    check_outputs([("-o", output)], [("the mission", mission)])
    cert, net, problems = certify_file(mission, abort_pending, max_mission_size)
    if not problems:
        save_certificate(cert, output)
        note(f"wrote {output}")
    return cert, net, problems


def certificate_lines(net: Net, cert: dict[str, Any], problems: Sequence[str]) -> list[str]:
    """What ``certify`` prints: what does not hold, or what the certificate proves."""
    if problems:
        return [f"{net.name}: the certificate does not hold:", *(f"  {p}" for p in problems)]
    instances = sum(len(t) for t in cert.get("trees", {}).values())
    tasks, functions = len(cert["tasks"]), len(cert["functions"])
    return [f"{net.name}: certified from its parts ({instances} instances, "
            f"{tasks} task{'s' * (tasks != 1)}, {functions} function"
            f"{'s' * (functions != 1)}): 1-safe, an end always reachable, reusable; every end "
            "one of " + ", ".join(cert["conclusion"]["ends"])]


# -- a file analysed, as ``mcl2pnml analyze`` does it --------------------------------------

@dataclass(frozen=True)
class AnalyzeOutcome:
    """What one :func:`analyze_file` found and did, for the CLI to print and a test or a
    notebook to read, so that none of them decides anything again.

    ``result``: the analysis (:func:`analyze`, with a certificate's facts where one beside
    the file holds; empty for a timed one); ``verdicts``: the properties' (None without
    ``properties``); ``witnesses``: beside them, each failing one's explanation
    (:func:`witnesses`), None for those not explained, and None in all when none was asked
    for; ``timed``: the timed ends (:func:`timed_ends`) of a timed analysis; ``messages``:
    what was said on the way, standard error's, in order; ``written``: the counterexample
    files; ``status``: the exit status (0 ok, 1 a property fails, 3 a partial answer, a
    property unknown, or the ends undecided).
    """

    result: dict[str, Any]
    verdicts: tuple | None = None
    witnesses: tuple | None = None
    timed: Any = None
    messages: tuple[str, ...] = ()
    written: tuple[Path, ...] = ()
    status: int = 0
    #: The text says, under a counterexample not explained, how to ask (``--explain``):
    #: no explanation was asked for, and one could be (the run starts at the mission's start).
    hint: bool = False

    def as_json(self) -> dict[str, Any]:
        """The object ``analyze --json`` prints."""
        out = dict(self.result)
        if self.verdicts is not None:
            out["properties"] = verdicts_json(self.verdicts, self.witnesses)
        if self.timed is not None:
            out["timed"] = self.timed.as_json()
        return out

    def lines(self) -> list[str]:
        """What ``analyze`` prints: the analysis (or the timed ends), then each verdict."""
        out = ["\n".join(self.timed.lines()) if self.timed is not None
               else analysis_text(self.result)]
        for k, v in enumerate(self.verdicts or ()):
            out += witness_text(v, self.witnesses[k] if self.witnesses else None, self.hint)
        return out


def analyze_file(file: str | Path, *, initial: str | None = None, state_space: bool = False,
                 max_states: int = 5_000_000, explorer: str = "auto",
                 max_memory: int | str | None = None, net_id: str | None = None,
                 properties: str | None = None, counterexamples: str | Path | None = None,
                 explain: bool = False, explore: bool = False,
                 max_counterexamples: int | None = MAX_COUNTEREXAMPLES,
                 max_props_size: int | str | None = None, max_atoms: int | None = None,
                 max_cert: int | str = MAX_CERTIFICATE, timed: bool | None = None,
                 ack_within: str = "0", report_gap: str = "1", fair_reports: bool = False,
                 urgency_only: bool = False, stubborn: bool = False, lenient: bool = False,
                 max_mission_size: int | str | None = None,
                 progress: Callable[[int, int], None] | None = None,
                 note: Callable[[str], None] = lambda line: None) -> AnalyzeOutcome:
    """``mcl2pnml analyze FILE``, its options by their names (``--help`` says them), as one
    call that the CLI, the tests and a notebook share.

    It decides what the command does: timed or not (a mission's properties are about
    the runs it has, in time, unless ``timed`` says otherwise), a certificate beside the
    file taken instead of exploring, the properties checked, and the counterexamples
    explained (in the mission's terms, replayed on both engines: the costly part) only
    when ``explain`` or ``counterexamples`` asks, up to ``max_counterexamples``, and
    written in the folder ``counterexamples``. ``properties``: ``--properties [FILE]``'s
    value ("" for MISSION.props). Each message is handed to ``note`` when it is said (the
    CLI prints it on standard error) and kept in the outcome; an input or an option that
    does not fit raises the project's errors (:class:`~mcl2pnml.core.errors.OptionError`,
    :class:`~mcl2pnml.core.errors.Mcl2PnmlError`) before anything is explored or written.
    """
    file = Path(file)
    folder = None if counterexamples is None else Path(counterexamples)
    _explanations_possible(properties, initial, folder, explain)
    if timed is None:   # a mission's properties are about the runs it has: in time
        timed = properties is not None and file.suffix == ".mcl" and initial is None
    assumptions = timed_assumptions(timed, ack_within, report_gap, fair_reports, urgency_only)
    if timed and initial is not None:
        raise OptionError("--timed", "a timed verdict starts the mission from its start (its "
                                     "clocks at 0): leave out --initial")
    if stubborn and (timed or properties is None):
        raise OptionError("--stubborn", "the reduction is of the untimed check of properties: "
                                        "add --untimed --properties")
    net, props, extra = _analyzed_net(file, net_id, properties, max_memory, max_props_size,
                                      max_atoms, lenient, max_mission_size)
    if folder is not None:      # before the analysis: a folder that cannot be is said at once
        _counterexample_folder(file, folder, props, extra)
    start = None if initial is None else parse_marking(initial, net, str(file))
    said: list[str] = []

    def say(line: str) -> None:
        said.append(line)
        note(line)
    ends = verdicts = None
    if timed:   # the runs in time: the timed answers alone, the untimed ones with --untimed
        result: dict[str, Any] = {}
        ends = timed_ends(net, assumptions, max_states)
        if props is not None:
            verdicts = check_properties_timed(net, props, assumptions, max_states)
    else:
        result = _explored(file, net, start, say, progress, state_space=state_space,
                           max_states=max_states, explorer=explorer, max_memory=max_memory,
                           max_cert=max_cert, explore=explore or lenient)
        if progress is not None:
            note("")   # the progress line ended
        if props is not None:
            verdicts = _untimed_verdicts(file, net, props, start, max_states, stubborn,
                                         max_mission_size)
            if stubborn:
                result["stubborn"] = True
    asked = explain or folder is not None
    explained = None
    if verdicts is not None and asked:
        explained = witnesses(file, net, verdicts, max_counterexamples,
                              assumptions if timed else None, max_mission_size)
        _say_left_out(verdicts, explained, say)
    written = [] if folder is None or explained is None else \
        _save_witnesses(folder, file, verdicts, explained, say, max_mission_size)
    return AnalyzeOutcome(
        result, None if verdicts is None else tuple(verdicts),
        None if explained is None else tuple(explained), ends, tuple(said), tuple(written),
        _analyze_status(result, verdicts, ends), hint=not asked and start is None)


def _untimed_verdicts(file: Path, net: Net, props, start, max_states: int,
                      stubborn: bool, max_mission_size: int | str | None = None) -> list:
    """The properties' verdicts on the net's runs; with ``stubborn`` the reduction, once
    the mission's certificate proves the net 1-safe (from its own start only: another
    start needs a P-invariant to), or refused saying why."""
    from mcl2pnml.analysis.checking.on_the_fly import NotProvenSafe
    safe = stubborn and start is None and proven_safe_by_certificate(file, net,
                                                                     max_mission_size)
    try:
        return check_properties(net if start is None else net.with_initial(start), props,
                                max_states, stubborn=stubborn, safe=safe)
    except NotProvenSafe as e:
        raise OptionError("--stubborn", f"{e}: the reduction could skip the firing that "
                                        "shows a second token") from None


def _explanations_possible(properties: str | None, initial: str | None,
                           folder: Path | None, explain: bool) -> None:
    """Refuse an explanation asked for where there can be none: without properties, or
    from another start than the mission's (the mission's terms and the replay start
    there)."""
    for option, asked in (("--counterexamples", folder is not None), ("--explain", explain)):
        if asked and properties is None:
            raise OptionError(option, "counterexamples are of properties: add --properties")
        if asked and initial is not None:
            raise OptionError(option, "a replay starts the mission from its start: leave "
                                      "out --initial")


def _analyzed_net(file: Path, net_id: str | None, properties: str | None, max_memory,
                  max_size, max_atoms, lenient: bool = False,
                  max_mission_size: int | str | None = None
                  ) -> tuple[Net, tuple | None, Path | None]:
    """The net ``analyze`` reads, and with ``--properties`` the properties and their side
    file, read, counted and checked before the analysis, which they may make long. A net
    read with ``lenient`` is explored: a certificate beside it is never taken for it."""
    if properties is None:
        return load_net(file, net_id, max_memory, lenient, max_mission_size), None, None
    if lenient:
        raise OptionError("--lenient", "properties are a mission's, compiled, not read as "
                                       "PNML; leave out --lenient")
    if file.suffix != ".mcl":
        raise OptionError("--properties", "properties are a mission's (an .mcl file)")
    if net_id is not None:
        raise OptionError("--net", "properties are a mission's, which compiles to one net; "
                                   "leave out --net")
    extra = properties_file(file, properties)
    net, props = properties_of(file, extra=extra, max_memory=max_memory, max_size=max_size,
                               max_atoms=max_atoms, max_mission_size=max_mission_size)
    return net, props, extra


def _counterexample_folder(file: Path, folder: Path, props, extra: Path | None) -> None:
    """The folder of ``--counterexamples`` made, once no property's file in it is found
    to be an input: refused before anything is written."""
    from mcl2pnml.core.files import check_outputs
    inputs = [("the mission", file), ("the properties file (--properties)", extra),
              ("the certificate beside it", certificate_beside(file))]
    check_outputs([("--counterexamples", path) for prop in props for path in
                   witness_files(folder, prop.name).values()], inputs,
                  "give another folder, or rename the property")
    make_folder(folder)


def _explored(file: Path, net: Net, start, say: Callable[[str], None], progress,
              *, max_cert, explore: bool, **options: Any) -> dict[str, Any]:
    """The untimed analysis of ``net``; a certificate beside the file, if it holds for the
    net and the run starts at M0, proves the behaviour without exploring
    (:mod:`mcl2pnml.certify`), and ``explore`` explores anyway."""
    beside = certificate_beside(file)
    certified = None
    if beside.is_file() and start is None and not explore:
        certified, problems = certified_facts(net, beside, max_cert)
        if problems:
            say(f"{beside}: the certificate does not hold for this net ({problems[0]}"
                + (f"; {len(problems) - 1} more" if len(problems) > 1 else "")
                + "): exploring instead")
    result = analyze(net, start, state_space_only=options.pop("state_space"),
                     progress=progress, explore_states=certified is None, **options)
    if certified is not None:
        result.update(certified)
        say(f"{beside}: the certificate holds: 1-safe, an end always reachable, reusable, "
            "proven from the mission's parts; the markings were not explored (--explore to "
            "explore them)")
    return result


def _say_left_out(verdicts, explained, say: Callable[[str], None]) -> None:
    failing = sum(v.shape is not None for v in verdicts)
    done = sum(w is not None for w in explained)
    if done < failing:
        say(f"counterexamples of {failing - done:,} of the {failing:,} failing properties "
            f"left out: the first {done:,} are explained (--max-counterexamples to raise "
            "the limit)")


def _save_witnesses(folder: Path, file: Path, verdicts, explained,
                    say: Callable[[str], None],
                    max_mission_size: int | str | None = None) -> list[Path]:
    """Each explained counterexample's files (:func:`save_witness`); one page content for
    all, since a run does not change the mission's drawing."""
    written: list[Path] = []
    if not any(w is not None for w in explained):
        return written
    page = show_nets(str(file), with_run=True, max_mission_size=max_mission_size)
    for v, w in zip(verdicts, explained):
        if w is not None:
            for path in save_witness(folder, file, v, w, page):
                say(f"wrote {path}")
                written.append(path)
    return written


def _analyze_status(result: dict[str, Any], verdicts, ends) -> int:
    statuses = {v.status.value for v in verdicts or ()}
    if "fails" in statuses:
        return 1
    undecided = ends is not None and ends.always_ends is None
    return 3 if "partial" in result or "unknown" in statuses or undecided else 0


def timed_assumptions(timed: bool, ack_within: str = "0", report_gap: str = "1",
                      fair: bool = False, urgency_only: bool = False) -> "Assumptions":
    """The vehicle's assumptions of ``--timed`` (docs/time.md), from the options as written;
    one given without ``timed`` is refused."""
    from mcl2pnml.core.timing import Assumptions, seconds_option
    given = [name for name, said in (("--ack-within", ack_within != "0"),
                                     ("--report-gap", report_gap != "1"),
                                     ("--fair-reports", fair), ("--urgency-only", urgency_only))
             if said]
    if given and not timed:
        raise OptionError(given[0], "an assumption of the timed verdicts: add --timed")
    return Assumptions(seconds_option(ack_within, "--ack-within"),
                       seconds_option(report_gap, "--report-gap"), fair, not urgency_only)


def properties_file(mission: Path, properties: str) -> Path | None:
    """The side file of ``--properties [FILE]``: FILE, else MISSION.props if there is one."""
    extra = Path(properties) if properties else mission.with_suffix(".props")
    if properties and not extra.is_file():
        raise OptionError("--properties", f"no file '{properties}'")
    return extra if extra.is_file() else None


# -- running -------------------------------------------------------------------------------

def _engine_for(mission: Path, net_id: str | None, lenient: bool = False,
                max_mission_size: int | str | None = None) -> Callable[[str], Any]:
    """How to build each engine for ``mission`` (the reference engine reads MCL only)."""
    def make(kind: str):
        from mcl2pnml.runtime.executor import PetriEngine
        if mission.suffix == ".mcl":
            checked = check_file(mission, max_mission_size)
            if kind == "reference":
                from mcl2pnml.runtime.reference import ReferenceEngine
                return ReferenceEngine(checked)
            return PetriEngine(compile_checked(checked))
        if kind == "reference":
            raise OptionError("--engine", "the reference engine reads MCL, not a net; give "
                                          "the .mcl file")
        from mcl2pnml.core.memory import Budget, check_load
        from mcl2pnml.io.pnml.reader import read_pnml
        check_load(mission, Budget())
        return PetriEngine(read_pnml(mission, net_id, lenient))
    if lenient and mission.suffix == ".mcl":
        raise OptionError("--lenient", "a mission is compiled, not read as PNML; leave out "
                                       "--lenient")
    return make


def run_mission(mission: str | Path, options: "RunOptions | None" = None, *,
                text: IO[str] | None = None, log_path: str | Path | None = None,
                note: Callable[[str], None] = lambda line: None, net_id: str | None = None,
                lenient: bool = False, max_mission_size: int | str | None = None):
    """Run ``mission`` (MCL, or a compiled PNML for the Petri-net engine) against a vehicle;
    ``lenient``: a PNML read the forgiving way (docs/pnml.md).

    Returns the run (outcome, time, trace, safe stop); see
    :func:`mcl2pnml.runtime.session.run_session` for the rest.
    """
    from mcl2pnml.runtime.session import RunOptions, run_session
    mission = Path(mission)
    return run_session(mission, options or RunOptions(),
                       _engine_for(mission, net_id, lenient, max_mission_size), text=text,
                       log_path=Path(log_path) if log_path else None, note=note)


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
    from mcl2pnml.io.formats import SUFFIXES
    path = Path(what)
    if net_id is not None and path.suffix.lower() not in SUFFIXES:
        raise OptionError("--net", "only a net file (PNML) may hold several nets; leave out "
                                   "--net")
    if path.suffix == ".mcl" or path.suffix.lower() in SUFFIXES:
        if not path.is_file():
            raise OptionError("MISSION.mcl|NET|TEMPLATE", f"no file '{what}'")
        if path.suffix != ".mcl":
            return Shown(path.stem, [(load_net(path, net_id, lenient=lenient), "the net")])
        from mcl2pnml.core.payloads import MISSION
        from mcl2pnml.language.functional import (function_expression, instances,
                                                  mission_expression)
        checked = check_file(path, max_mission_size)
        trees = [(MISSION, instances(mission_expression(checked.mission), MISSION, ""))]
        trees += [(name, instances(function_expression(checked.functions[name]), name, name))
                  for name in checked.function_order]
        return Shown(path.stem, [(compile_checked(checked), "the mission"),
                                 (compile_checked(checked, reduced=True),
                                  "the mission, every task reduced (Fig. 3)")], trees)
    if with_run:
        raise OptionError("--run", "a run is of a mission: give the mission's .mcl or its "
                                   "compiled net, not a template")
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
    from mcl2pnml.view.show import check_run, read_run, save_page, tree_data, variant
    entries = None
    if run_log is not None:
        entries = read_run(run_log)
        check_run(shown.nets[0][0], entries, str(run_log))
    tree = tree_data(shown.trees)
    if not shown.drawn:
        shown.drawn.extend(variant(net, label, tree, shown.boxes.get(label))
                           for net, label in shown.nets)
    save_page(path, shown.title, shown.drawn, entries, tree)
    return Path(path)


def serve_show_live(shown: Shown, run_log: str | Path, *, port: int = 0, linger: float = 10.0,
                    ready=print) -> None:
    """Serve the token-game page of ``shown`` on loopback, following the run of ``run_log``
    as it is written (:func:`mcl2pnml.view.show.serve_live`): ``ready`` is given the
    page's URL; returns on Ctrl-C or ``linger`` seconds after the run's end was served."""
    from mcl2pnml.view.show import LiveLog, page, serve_live, tree_data, variant
    tree = tree_data(shown.trees)
    if not shown.drawn:
        shown.drawn.extend(variant(net, label, tree, shown.boxes.get(label))
                           for net, label in shown.nets)
    html = page(shown.title, shown.drawn, None, tree, live=True)
    serve_live(html, LiveLog(shown.nets[0][0], run_log), port=port, linger=linger, ready=ready)


def save_reachability_json(net: Net, path: str | Path) -> dict[str, Any]:
    """Write the reachability graph the page draws (:mod:`mcl2pnml.view.reachability`)
    to ``path`` as JSON, with the place and transition ids its indices refer to, or
    why there is none (``reason``); returns what was written."""
    import json

    from mcl2pnml.core.files import atomic_write_text
    from mcl2pnml.view.reachability import reachability_graph
    graph = reachability_graph(net).to_json()
    graph["places"] = [p.id for p in net.places]
    graph["transitions"] = [t.id for t in net.transitions]
    atomic_write_text(path, json.dumps(graph, ensure_ascii=False) + "\n")
    return graph


# -- time in the verdicts (docs/time.md) --------------------------------------------------

def timed_ends(net: Net, assumptions: "Assumptions | None" = None,
               max_states: int = 1_000_000):
    """Whether every run of the compiled mission ``net`` ends under ``assumptions`` (the
    defaults of :class:`~mcl2pnml.core.timing.Assumptions` if None), its earliest and
    latest end times, and what a run that never ends waits for
    (:class:`mcl2pnml.timed.TimedEnds`)."""
    from mcl2pnml import timed
    from mcl2pnml.core.timing import Assumptions
    return timed.ends(net, assumptions or Assumptions(), max_states)


def check_properties_timed(net: Net, properties, assumptions: "Assumptions | None" = None,
                           max_states: int = 1_000_000) -> list:
    """Each property's :class:`mcl2pnml.analysis.checking.on_graph.Verdict` on the mission's time-divergent
    runs (docs/time.md), on one zone graph."""
    from mcl2pnml import timed
    from mcl2pnml.core.timing import Assumptions
    return timed.check(net, properties, assumptions or Assumptions(), max_states)


# -- the contest's questions, as ``mcl2pnml query`` answers them ----------------------------

@dataclass(frozen=True)
class QueryOutcome:
    """What ``mcl2pnml query`` prints: one answer per formula and examination."""

    net: str
    answers: list[Any]

    @property
    def status(self) -> int:
        """0 when every question is answered, 3 when one is not."""
        return 3 if any(a.value is None for a in self.answers) else 0

    def lines(self) -> list[str]:
        return [a.line() for a in self.answers]

    def as_json(self) -> dict[str, Any]:
        return {"net": self.net, "answers": [
            {"id": a.id, "value": a.value, **({"technique": a.technique} if a.technique else {}),
             **({"reason": a.reason} if a.reason else {})} for a in self.answers]}


def query_file(net_path: Path, formulas: Sequence[Path], examinations: Sequence[str] = (), *,
               net_id: str | None = None, max_states: int = 5_000_000,
               max_memory: int | str | None = None, stubborn: bool = False,
               lenient: bool = False, max_mission_size: int | str | None = None
               ) -> QueryOutcome:
    """``mcl2pnml query``: the Model Checking Contest's formula files (and generic
    examinations) answered on any net we read (:mod:`mcl2pnml.analysis.contest.answers`)."""
    from mcl2pnml.analysis.contest import answers as mcc
    from mcl2pnml.io.mccquery import read_queries
    if not formulas and not examinations:
        raise OptionError("FORMULAS", "give a formula file of the contest, or --examination")
    queries = [x for path in formulas for x in read_queries(path)]
    net = load_net(net_path, net_id, max_memory, lenient, max_mission_size)
    if isinstance(max_memory, str):
        max_memory = parse_size(max_memory)
    answers = mcc.answer(net, queries, max_states=max_states, max_memory=max_memory,
                         stubborn=stubborn) if queries else []
    if examinations:
        answers += mcc.generic(net, examinations, max_states=max_states, max_memory=max_memory)
    return QueryOutcome(net.name, answers)


# -- the exact odds, as ``mcl2pnml odds`` gives them ----------------------------------------

@dataclass(frozen=True)
class OddsOutcome:
    """What ``mcl2pnml odds`` prints: the mission's odds with its vehicle model, and
    (asked for) each primitive's sway on P(OK)."""

    mission: str
    model: str
    odds: "Odds"
    sensitivity: list[dict[str, Any]] = field(default_factory=list)

    def as_json(self) -> dict[str, Any]:
        out = {"mission": self.mission, "vehicle_model": self.model, **self.odds.as_json()}
        if self.sensitivity:
            out["sensitivity"] = self.sensitivity
        return out

    def lines(self) -> list[str]:
        o = self.odds
        lines = [f"{self.mission} with the vehicle model {self.model} "
                 f"({o.states:,} states, {o.transitions:,} transitions; docs/odds.md):"]
        for name, p in o.outcomes.items():
            exact = o.exact.get(name) if o.exact is not None else None
            said = f" = {exact}" if exact is not None and exact.denominator > 1 and \
                len(str(exact)) <= 40 else ""
            lines.append(f"  P({name}) = {p:.6f}{said}")
        if o.mean is None:
            lines.append("  end time: the mission never ends")
        else:
            q = o.quantiles
            lines.append(f"  end time, if it ends: mean {o.mean:.2f} s, standard deviation "
                         f"{o.spread:.2f} s; 5% by {_s(q['p5'])}, half by {_s(q['p50'])}, "
                         f"95% by {_s(q['p95'])}")
        if o.beyond:
            lines.append(f"  (the distribution stops at its horizon with {o.beyond:.2e} of "
                         "the runs still going)")
        if o.properties:
            lines.append("  the properties (the probability that each holds):")
            width = max(len(p.name) for p in o.properties)
            for p in o.properties:
                said = f" = {p.exact}" if p.exact is not None and p.exact.denominator > 1 \
                    and len(str(p.exact)) <= 40 else ""
                lines.append(f"    {p.name:<{width}}  {p.holds:.6f}{said}")
        if self.sensitivity:
            lines.append("  P(OK) by primitive (as modelled; if it always achieved; if it never "
                         "did):")
            width = max(len(r["primitive"]) for r in self.sensitivity)
            for r in self.sensitivity:
                lines.append(f"    {r['primitive']:<{width}}  {r['ok']:.4f}  "
                             f"{r['ok_if_it_always_achieves']:.4f}  "
                             f"{r['ok_if_it_never_achieves']:.4f}  swing {r['swing']:.4f}")
        return lines


def _s(seconds: float | None) -> str:
    return "never" if seconds is None else f"{seconds:g} s"


def odds_file(mission: Path, model_path: Path, *, max_states: int | None = None,
              sensitivity: bool = False, prism: Path | None = None,
              properties: str | None = None, max_props_size=None, max_atoms=None,
              max_mission_size: int | str | None = None,
              note: Callable[[str], None] = lambda line: None) -> OddsOutcome:
    """``mcl2pnml odds``: the exact odds of a mission (MCL) with a vehicle model; with
    ``properties`` (``--properties [FILE]``, as :func:`properties_file` reads it) the
    probability that each of the mission's properties holds; the chain in PRISM's
    language to ``prism`` if asked (Storm and PRISM read it)."""
    from mcl2pnml.core.files import atomic_write_text, check_outputs
    from mcl2pnml import odds as exact
    from mcl2pnml.runtime.executor import PetriEngine
    from mcl2pnml.runtime.vehicle_model import VehicleModel
    if mission.suffix != ".mcl":
        raise OptionError("MISSION", f"'{mission}' is not a mission (.mcl): the odds are a "
                                     "mission's, run as the engines run it")
    extra = None if properties is None else properties_file(mission, properties)
    check_outputs([("--prism", prism)], [("the mission", mission),
                                          ("the vehicle model", model_path),
                                          ("the properties file (--properties)", extra)])
    model = VehicleModel.load(model_path)
    if properties is None:
        net, props = compile_checked(check_file(mission, max_mission_size)), ()
    else:
        net, props = properties_of(mission, extra=extra, max_size=max_props_size,
                                   max_atoms=max_atoms, max_mission_size=max_mission_size)
    limit = max_states or exact.MAX_STATES
    used = PetriEngine(net).primitives_used()
    model.check_primitives(used)
    chain = exact.chain_of(net, model, limit, props)
    odds = exact.odds_of(chain)
    if prism is not None:
        atomic_write_text(prism, exact.to_prism(chain, f"{mission.name} with {model_path.name}"))
        note(f"wrote {prism}")
    table = exact.sensitivity(net, model, used, limit, odds.outcomes["OK"]) if sensitivity \
        else []
    return OddsOutcome(mission.name, model_path.name, odds, table)


def campaign_file(mission: Path, model_path: Path | None, runs: int, *, engine: str = "petri",
                  seed: int = 0, confidence: float = 0.99, target: float | None = None,
                  workers: int | None = None, scheduler: str | None = None,
                  scheduler_timeout: SchedulerTimeouts | None = None,
                  world: Path | None = None, faults: Path | None = None,
                  properties: str | None = None, max_props_size=None, max_atoms=None,
                  max_mission_size: int | str | None = None,
                  table: Path | None = None, plot: Path | None = None,
                  max_time: float = 24 * 3600.0,
                  progress: Callable[[int, int], None] | None = None,
                  note: Callable[[str], None] = lambda line: None):
    """``mcl2pnml campaign``: ``runs`` simulated runs of a mission on Dask
    (:mod:`mcl2pnml.campaign`), with a vehicle model (``model_path``) or on the
    kinematic simulator (``world``, else the one beside the mission, else the default
    world), the faults of ``faults`` injected; each run judged on the mission's
    properties if asked (``--properties [FILE]``); the table and the plot written if
    asked; a user's ``scheduler`` held to ``scheduler_timeout`` (default: the handshake's
    and the silence's bounds of :mod:`mcl2pnml.campaign`). Every file is read and checked
    here, before any run."""
    from mcl2pnml.core.files import check_outputs
    from mcl2pnml import campaign as campaigns
    from mcl2pnml.runtime.executor import PetriEngine
    from mcl2pnml.runtime.faults import Faults
    from mcl2pnml.runtime.session import WORLD_SUFFIX
    from mcl2pnml.runtime.simulator import AUVSimulator, World
    from mcl2pnml.runtime.vehicle_model import VehicleModel
    if mission.suffix != ".mcl":
        raise OptionError("MISSION", f"'{mission}' is not a mission (.mcl)")
    if scheduler is not None and workers is not None:
        raise OptionError("--workers", "the scheduler's cluster has its own workers")
    if model_path is not None and world is not None:
        raise OptionError("--world", "a world is for the simulator; a vehicle model answers "
                                     "without one (give --vehicle-model or --world)")
    if properties is not None and engine != "petri":
        raise OptionError("--properties", "properties are judged on the net's markings: "
                                          "--engine petri")
    beside = mission.with_name(mission.name[:-len(".mcl")] + WORLD_SUFFIX)
    if model_path is None and world is None and beside.is_file():
        world = beside
        note(f"world: {world}, the one beside the mission (--world to give another)")
    extra = None if properties is None else properties_file(mission, properties)
    check_outputs([("--table", table), ("--plot", plot)],
                  [("the mission", mission), ("the vehicle model", model_path),
                   ("the world (--world)", world), ("the faults (--faults)", faults),
                   ("the properties file (--properties)", extra)])
    campaigns.check_outputs(table, plot)
    # every file refused here, with its place, not on a worker
    if properties is None:
        net, props = compile_checked(check_file(mission, max_mission_size)), ()
    else:
        net, props = properties_of(mission, extra=extra, max_size=max_props_size,
                                   max_atoms=max_atoms, max_mission_size=max_mission_size)
    used = PetriEngine(net).primitives_used()
    if model_path is not None:
        VehicleModel.load(model_path).check_primitives(used)
    else:
        flown_in = World.load(world) if world else World()
        offered = AUVSimulator(flown_in).primitives
        if not flown_in.noise and faults is None:
            note("every run flies alike: the world has no noise and no faults are injected "
                 '("noise" in the world file, or --faults, makes runs differ)')
        if used - offered:
            raise OptionError("--vehicle-model", f"the mission uses "
                              f"'{sorted(used - offered)[0]}', which the simulator does not "
                              f"offer (it offers {', '.join(sorted(offered))}): fly it with "
                              "a vehicle model")
    if faults is not None:
        Faults.load(faults).check_primitives(used)
    fleet = campaigns.Fleet(*(str(f.resolve()) if f is not None else None
                              for f in (model_path, world, faults)))
    flown = campaigns.fly(mission, fleet, runs, engine=engine, seed=seed,
                          confidence=confidence, target=target, workers=workers,
                          scheduler=scheduler, max_time=max_time, properties=props,
                          timeouts=scheduler_timeout or campaigns.SchedulerTimeouts(),
                          progress=progress)
    first = next((r for r in flown.runs if r.outcome != "OK"), None)
    if first is not None:     # the command as the user wrote the files
        given = campaigns.Fleet(*(str(f) if f is not None else None
                                  for f in (model_path, world, faults)))
        flown.again = (first.seed, first.outcome, given.replay(str(mission), first.seed))
    if table is not None:
        campaigns.write_table(flown, table)
        note(f"wrote {table}")
    if plot is not None:
        what = model_path.name if model_path is not None else \
            (world.name if world is not None else "the default world")
        what += f", faults of {faults.name}" if faults is not None else ""
        campaigns.plot(flown, plot, f"{mission.name} with {what}")
        note(f"wrote {plot}")
    return flown
