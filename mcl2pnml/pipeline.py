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
    from mcl2pnml.core.properties import Property
    from mcl2pnml.core.timing import Assumptions
    from mcl2pnml.language.functional import Instance
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
    "Shown", "save_reachability_json",
]


# -- the language: MCL to a net (section 2.4) ---------------------------------------------

def check_file(path: str | Path):
    """Parse and check an MCL file: the resolved program the compiler takes."""
    from mcl2pnml.language.checker import check
    from mcl2pnml.language.parser import parse_file
    return check(parse_file(path))


def check_source(text: str, filename: str = "<mcl>"):
    """Parse and check MCL text; errors name ``filename``."""
    from mcl2pnml.language.checker import check
    from mcl2pnml.language.parser import parse
    return check(parse(text, filename))


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
                  max_atoms: int | None = None, checked=None
                  ) -> tuple[Net, tuple["Property", ...]]:
    """The compiled net of ``mission`` and its properties compiled to predicates on its
    places (:mod:`mcl2pnml.language.properties`): those the mission declares, then those
    of ``extra`` (a side file of ``property`` declarations), each with its location.
    ``reduced``: on the reduced model (Fig. 3), where an atom on a primitive is an error.

    ``extra`` over ``max_size`` bytes (or as ``--max-properties-size`` takes it) is
    refused before it is read, and properties of more than ``max_atoms`` atoms in all
    once parsed, before they are checked (defaults: the limits of
    :mod:`mcl2pnml.core.bounds`). ``checked``: the mission already checked, not read
    again."""
    from mcl2pnml.core.bounds import MAX_PROPERTIES_SIZE, MAX_PROPERTY_ATOMS
    from mcl2pnml.language.parser import parse_file
    from mcl2pnml.language.properties import check_atoms, check_side_file, compile_properties
    if isinstance(max_size, str):
        max_size = parse_size(max_size, "--max-properties-size")
    checked = check_file(mission) if checked is None else checked
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
                 max_memory: int | str | None = None, checked=None) -> Net:
    """The mission in ``path`` compiled to one net, within the memory budget.

    A mission's net is about as large as its text is long, but only the
    compiling tells how large: it runs under the budget's guard
    (:func:`mcl2pnml.core.memory.guard`; ``max_memory`` in bytes or as
    ``--max-memory`` takes it, default half the memory available), which
    stops it with one message instead of the kernel killing the process.
    ``checked``: the file already checked (:func:`check_file`), not read again.
    """
    from mcl2pnml.core.memory import Budget, guard
    if isinstance(max_memory, str):
        max_memory = parse_size(max_memory)
    checked = check_file(path) if checked is None else checked
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
             max_memory: int | str | None = None) -> Net:
    """A net from any file: a mission (``.mcl``, compiled) or a format of the table.

    ``net_id`` chooses one net of a file that holds several (PNML). A net file
    that reading could not hold within ``max_memory`` (bytes, or as
    ``--max-memory`` takes it; default half the memory available) is refused
    before it is read (:func:`mcl2pnml.core.memory.check_load`).
    """
    if Path(path).suffix != ".mcl":
        from mcl2pnml.core.memory import Budget, check_load, release
        if isinstance(max_memory, str):
            max_memory = parse_size(max_memory)
        check_load(path, Budget(max_memory))
        net = reader_of(path).load(path, net_id)
        release()   # the parsed file is freed: what the analysis may use is back
        return net
    if net_id is not None:
        raise OptionError("--net", "a mission compiles to one net; leave out --net")
    return compile_file(path, max_memory=max_memory)


def save_net(net: Net, path: str | Path, fmt: str = "pnml", *, layout: str = "auto",
             title: str | None = None, mission: bool = False,
             clusters: Mapping[str, Sequence[str]] | None = None,
             expand: Sequence[str] | None = (), timing: "Assumptions | None" = None) -> Path:
    """Write ``net`` to ``path`` in format ``fmt`` (a name of the format table).

    ``layout`` places the nodes where the format keeps positions (PNML):
    ``auto``, ``dot``, ``layers`` or ``none``; with dot, the arcs' bend points
    too. ``mission``: a compiled mission, whose TINA file follows the
    executor's timing. A drawing (svg, png, dot) shows ``clusters`` as boxes
    (None: a mission's calls, :func:`template_clusters` for a template) and
    opens those ``expand`` names (None: all). ``timing``: what the vehicle is assumed to
    do, for the formats that write a mission's timed semantics (tapn).
    """
    form = FORMATS.get(fmt)
    if form is None:
        raise ValueError(f"unknown format {fmt!r}; known: {', '.join(FORMATS)}")
    drawn = _drawn(net, layout) if "positions" in form.options else None
    form.save(net, path, SaveOptions(positions=drawn and drawn.positions,
                                     bends=drawn and drawn.bends, title=title,
                                     urgent=mission, clusters=clusters, expand=expand,
                                     timing=timing))
    return Path(path)


