"""The ``mcl2pnml`` command (click), as specified in ``shared/spec/cli.md``.

A thin layer: each command parses its arguments, calls one library function
and prints. Errors are handled once, in :meth:`Cli.main`: a bad argument is
one line on stderr, a bad input file is the error's own message (file, line,
column, the line with a caret), and both exit with status 2, with no
traceback and no partial output file.
"""
from __future__ import annotations

import sys
from pathlib import Path

import click

from mcl2pnml.core.version import __version__
from mcl2pnml.core.errors import Location, Mcl2PnmlError, did_you_mean
from mcl2pnml.view.layout import DOT_LIMIT, ENGINES, LAYERS_LIMIT

EXAMPLES = """\b
Examples:
  mcl2pnml check examples/sauce.mcl
  mcl2pnml functional examples/sauce.mcl
  mcl2pnml compile examples/sauce.mcl -o sauce.pnml
  mcl2pnml compile examples/sauce.mcl --format dot -o sauce.dot
  mcl2pnml run examples/sauce.mcl --vehicle script.json
  mcl2pnml run examples/sauce.mcl --engine reference --vehicle script.json --json
  mcl2pnml run examples/sauce.mcl --vehicle script.json --journal run.journal
  mcl2pnml run examples/sauce.mcl --resume run.journal
  mcl2pnml template --list
  mcl2pnml template task -o task.pnml
  mcl2pnml analyze task.pnml
  mcl2pnml analyze task.pnml --json --initial B,MTX,OFF,C
  mcl2pnml show task -o task.html
  mcl2pnml show examples/sauce.mcl --run run.jsonl
  mcl2pnml validate task.pnml --grammar ~/pnml/grammar
"""


