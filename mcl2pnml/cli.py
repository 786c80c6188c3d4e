"""The ``mcl2pnml`` command (click), as ``mcl2pnml --help`` and README's Commands table document it.

It parses options and prints; the work is :mod:`mcl2pnml.pipeline`'s. Errors are handled
once, in :meth:`Cli.main`: a bad argument is one line, a bad input file its located
message (file:line:col, the line, a caret); both exit 2, with no traceback or partial file.
"""
from __future__ import annotations

import json
import signal
import sys
from pathlib import Path

import click

from mcl2pnml import pipeline
from mcl2pnml.cli_options import (
    ANALYZE_OPTIONS, CAMPAIGN_OPTIONS, QUERY_OPTIONS, CERTIFICATE_SIZE, CERTIFY_OPTIONS, CHECK_OPTIONS, COMPILE_OPTIONS, FILE,
    FORMAT_OPTION, MISSION_SIZE, MISSION_SIZE_OPTION, NET_OPTION, ODDS_OPTIONS, OUTPUT,
    PROPERTIES_SIZE, PROPERTY_ATOMS, RUN_OPTIONS, SHOW_OPTIONS)
from mcl2pnml.core.errors import Mcl2PnmlError, OptionError, shown, visible
from mcl2pnml.core.files import check_outputs
from mcl2pnml.core.version import __version__
from mcl2pnml.io.formats import FORMATS
from mcl2pnml.runtime import interrupts

EXAMPLES = """\b
Examples:
  mcl2pnml check examples/sauce.mcl
  mcl2pnml functional examples/sauce.mcl
  mcl2pnml compile examples/sauce.mcl -o sauce.pnml
  mcl2pnml run examples/sauce.mcl --engine reference --vehicle script.json --json
  mcl2pnml run examples/sauce.mcl --vehicle script.json --journal run.journal
  mcl2pnml run examples/sauce.mcl --resume run.journal
  mcl2pnml template task -o task.pnml
  mcl2pnml analyze task.pnml --json --initial B,MTX,OFF,C
  mcl2pnml show examples/sauce.mcl --run run.jsonl
  mcl2pnml validate task.pnml --grammar ~/pnml/grammar
  mcl2pnml certify examples/sauce.mcl
  mcl2pnml odds examples/sauce.mcl --vehicle-model examples/sauce.model.json
  mcl2pnml campaign examples/sauce.mcl --vehicle-model examples/sauce.model.json --runs 10000
"""


class Command(click.Command):
    """A command that shows the option errors of the layers below as its own."""

    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except OptionError as e:   # raised below the CLI: shown as click shows its own
            raise click.BadParameter(e.message, ctx, param_hint=e.option) from None


class Cli(click.Group):
    """A click group whose errors are one clear line and exit status 2."""

    command_class = Command

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
            click.echo(f"{cmd}: error: {visible(e.format_message())} (see '{cmd} --help')",
                       err=True)
            sys.exit(2)
        except click.ClickException as e:
            click.echo(f"mcl2pnml: error: {visible(e.format_message())}", err=True)
            sys.exit(2)
        except Mcl2PnmlError as e:
            click.echo(str(e), err=True)
            sys.exit(2)
        except click.Abort as e:
            click.echo("mcl2pnml: interrupted", err=True)
            # 128 + the signal: a run's SIGTERM that came past its end is 143, Ctrl-C 130
            sys.exit(interrupts.exit_status(getattr(e.__cause__, "signum", signal.SIGINT)))
        except BrokenPipeError:  # e.g. `mcl2pnml ... | head`
            sys.exit(0)
        sys.exit(code if isinstance(code, int) else 0)


@click.group(cls=Cli, epilog=EXAMPLES, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, "--version", prog_name="mcl2pnml", message="%(prog)s %(version)s")
def main() -> None:
    """Compile AUV missions written in MCL to Petri nets, analyse them, run them.

    Nets are read and written as ISO/IEC 15909-2 PNML (P/T nets).
    """


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=FILE)
@CHECK_OPTIONS
def check(mission: Path, properties: str | None, max_props_size: str = PROPERTIES_SIZE,
          max_atoms: int = PROPERTY_ATOMS, strict: bool = False,
          max_mission_size: str = MISSION_SIZE) -> int:
    """Parse and check MISSION (MCL): names, arities, patterns, recursion, properties.

    Every error of the file is reported at once, each with file:line:col; then the
    warnings (docs/warnings.md), on standard error.
    """
    checked = pipeline.check_file(mission, max_mission_size)
    pipeline.warned(mission, checked, strict, _note)
    click.echo(f"{visible(str(mission))}: ok ({checked.summary()})")
    if properties is not None:
        _, compiled = pipeline.properties_of(
            mission, extra=pipeline.properties_file(mission, properties),
            max_size=max_props_size, max_atoms=max_atoms, checked=checked)
        click.echo("\n".join(pipeline.properties_lines(compiled)))
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=FILE)
@click.option("--functions", "with_functions", is_flag=True,
              help="Also print each function's body in functional form.")