def save_timed_queries(net: Net, net_path: str | Path, timing: "Assumptions | None" = None,
                       properties=()):
    """The queries verifydtapn checks a mission's timed-arc net (``compile --format tapn``)
    against, written beside it (an end always reached, a dead state that is not an end, the
    safety its clocks rest on, the properties a state formula says; :mod:`mcl2pnml.io.tapn`);
    returns each file, its query and the k-bound to give verifydtapn."""
    from mcl2pnml.io.tapn import save_queries as save
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
    from mcl2pnml.io.tapn import save_deadline as save
    return save(net, path, seconds, timing)


def save_pnml(net: Net, path: str | Path, layout_engine: str = "auto") -> Path:
    """``net`` as PNML at ``path``, laid out by ``layout_engine`` (written whole or not at all)."""
    return save_net(net, path, "pnml", layout=layout_engine)


def save_queries(net: Net, path: str | Path, tool: str = "verifypn"):
    """The compiled mission's properties for ``tool`` (verifypn or lola) in the Model Checking
    Contest's XML (:mod:`mcl2pnml.io.mccquery`), with the ids of its PNML; returns them."""
    from mcl2pnml.io.mccquery import save_queries as save
    return save(net, path, tool)


def save_property_queries(properties, stem: str | Path):
    """A mission's properties in the Model Checking Contest's categories, one file each,
    ``STEM.LTLCardinality.xml`` and so on (:mod:`mcl2pnml.io.mccquery`); the files written."""
    from mcl2pnml.io.mccquery import save_property_queries as save
    return save(properties, stem)


def to_pnml_bytes(net: Net, layout_engine: str = "auto") -> bytes:
    """``net`` as a PNML document, laid out by ``layout_engine``."""
    from mcl2pnml.io.pnml.writer import to_pnml_bytes as write
    drawn = _drawn(net, layout_engine)
    return write(net, drawn and drawn.positions, drawn and drawn.bends)


def _drawn(net: Net, layout: str):
    """Node positions and arc bend points from ``layout`` (None for ``none``, which
    imports nothing of the view)."""
    if layout == "none":
        return None
    from mcl2pnml.view.layout import drawn_layout
    return drawn_layout(net, layout)


def validate_pnml(path: str | Path, grammar: str | Path | None = None,
                  net_id: str | None = None):
    """The verdict on a PNML file of our schema, of the official grammar when ``grammar``
    gives it (or it is found: :func:`mcl2pnml.io.pnml.grammar.find_grammar`) and of the
    reader's rules; and the net when it is valid."""
    from mcl2pnml.core.memory import Budget, check_load
    from mcl2pnml.io.pnml.grammar import validate
    from mcl2pnml.io.pnml.reader import load_pnml
    check_load(path, Budget())   # the schemas read the file whole too
    verdict = validate(path, grammar, net_id)
    return verdict, (load_pnml(path, net_id) if verdict.valid else None)


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

def certify_file(mission: str | Path, abort_pending: bool = False
                 ) -> tuple[dict[str, Any], Net, list[str]]:
    """The certificate of ``mission`` (:mod:`mcl2pnml.certify.certificate`), its compiled
    net (with ``mission.A`` marked too if ``abort_pending``), and what the independent
    checker finds wrong with the pair (nothing: it holds)."""
    from mcl2pnml.certify.certificate import certify
    from mcl2pnml.certify.checker import check
    from mcl2pnml.certify.templates import current
    from mcl2pnml.core.payloads import MissionPlace
    checked = check_file(mission)
    net = compile_checked(checked)
    if abort_pending:
        net = net.with_initial({**net.initial, MissionPlace.A.id: 1})
    proofs = current()      # read once, for the certificate and its check
    cert = certify(checked, net_name=net.name, abort_pending=abort_pending, proofs=proofs)
    # checked as it will be read back: plain JSON
    return cert, net, check(net, json.loads(json.dumps(cert)), proofs)


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
    from mcl2pnml.core.files import json_fault, read_text
    limit = parse_size(max_size, "--max-certificate-size") if isinstance(max_size, str) \
        else max_size
    text = read_text(path, "certificate", limit, "--max-certificate-size")

    def not_json(constant: str):
        raise ValueError(f"{constant} is not JSON")
    try:
        cert = json.loads(text, parse_constant=not_json)
    except json.JSONDecodeError as e:
        lines = text.splitlines()
        raise Mcl2PnmlError(f"not a certificate: {e.msg}", Location(
            str(path), e.lineno, e.colno, lines[e.lineno - 1] if lines else None)) from None
    except (ValueError, RecursionError) as e:
        raise Mcl2PnmlError(f"not a certificate: {json_fault(e)}", Location(str(path))) from None
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
    from mcl2pnml.certify.checker import check
    return check(net, cert, shaped=shaped)


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
    """Invariants, siphons and reachable markings (:func:`analysis.report.analyze`);
    ``max_memory`` may be written as ``--max-memory`` takes it (:func:`parse_size`)."""
    from analysis.report import analyze as run
    if isinstance(options.get("max_memory"), str):
        options["max_memory"] = parse_size(options["max_memory"])
    return run(net, initial, **options)