class Cli(click.Group):
    """A click group whose errors are one clear line and exit status 2."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True,
             **extra):
        try:
            code = super().main(args, prog_name or "mcl2pnml", complete_var,
                                standalone_mode=False, **extra)
        except click.exceptions.NoArgsIsHelpError as e:
            click.echo(e.ctx.get_help())
            sys.exit(0)
        except click.UsageError as e:
            cmd = e.ctx.command_path if e.ctx is not None else "mcl2pnml"
            click.echo(f"{cmd}: error: {e.format_message()} (see '{cmd} --help')", err=True)
            sys.exit(2)
        except click.ClickException as e:
            click.echo(f"mcl2pnml: error: {e.format_message()}", err=True)
            sys.exit(2)
        except Mcl2PnmlError as e:
            click.echo(str(e), err=True)
            sys.exit(2)
        except click.Abort:
            click.echo("mcl2pnml: interrupted", err=True)
            sys.exit(130)
        except BrokenPipeError:  # e.g. `mcl2pnml ... | head`
            sys.exit(0)
        sys.exit(code if isinstance(code, int) else 0)


@click.group(cls=Cli, epilog=EXAMPLES, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, "--version", prog_name="mcl2pnml", message="%(prog)s %(version)s")
def main() -> None:
    """Compile AUV missions written in MCL to Petri nets, analyse them, run them.

    Nets are read and written as ISO/IEC 15909-2 PNML (P/T nets).
    """


def _checked(file: Path):
    from mcl2pnml.language.checker import check as run_checks
    from mcl2pnml.language.parser import parse_file

    return run_checks(parse_file(file))


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=click.Path(exists=True, dir_okay=False, path_type=Path))
def check(mission: Path) -> int:
    """Parse and check MISSION (MCL): names, arities, patterns, recursion.

    Every error of the file is reported at once, each with file:line:col.
    """
    checked = _checked(mission)
    tasks, functions = len(checked.tasks), len(checked.functions)
    click.echo(f"{mission}: ok ({len(checked.primitives)} primitives, {tasks} tasks, "
               f"{functions} function{'s' * (functions != 1)}, {len(checked.consts)} consts)")
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--functions", "with_functions", is_flag=True,
              help="Also print each function's body in functional form.")
def functional(mission: Path, with_functions: bool) -> int:
    """Print the functional form of MISSION (the paper's Algorithm 2).

    Structures are written sequence, parallel, if-then-else, while and
    monitor; an empty block or a missing else is NULL; functions stay calls.
    """
    from mcl2pnml.language.functional import format_node, function_expression, mission_expression

    checked = _checked(mission)
    if with_functions:
        for name in checked.function_order:
            f = checked.functions[name]
            click.echo(f"{name}({', '.join(f.params)}) = {format_node(function_expression(f))}")
    click.echo(format_node(mission_expression(checked.mission)))
    return 0


def compile_file(mission: Path):
    from mcl2pnml.language.compiler import compile_checked

    return compile_checked(_checked(mission))


FORMATS = ("pnml", "tina", "lola", "dot", "svg", "png")
#: The suffix each format's file gets by default.
SUFFIX = {"pnml": ".pnml", "tina": ".net", "lola": ".lola", "dot": ".dot", "svg": ".svg",
          "png": ".png"}


def write_net(net, output: Path, fmt: str, layout_engine: str = "auto",
              title: str | None = None, mission: bool = False) -> None:
    """``net`` to ``output`` in one of :data:`FORMATS` (drawings boxed by instance).

    ``mission``: a compiled mission, whose TINA file follows the executor's
    timing (what the vehicle does not fire fires at once, [0,0]).
    """
    from mcl2pnml.view.draw import instance_clusters, render, to_dot
    from mcl2pnml.core.files import atomic_write_text
    from mcl2pnml.io.lola import save_lola
    from mcl2pnml.io.tina import save_tina
    from mcl2pnml.io.pnml.writer import save_pnml

    if fmt == "pnml":
        save_pnml(net, output, layout_engine)
    elif fmt == "tina":
        save_tina(net, output, urgent=mission)
    elif fmt == "lola":
        save_lola(net, output)
    else:
        graph = to_dot(net, clusters=instance_clusters(net), title=title or net.name,
                       legend=True)
        if fmt == "dot":
            atomic_write_text(output, graph.source)
        else:
            render(graph, str(output), fmt)


@main.command("compile", epilog=EXAMPLES)
@click.argument("mission", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path),
              help="Write here (default: MISSION with the format's suffix).")
@click.option("--format", "fmt", type=click.Choice(FORMATS), default="pnml", show_default=True,
              help="PNML (ISO/IEC 15909-2); TINA's .net (a time Petri net: time-outs as "
                   "intervals); LoLA's net format; or a graphviz drawing: dot source, SVG or "
                   "PNG.")
@click.option("--layout", "layout_engine", type=click.Choice(ENGINES), default="auto",
              show_default=True,
              help="Node positions in the PNML: graphviz dot, BFS layers, or none "
                   f"(auto: dot up to {DOT_LIMIT:,} nodes, layers up to {LAYERS_LIMIT:,}).")
def compile_(mission: Path, output: Path | None, fmt: str, layout_engine: str) -> int:
    """Compile MISSION (MCL) to one composed Petri net.

    One shared net per task and per function, entered from every call site;
    time-outs and vehicle bindings travel in the PNML as toolspecific data.
    The initial marking has mission.B and mission.MTX marked.
    """
    net = compile_file(mission)
    output = output or mission.with_suffix(SUFFIX[fmt])
    write_net(net, output, fmt, layout_engine, title=mission.name, mission=True)
    click.echo(f"wrote {output}: {net.summary()}", err=True)
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--engine", type=click.Choice(["petri", "reference"]), default="petri",
              show_default=True,
              help="petri: the executor plays the compiled net; reference: MCL interpreted "
                   "directly. Both must give the same result.")
@click.option("--vehicle", default="sim", show_default=True,
              metavar="sim|SCRIPT.json|bridge:MAPPING.json",
              help="The kinematic AUV simulator, a vehicle script "
                   '({"PRIMITIVE": ["ok@5", "fail@3", "never"], ...}), or a real vehicle '
                   "through a mapping file and a bridge (real time; see --connect).")
@click.option("--connect", metavar="HOST:PORT",
              help="The vehicle's bridge server, for --vehicle bridge:MAPPING.json.")
@click.option("--json", "as_json", is_flag=True,
              help="Print only the result: {outcome, time, trace}.")
@click.option("--log", "log_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Also write every action, event and fired transition as JSON lines here.")
@click.option("--world", type=click.Path(exists=True, dir_okay=False, path_type=Path),
              help="The simulator's world as JSON: tank, start, cross (null: none), noise, "
                   "seed, limits. Default: the paper's 16 x 8 x 5 m tank, a cross at (10, 4).")
@click.option("--transitions", is_flag=True, help="Show fired transitions in the live log.")
@click.option("--max-time", type=click.FloatRange(min=0), default=24 * 3600.0,
              show_default=True, help="Stop a mission still running at this virtual time.")
@click.option("--journal", "journal_path", type=click.Path(dir_okay=False, path_type=Path),
              help="Journal the run here as it happens (JSON lines, each flushed; a new "
                   "file), so that a killed run can be resumed.")
@click.option("--resume", type=click.Path(exists=True, dir_okay=False, path_type=Path),
              help="Continue the killed run of this journal: replay it, check it, go on "
                   "and append to it (its engine, vehicle, world and time limit are reused).")
@click.pass_context
def run(ctx: click.Context, mission: Path, engine: str, vehicle: str, connect: str | None,
        as_json: bool, log_path: Path | None, world: Path | None, transitions: bool,
        max_time: float, journal_path: Path | None, resume: Path | None) -> int:
    """Run MISSION (MCL, or a compiled PNML for the petri engine) against a vehicle.

    Time is virtual: a mission of hours runs in a moment. The live log shows
    each action and event as it happens; at the end, the outcome (OK, FAIL,
    ABORTED, or STALLED with what the mission still waits for), and the
    safe stop: every primitive still enabled is disabled, however the run
    ends (docs/faults.md). --journal writes the run down as it goes;
    --resume JOURNAL continues it after a crash, with no step lost or
    repeated.
    """
    import io
    import json

    from mcl2pnml.runtime import journal as journals
    from mcl2pnml.runtime.aal import ScriptedVehicle
    from mcl2pnml.runtime.engine import run as drive
    from mcl2pnml.core.files import atomic_write_text
    from mcl2pnml.runtime.runlog import RunLog

    replay = header = None
    if resume is not None:
        if journal_path is not None:
            raise click.BadParameter("--resume appends to its own journal; leave out --journal",
                                     param_hint="--journal")
        loaded = journals.load(resume)
        header = loaded.header
        given = {"engine": engine, "vehicle": vehicle, "world": world and str(world),
                 "max_time": max_time}
        for key, value in given.items():
            explicit = ctx.get_parameter_source(key) is click.core.ParameterSource.COMMANDLINE
            if explicit and value != header.get(key):
                raise Mcl2PnmlError(f"the journal's run has --{key.replace('_', '-')} "
                                    f"{header.get(key)}, not {value}",
                                    Location(str(resume), 1, 1))
        engine, vehicle, max_time = header["engine"], header["vehicle"], header["max_time"]
        world = Path(header["world"]) if header.get("world") else None
        if loaded.torn:
            click.echo(loaded.torn, err=True)
    if vehicle.startswith("bridge:") and (resume or journal_path):
        raise click.BadParameter("a journal replays a vehicle of its own (sim or a script); "
                                 "a real vehicle's run cannot be replayed",
                                 param_hint="--resume" if resume else "--journal")
    realtime = vehicle.startswith("bridge:")
    if world and vehicle != "sim":
        raise click.BadParameter("a world is for the simulator (--vehicle sim)",
                                 param_hint="--world")
    if vehicle == "sim":
        from mcl2pnml.runtime.simulator import AUVSimulator, World
        car = AUVSimulator(World.load(world) if world else World())
    elif realtime:
        from mcl2pnml.runtime.bridge import MappedVehicle, TcpTransport, VehicleMapping
        if connect is None:
            raise click.BadParameter("a bridge needs --connect HOST:PORT (the bridge server "
                                     "on the vehicle)", param_hint="--connect")
        car = MappedVehicle(VehicleMapping.load(vehicle[len("bridge:"):]),
                            TcpTransport(connect))
    else:
        car = ScriptedVehicle.load(vehicle)
    if mission.suffix == ".mcl":
        checked = _checked(mission)
        if engine == "reference":
            from mcl2pnml.runtime.reference import ReferenceEngine
            eng = ReferenceEngine(checked)
        else:
            from mcl2pnml.language.compiler import compile_checked
            from mcl2pnml.runtime.executor import PetriEngine
            eng = PetriEngine(compile_checked(checked))
    else:
        if engine == "reference":
            raise click.BadParameter("the reference engine reads MCL, not a net; give the "
                                     ".mcl file", param_hint="--engine")
        from mcl2pnml.runtime.executor import PetriEngine
        from mcl2pnml.io.pnml.reader import load_pnml
        eng = PetriEngine(load_pnml(mission))
    offered = car.primitives
    needed = eng.primitives_used()
    if offered is not None and needed - offered:
        missing = sorted(needed - offered)[0]
        raise click.BadParameter(f"the mission uses '{missing}', which this vehicle does not "
                                 f"offer; it offers {', '.join(sorted(offered))}",
                                 param_hint="--vehicle")
    if isinstance(car, ScriptedVehicle):
        car.check_primitives(needed)
    if resume or journal_path:   # the files the run depends on, as they are now
        files = {"mission": mission, "vehicle": None if vehicle == "sim" else Path(vehicle),
                 "world": world}
        digests = {f"{k}_sha256": journals.digest(f) for k, f in files.items() if f}
        for key, value in digests.items():
            if header is not None and header.get(key) != value:
                raise Mcl2PnmlError(f"{files[key[:-7]]} has changed since this journal was "
                                    "written: its run cannot be resumed",
                                    Location(str(resume), 1, 1))
    jsonl = io.StringIO() if log_path else None
    if resume is not None:
        replay = sink = journals.Replay(loaded)
    elif journal_path is not None:
        sink = journals.create(journal_path, {
            "mission": str(mission), "engine": engine, "vehicle": vehicle,
            "world": world and str(world), "max_time": max_time, **digests})
    else:
        sink = None
    log = RunLog(None if as_json else sys.stdout, jsonl, transitions, sink)
    eng.on_fire = log.fired
    seen = 0

    def listener(entry) -> None:
        nonlocal seen
        log.entry(entry)
        for event, reason in eng.ignored[seen:]:
            log.ignored(event, reason)
        seen = len(eng.ignored)

    if realtime:
        from mcl2pnml.runtime.engine import run_realtime
        result = run_realtime(eng, car, listener=listener, max_time=max_time)
    else:
        result = drive(eng, car, listener=listener, max_time=max_time)
    for event, reason in result.ignored[seen:]:
        log.ignored(event, reason)
    log.end(result.time, result.outcome.value)
    if replay is not None:
        replay.finish()
    if log_path is not None:
        atomic_write_text(log_path, jsonl.getvalue())
    if as_json:
        click.echo(json.dumps(result.as_json()))
    else:
        click.echo(f"outcome {result.outcome.value} at t={result.time:g} s")
        for line in result.waiting:
            click.echo(f"  {line}")
        if result.safe_stop:
            click.echo("  safe stop: disabled " + ", ".join(a.primitive
                                                            for a in result.safe_stop))
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--grammar", type=click.Path(exists=True, file_okay=False, path_type=Path),
              help="Directory of the official PNML RELAX NG grammar (ptnet.pntd and the "
                   "files it includes). Default: $MCL2PNML_PNML_GRAMMAR, else a "
                   "shared/pnml-grammar directory beside or above this one.")
def validate(file: Path, grammar: Path | None) -> int:
    """Check FILE against the official PNML grammar and the P/T net rules.

    The grammar lets some faults pass (an arc from a place to a place, a
    dangling arc); the reader's own checks catch those. Exit status 0 when
    valid, 2 with every problem listed when not.
    """
    from mcl2pnml.io.pnml.grammar import validate as run
    from mcl2pnml.io.pnml.reader import load_pnml

    verdict = run(file, grammar)
    if not verdict.valid:
        for error in verdict.errors:
            click.echo(str(error), err=True)
        n = len(verdict.errors)
        click.echo(f"{file}: invalid PNML ({n} problem{'s' * (n != 1)})", err=True)
        return 2
    net = load_pnml(file)
    click.echo(f"{file}: valid PNML P/T net (ISO/IEC 15909-2, 2009 grammar): "
               f"{len(net.places)} places, {len(net.transitions)} transitions, "
               f"{len(net.arcs)} arcs")
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("name", required=False)
@click.option("--list", "list_", is_flag=True, help="List the template nets and exit.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path),
              help="Write here (default: PNML to standard output).")
@click.option("--format", "fmt", type=click.Choice(FORMATS), default="pnml", show_default=True,
              help="As for compile: PNML, TINA, LoLA, or a drawing (dot, SVG, PNG).")
def template(name: str | None, list_: bool, output: Path | None, fmt: str) -> int:
    """Write the paper's net NAME, from the paper's initial marking M0.

    A pattern (task) comes fused with its primitive, a structure with
    reduced tasks in its slots: the nets the paper analyses.
    """
    from mcl2pnml.io.pnml.writer import to_pnml_bytes
    from mcl2pnml.language.library import default_library

    lib = default_library()
    if list_:
        rows = [(", ".join(t.names), t.kind.value, t.doc) for t in lib.unique()]
        width = max(len(r[0]) for r in rows)
        for names, kind, doc in rows:
            click.echo(f"{names.ljust(width)}  {kind:<9}  {doc}")
        return 0
    if name is None:
        raise click.UsageError("give a template NAME, or --list")
    net = lib.composed(name)
    if output is None and fmt == "pnml":
        click.echo(to_pnml_bytes(net).decode(), nl=False)
        return 0
    output = output or Path(name + SUFFIX[fmt])
    write_net(net, output, fmt)
    click.echo(f"wrote {output}: {net.summary()}", err=True)
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("what", metavar="MISSION.mcl|NET|TEMPLATE")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path),
              help="Write the page here (default: the mission's, net's or template's name "
                   "with .html, in the current directory).")
@click.option("--run", "run_log", type=click.Path(exists=True, dir_okay=False, path_type=Path),
              help="A run to follow step by step: the JSON-lines log of `mcl2pnml run --log`.")
def show(what: str, output: Path | None, run_log: Path | None) -> int:
    """Write one self-contained HTML page to play the token game on a net.

    WHAT is a mission (.mcl), a net (.pnml, TINA .net, LoLA .lola) or a
    template's name (see `template --list`). Click an enabled transition to
    fire it; step back, reset; the marking and every P-invariant are shown
    at each step. A mission or a task can be switched to its reduced model
    (Fig. 3 of the paper); a recorded run can be followed step by step.
    The page needs no server and fetches nothing.
    """
    from mcl2pnml.language.compiler import compile_checked
    from mcl2pnml.io.formats import SUFFIXES, load_net
    from mcl2pnml.view.show import check_run, read_run, save_page, variant
    from mcl2pnml.language.library import TemplateKind, default_library

    path = Path(what)
    is_file = path.suffix == ".mcl" or path.suffix.lower() in SUFFIXES
    if is_file and not path.is_file():
        raise click.BadParameter(f"no file '{what}'", param_hint="MISSION.mcl|NET|TEMPLATE")
    if not is_file and run_log is not None:
        raise click.BadParameter("a run is of a mission: give the mission's .mcl or its "
                                 "compiled net, not a template", param_hint="--run")
    if path.suffix == ".mcl":
        title = path.stem
        checked = _checked(path)
        nets = [(compile_checked(checked), "the mission"),
                (compile_checked(checked, reduced=True),
                 "the mission, every task reduced (Fig. 3)")]
    elif is_file:
        title = path.stem
        nets = [(load_net(path), "the net")]
    else:
        lib = default_library()
        template = lib.get(what)   # unknown: the error lists the templates
        title = what
        if template.kind is TemplateKind.PATTERN:
            nets = [(lib.composed(what), f"{what} with its primitive (Fig. 2)"),
                    (lib.composed(lib.reduced.name), "its reduced model (Fig. 3)")]
        else:
            nets = [(lib.composed(what), f"{what}, as the paper analyses it")]
    run_entries = None
    if run_log is not None:
        run_entries = read_run(run_log)
        check_run(nets[0][0], run_entries, str(run_log))
    output = output or Path(f"{title}.html")
    save_page(output, title, [variant(net, label) for net, label in nets], run_entries)
    click.echo(f"wrote {output}: {nets[0][0].summary()}", err=True)
    return 0


def _parse_initial(text: str) -> dict[str, int]:
    marking: dict[str, int] = {}
    for item in filter(None, (i.strip() for i in text.split(","))):
        place, _, count = item.partition("*")
        if count and not count.isdigit():
            raise click.BadParameter(f"'{item}': a count is a natural number (P*2)",
                                     param_hint="--initial")
        marking[place] = marking.get(place, 0) + (int(count) if count else 1)
    return marking


@main.command(epilog=EXAMPLES)
@click.argument("file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
@click.option("--initial", metavar="P,Q,...",
              help="Start from this marking instead of the file's (P*2 for two tokens).")
@click.option("--state-space", is_flag=True,
              help="Explore the reachable markings only (no invariants, no siphons).")
@click.option("--max-states", type=click.IntRange(min=1), default=5_000_000, show_default=True,
              help="Stop exploring past this many markings.")
@click.option("--progress/--no-progress", default=None,
              help="Show progress of long explorations (default: when stderr is a terminal).")
@click.option("--explorer", type=click.Choice(["auto", "compiled", "packed", "general"]),
              default="auto", show_default=True,
              help="How to explore the markings of a safe net: compiled code (fastest; "
                   "most of a second to load in a fresh process), numpy, or the general "
                   "explorer that every net can use. auto: numpy, then compiled past "
                   "500,000 markings.")
def analyze(file: Path, as_json: bool, initial: str | None, state_space: bool,
            max_states: int, progress: bool | None, explorer: str) -> int:
    """Analyse FILE: a P/T net (PNML, TINA .net, LoLA) or a mission (MCL, compiled first).

    Invariants, siphons, reachable markings. Works on any P/T net, not only
    ours: PNML from TAPAAL, PIPE, pm4py..., and the text formats of TINA
    and LoLA (told apart by the file's suffix: .pnml or .xml, .net, .lola).
    """
    import json

    from analysis.report import analyze as run, render_text

    from mcl2pnml.io.formats import load_net

    net = compile_file(file) if file.suffix == ".mcl" else load_net(file)
    start = None
    if initial is not None:
        start = _parse_initial(initial)
        unknown = sorted(p for p in start if p not in net.place_index)
        if unknown:
            raise click.BadParameter(
                f"no place {', '.join(unknown)} in {file}"
                + did_you_mean(unknown[0], net.place_index, "places"), param_hint="--initial")
    show = sys.stderr.isatty() if progress is None else progress

    def report(states: int, frontier: int) -> None:
        click.echo(f"\r  explored {states:,} markings, {frontier:,} to go...", err=True, nl=False)

    result = run(net, start, state_space_only=state_space, max_states=max_states,
                 progress=report if show else None, explorer=explorer)
    if show:
        click.echo("", err=True)
    click.echo(json.dumps(result, indent=2) if as_json else render_text(result))
    return 0


if __name__ == "__main__":  # pragma: no cover
    main()