@MISSION_SIZE_OPTION
def functional(mission: Path, with_functions: bool, max_mission_size: str = MISSION_SIZE) -> int:
    """Print the functional form of MISSION (the paper's Algorithm 2).

    Structures are written sequence, parallel, if-then-else, while and
    monitor; an empty block or a missing else is NULL; functions stay calls.
    """
    checked = pipeline.check_file(mission, max_mission_size)
    for line in pipeline.functional_form(checked, functions=with_functions):
        click.echo(line)
    return 0


@main.command("compile", epilog=EXAMPLES)
@click.argument("mission", type=FILE)
@COMPILE_OPTIONS
def compile_(mission: Path, output: Path | None, fmt: str, **options) -> int:
    """Compile MISSION (MCL) to one composed Petri net, from mission.B and mission.MTX.

    One shared net per task and per function, entered from every call site;
    time-outs and vehicle bindings travel in the PNML as toolspecific data.
    """
    pipeline.compile_mission(mission, output, fmt, note=_note, **options)
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=FILE)
@RUN_OPTIONS
@click.pass_context
def run(ctx: click.Context, mission: Path, as_json: bool, log_path: Path | None,
        net_id: str | None, lenient: bool, max_mission_size: str, **options) -> int:
    """Run MISSION (MCL, or a compiled PNML for the petri engine) against a vehicle.

    Time is virtual: a mission of hours runs in a moment. The live log shows each action
    and event; then the outcome (OK, FAIL, ABORTED, STALLED with what it waits for, or
    TIMELIMIT: cut short by --max-time, INTERRUPTED: by SIGINT, SIGTERM or SIGHUP) and
    the safe stop: every primitive still enabled is disabled, however the run ends
    (docs/faults.md); a second signal meanwhile is ignored, a third cuts it short.
    --journal writes the run as it goes; --resume continues it.

    \b
    Exit status, one per outcome: 0 OK, 1 FAIL, 4 ABORTED, 5 STALLED, 6 TIMELIMIT;
    2 bad input; interrupted: 128 + the signal (130 SIGINT, 143 SIGTERM, 129 SIGHUP).
    """
    given = frozenset(k for k in options if ctx.get_parameter_source(k)
                      is click.core.ParameterSource.COMMANDLINE)
    result = pipeline.run_mission(
        mission, pipeline.RunOptions(**options, explicit=given),
        text=None if as_json else sys.stdout, log_path=log_path, net_id=net_id,
        lenient=lenient, max_mission_size=max_mission_size, note=_note)
    # the run's end: its outcome is printed whatever signal comes now (but a third)
    with interrupts.guard(interrupts.Phase.PRINTING):
        click.echo(json.dumps(result.as_json()) if as_json else "\n".join(result.report()))
    return result.exit_status


@main.command(epilog=EXAMPLES)
@click.argument("file", type=FILE)
@click.option("--grammar", type=click.Path(exists=True, file_okay=False, path_type=Path),
              help="Directory of the official PNML RELAX NG grammar (ptnet.pntd...), applied "
                   "as well as mcl2pnml's own schema. Default: $MCL2PNML_PNML_GRAMMAR, else a "
                   "shared/pnml-grammar beside or above, else none.")