def check_properties(net: Net, properties, max_states: int = 1_000_000) -> list:
    """Each property's :class:`analysis.properties.Verdict` on ``net``'s runs, in order:
    holds, fails with a shortest counterexample, or unknown past ``max_states``. The state
    space is explored once for all of them."""
    from analysis.properties import check_all
    return check_all(net, properties, max_states)


#: How many failing properties ``analyze`` explains, unless told (``--max-counterexamples``):
#: each costs its replay on both engines, at times a search of the engines' own runs, and
#: four files, so that thousands of failing properties would take minutes to hours.
MAX_COUNTEREXAMPLES = 100


def witnesses(mission: Path, net: Net, verdicts, most: int | None = None,
              timing: "Assumptions | None" = None) -> list:
    """For each verdict, its :class:`~mcl2pnml.counterexample.Witness` when it fails
    (the counterexample in the mission's terms, the vehicle script that replays a violation
    on both engines, or why none does), else None. ``net`` is ``mission``'s compiled net.
    ``most``: only the first ``most`` failing verdicts are explained, the others' are None,
    and cost nothing."""
    from mcl2pnml.counterexample import witness
    checked = check_file(mission)
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
    """Verdicts as ``analyze --json`` prints them, each failing one with its witness if given."""
    out = []
    for k, v in enumerate(verdicts):
        w = witnesses[k] if witnesses else None
        cex = None if v.shape is None else {
            "shape": v.shape.value, "transitions": list(v.transitions),
            "loop": v.loop, "markings": [dict(m) for m in v.markings]}
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


def witness_text(v, w) -> list[str]:
    """A verdict as ``analyze --properties`` prints it: the firing sequence, the same run in
    the mission's terms, and the vehicle script that replays a violation, or why none does."""
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
        return out
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
    from analysis.report import render_text
    return render_text(result)


# -- running -------------------------------------------------------------------------------

def _engine_for(mission: Path, net_id: str | None) -> Callable[[str], Any]:
    """How to build each engine for ``mission`` (the reference engine reads MCL only)."""
    def make(kind: str):
        from mcl2pnml.runtime.executor import PetriEngine
        if mission.suffix == ".mcl":
            checked = check_file(mission)
            if kind == "reference":
                from mcl2pnml.runtime.reference import ReferenceEngine
                return ReferenceEngine(checked)
            return PetriEngine(compile_checked(checked))
        if kind == "reference":
            raise OptionError("--engine", "the reference engine reads MCL, not a net; give "
                                          "the .mcl file")
        from mcl2pnml.core.memory import Budget, check_load
        from mcl2pnml.io.pnml.reader import load_pnml
        check_load(mission, Budget())
        return PetriEngine(load_pnml(mission, net_id))
    return make


def run_mission(mission: str | Path, options: "RunOptions | None" = None, *,
                text: IO[str] | None = None, log_path: str | Path | None = None,
                note: Callable[[str], None] = lambda line: None, net_id: str | None = None):
    """Run ``mission`` (MCL, or a compiled PNML for the Petri-net engine) against a vehicle.

    Returns the run (outcome, time, trace, safe stop); see
    :func:`mcl2pnml.runtime.session.run_session` for the rest.
    """
    from mcl2pnml.runtime.session import RunOptions, run_session
    mission = Path(mission)
    return run_session(mission, options or RunOptions(), _engine_for(mission, net_id), text=text,
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


def show_nets(what: str, *, with_run: bool = False, net_id: str | None = None) -> Shown:
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
            return Shown(path.stem, [(load_net(path, net_id), "the net")])
        from mcl2pnml.core.payloads import MISSION
        from mcl2pnml.language.functional import (function_expression, instances,
                                                  mission_expression)
        checked = check_file(path)
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
    """Each property's :class:`analysis.properties.Verdict` on the mission's time-divergent
    runs (docs/time.md), on one zone graph."""
    from mcl2pnml import timed
    from mcl2pnml.core.timing import Assumptions
    return timed.check(net, properties, assumptions or Assumptions(), max_states)