@NET_OPTION
def validate(file: Path, grammar: Path | None, net_id: str | None) -> int:
    """Check FILE against mcl2pnml's PNML schema, the official grammar where it is
    given or found, and the P/T net rules.

    The rules catch what no schema can say (an arc from a place to a place, a
    reference loop). Exit 0 when valid, 2 with every problem when not.
    """
    verdict, net = pipeline.validate_pnml(file, grammar, net_id)
    if not verdict.valid:
        for line in shown(verdict.errors):
            click.echo(line, err=True)
        n = len(verdict.errors)
        click.echo(f"{visible(str(file))}: invalid PNML ({n} problem{'s' * (n != 1)}; "
                   f"{verdict.judges()})", err=True)
        return 2
    click.echo(f"{visible(str(file))}: valid PNML P/T net ({verdict.judges()}): "
               f"{len(net.places)} places, {len(net.transitions)} transitions, "
               f"{len(net.arcs)} arcs")
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("name", required=False)
@click.option("--list", "list_", is_flag=True, help="List the template nets and exit.")
@click.option("-o", "--output", type=OUTPUT, help="Write here (default: PNML to standard output).")
@FORMAT_OPTION
def template(name: str | None, list_: bool, output: Path | None, fmt: str) -> int:
    """Write the paper's net NAME, from the paper's initial marking M0.

    A pattern (task) comes fused with its primitive, a structure with
    reduced tasks in its slots: the nets the paper analyses.
    """
    if list_:
        rows = pipeline.templates()
        width = max(len(names) for names, _, _ in rows)
        for names, kind, doc in rows:
            click.echo(f"{names.ljust(width)}  {kind:<9}  {doc}")
        return 0
    if name is None:
        raise click.UsageError("give a template NAME, or --list")
    net = pipeline.template_net(name)
    if output is None and fmt == "pnml":
        click.echo(pipeline.to_pnml_bytes(net).decode(), nl=False)
        return 0
    output = output or Path(name + FORMATS[fmt].suffixes[0])
    pipeline.save_net(net, output, fmt, clusters=pipeline.template_clusters(name), expand=None,
                      note=_note)
    click.echo(f"wrote {visible(str(output))}: {net.summary()}", err=True)
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("what", metavar="MISSION.mcl|NET|TEMPLATE")
@SHOW_OPTIONS
def show(what: str, output: Path | None, run_log: Path | None, graph_json: Path | None,
         live_log: Path | None, port: int, linger: float, net_id: str | None,
         lenient: bool, max_mission_size: str = MISSION_SIZE) -> int:
    """Write one self-contained HTML page to play the token game on a net.

    WHAT is a mission (.mcl), a net (.pnml, TINA .net, LoLA .lola) or a
    template (see `template --list`). Click an enabled transition to fire it;
    step back, reset; see the marking and every P-invariant at each step,
    the reduced model (Fig. 3), a recorded run step by step on a clock, the
    mission's tree, the reachability graph. The page needs no server and
    fetches nothing. With --live LOG, the page is served on loopback instead
    and follows a run as `run --log LOG` writes it.
    """
    if live_log is None and (port != 0 or linger != 10.0):
        raise click.UsageError("--port and --linger go with --live")
    if live_log is not None:
        if output is not None or run_log is not None or graph_json is not None:
            raise click.UsageError("--live serves the page: leave out -o, --run and --graph-json")
        shown = pipeline.show_nets(what, with_run=True, net_id=net_id, lenient=lenient,
                                   max_mission_size=max_mission_size)

        def ready(url: str) -> None:
            click.echo(f"serving {shown.title} on {url} , following {live_log} "
                       f"(Ctrl-C stops)", err=True)
        pipeline.serve_show_live(shown, live_log, port=port, linger=linger, ready=ready)
        return 0
    shown = pipeline.show_nets(what, with_run=run_log is not None, net_id=net_id,
                               lenient=lenient, max_mission_size=max_mission_size)
    output = output or Path(f"{shown.title}.html")
    check_outputs([("-o", output), ("--graph-json", graph_json)],
                  [("the run log (--run)", run_log),
                   ("the net or mission", what if Path(what).is_file() else None)])
    pipeline.save_show_page(output, shown, run_log)
    click.echo(f"wrote {visible(str(output))}: {shown.nets[0][0].summary()}", err=True)
    if graph_json is not None:
        graph = pipeline.save_reachability_json(shown.nets[0][0], graph_json)
        click.echo(f"wrote {graph_json}: " + (f"{len(graph['markings']):,} markings, "
                                              f"{len(graph['edges']):,} edges"
                                              if "markings" in graph else graph["reason"]),
                   err=True)
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=FILE)
@CERTIFY_OPTIONS
def certify(mission: Path, output: Path | None, net_file: Path | None,
            net_id: str | None, abort_pending: bool = False,
            max_cert: str = CERTIFICATE_SIZE, max_mission_size: str = MISSION_SIZE) -> int:
    """Prove MISSION from its parts, without exploring: write its certificate.

    Every task pattern and control structure was proven once against the
    interface contract (docs/ARCHITECTURE.md, mcl2pnml.certify); the
    certificate says, instance by instance, which proof and which rule make
    the mission 1-safe, always able to end, and reusable, and which ends it
    has, and is re-checked at once against the compiled net. Exit status 1:
    it does not hold; 2: the mission cannot be certified (a loop that can
    never end: the message points at it; or, with --check, a certificate that is
    not one: too large, not JSON, or not of the certificate's shape).
    """
    cert, net, problems = pipeline.certify_command(mission, output, net_file, net_id,
                                                   abort_pending, max_cert, _note,
                                                   max_mission_size=max_mission_size)
    click.echo("\n".join(pipeline.certificate_lines(net, cert, problems)))
    return 1 if problems else 0


def _note(line: str) -> None:
    """What a command says on the way (warnings, files written), on standard error."""
    click.echo(line, err=True)


def _progress(states: int, frontier: int) -> None:
    click.echo(f"\r  explored {states:,} markings, {frontier:,} to go...", err=True, nl=False)


@main.command(epilog=EXAMPLES)
@click.argument("file", type=FILE)
@ANALYZE_OPTIONS
def analyze(file: Path, as_json: bool, progress: bool | None, **options) -> int:
    """Analyse FILE: a P/T net (PNML, TINA .net, LoLA) or a mission (MCL, compiled first).

    Invariants, siphons, reachable markings, on any P/T net: PNML from TAPAAL,
    PIPE, pm4py..., TINA and LoLA files (by suffix: .pnml or .xml, .net, .lola).
    Exit status 3: a partial answer (the memory budget was reached).
    """
    shown = sys.stderr.isatty() if progress is None else progress
    outcome = pipeline.analyze_file(file, progress=_progress if shown else None,
                                    note=_note, **options)
    click.echo(json.dumps(outcome.as_json(), indent=2) if as_json
               else "\n".join(outcome.lines()))
    return outcome.status


@main.command(epilog=EXAMPLES)
@click.argument("net", type=FILE)
@click.argument("formulas", type=FILE, nargs=-1)
@QUERY_OPTIONS
def query(net: Path, formulas: tuple[Path, ...], examinations: tuple[str, ...], as_json: bool,
          max_states: int, max_memory: str | None, stubborn: bool, net_id: str | None,
          lenient: bool, max_mission_size: str = MISSION_SIZE) -> int:
    """Answer the Model Checking Contest's formula files (FORMULAS.xml: reachability, CTL,
    LTL, upper bounds) and generic examinations on NET, one answer line each in the
    contest's format; exit 3 if one is not answered (docs/interop.md)."""
    outcome = pipeline.query_file(net, formulas, examinations, net_id=net_id,
                                  max_states=max_states, max_memory=max_memory,
                                  stubborn=stubborn, lenient=lenient,
                                  max_mission_size=max_mission_size)
    click.echo(json.dumps(outcome.as_json(), indent=2) if as_json
               else "\n".join(outcome.lines()))
    return outcome.status


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=FILE)
@ODDS_OPTIONS
def odds(mission: Path, model: Path, as_json: bool, sensitivity: bool, prism: Path | None,
         max_states: int, properties: str | None, max_props_size: str | None,
         max_atoms: int | None, max_mission_size: str = MISSION_SIZE) -> int:
    """The exact odds of MISSION with a vehicle model: how likely it ends OK, FAIL or
    ABORTED, or never, and when (docs/odds.md).

    The mission runs as the engines run it (the supervisor first, time-outs
    exact); every choice of the vehicle is weighed by its probability.
    """
    outcome = pipeline.odds_file(mission, model, max_states=max_states,
                                 sensitivity=sensitivity, prism=prism, properties=properties,
                                 max_props_size=max_props_size, max_atoms=max_atoms,
                                 max_mission_size=max_mission_size, note=_note)
    click.echo(json.dumps(outcome.as_json(), indent=2) if as_json
               else "\n".join(outcome.lines()))
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=FILE)
@CAMPAIGN_OPTIONS
def campaign(mission: Path, model: Path | None, as_json: bool, progress: bool | None,
             **options) -> int:
    """Fly MISSION many times, on Dask, with a vehicle model or on the kinematic
    simulator, faults injected if asked: each ending's frequency with its interval, the
    end times, how often each property holds, and optionally a sequential test
    (docs/odds.md)."""
    from tqdm import tqdm

    from mcl2pnml.campaign import lines
    shown = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(total=options["runs"], unit=" runs", file=sys.stderr, disable=not shown,
               dynamic_ncols=True)
    try:
        # a note (a file written) printed above the bar, not through it
        flown = pipeline.campaign_file(
            mission, model, **options, progress=lambda done, _: bar.update(done - bar.n),
            note=(lambda line: tqdm.write(line, file=sys.stderr)) if shown else _note)
    finally:
        bar.close()
    click.echo(json.dumps(flown.as_json(), indent=2) if as_json
               else "\n".join(lines(flown, mission.name)))
    return 0


