"""The ``mcl2pnml`` command (click), as ``mcl2pnml --help`` and README's Commands table document it.

It parses options and prints; the work is :mod:`mcl2pnml.pipeline`'s. Errors are handled
once, in :meth:`Cli.main`: a bad argument is one line, a bad input file its located
message (file:line:col, the line, a caret); both exit 2, with no traceback or partial file.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from analysis.explorers import CHOICES as EXPLORERS, EXPLORERS as EXPLORER_TABLE
from mcl2pnml import pipeline
from mcl2pnml.core.bounds import MAX_PROPERTIES_SIZE, MAX_PROPERTY_ATOMS as PROPERTY_ATOMS
from mcl2pnml.core.errors import Mcl2PnmlError, OptionError, shown
from mcl2pnml.core.files import check_outputs
from mcl2pnml.core.version import __version__
from mcl2pnml.io.formats import FORMATS
from mcl2pnml.io.mccquery import TOOLS as QUERY_TOOLS
from mcl2pnml.runtime.link import HEARTBEAT, LIVENESS, MAX_LINE, SEND_TIMEOUT
from mcl2pnml.runtime.simprims import built_in as simulated
from mcl2pnml.runtime.vehicles import VEHICLES
from mcl2pnml.view.layout import DOT_LIMIT, ENGINES, LAYERS_LIMIT

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
"""
FILE, OUTPUT = (click.Path(exists=True, dir_okay=False, path_type=Path),
                click.Path(dir_okay=False, path_type=Path))
NET_OPTION = click.option("--net", "net_id", metavar="ID",
                          help="The net to read, of a PNML file that holds several.")
PROPERTIES_SIZE = f"{MAX_PROPERTIES_SIZE >> 20}M"
PROPERTIES_SIZE_OPTION = click.option(
    "--max-properties-size", "max_props_size", metavar="SIZE", default=PROPERTIES_SIZE,
    show_default=True,
    help="With --properties: refuse a properties file larger than this, before reading it.")
ATOMS_OPTION = click.option(
    "--max-atoms", metavar="N", type=click.IntRange(min=1), default=PROPERTY_ATOMS,
    show_default=True, help="With --properties: refuse properties of more than N atoms in "
    "all (the mission's and the file's), before checking them.")
CERTIFICATE_SIZE = f"{pipeline.MAX_CERTIFICATE >> 20}M"


def _certificate_size_option(said: str):
    return click.option("--max-certificate-size", "max_cert", metavar="SIZE",
                        default=CERTIFICATE_SIZE, show_default=True, help=said)


STRICT_OPTION = click.option(
    "--strict", is_flag=True,
    help="Make the warnings (docs/warnings.md) errors: exit 2 if there is one. A warning "
    "that is meant is acknowledged in the mission: // mcl: allow W001 because ...")


FORMAT_OPTION = click.option("--format", "fmt", type=click.Choice(list(FORMATS)), default="pnml",
                             show_default=True,
                             help="; ".join(f"{f.name}: {f.says}" for f in FORMATS.values()))


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


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=FILE)
@click.option("--properties", "properties", is_flag=False, flag_value="", default=None,
              metavar="[FILE]", help="Also print each property compiled to place formulas "
              "(docs/properties.md): the mission's, then FILE's (default: MISSION.props, "
              "if there is one).")
@PROPERTIES_SIZE_OPTION
@ATOMS_OPTION
@STRICT_OPTION
def check(mission: Path, properties: str | None, max_props_size: str = PROPERTIES_SIZE,
          max_atoms: int = PROPERTY_ATOMS, strict: bool = False) -> int:
    """Parse and check MISSION (MCL): names, arities, patterns, recursion, properties.

    Every error of the file is reported at once, each with file:line:col; then the
    warnings (docs/warnings.md), on standard error.
    """
    checked = pipeline.check_file(mission)
    pipeline.warned(mission, checked, strict, _note)
    click.echo(f"{mission}: ok ({checked.summary()})")
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
def functional(mission: Path, with_functions: bool) -> int:
    """Print the functional form of MISSION (the paper's Algorithm 2).

    Structures are written sequence, parallel, if-then-else, while and
    monitor; an empty block or a missing else is NULL; functions stay calls.
    """
    for line in pipeline.functional_form(pipeline.check_file(mission), functions=with_functions):
        click.echo(line)
    return 0


@main.command("compile", epilog=EXAMPLES)
@click.argument("mission", type=FILE)
@click.option("-o", "--output", type=OUTPUT, help="Write here (default: MISSION.suffix).")
@FORMAT_OPTION
@click.option("--layout", "layout_engine", type=click.Choice(ENGINES), default="auto",
              show_default=True,
              help="Node positions in the PNML: graphviz dot, BFS layers, or none "
                   f"(auto: dot up to {DOT_LIMIT:,} nodes, layers up to {LAYERS_LIMIT:,}).")
@click.option("--expand", metavar="NAME[,NAME...]|all", default="",
              help="For a drawing (svg, png, dot): the calls drawn open, by the names on "
                   "their boxes, or all; the others are drawn shut, one box each.")
@click.option("--queries", type=OUTPUT, metavar="FILE.xml",
              help="Also write the mission's properties (deadlock, an end always reachable) "
                   "in the Model Checking Contest's XML, for the tools that read the PNML.")
@click.option("--queries-for", "tool", type=click.Choice(list(QUERY_TOOLS)), default="verifypn",
              show_default=True, help="How --queries writes a deadlock inside a formula: "
              + "; ".join(f"{name}: {form}" for name, form in QUERY_TOOLS.items()))
@click.option("--properties", "properties", is_flag=False, flag_value="", default=None,
              metavar="[FILE]", help="Also write the mission's properties (its own, then "
              "FILE's; default: MISSION.props, if there is one) in the Model Checking Contest's "
              "categories beside the output, OUTPUT.LTLCardinality.xml, .CTLCardinality.xml "
              "and .ReachabilityCardinality.xml (docs/properties.md).")
@click.option("--max-memory", metavar="SIZE", help="Memory budget: 4G, 500M (default: half "
              "free). A mission whose net would not fit is one message, exit 2.")
@click.option("--ack-within", metavar="SECONDS", help="With --format tapn: the vehicle "
              "acknowledges an enable or a disable within this many seconds of the moment it "
              "can (default 0: at once).")
@click.option("--report-gap", metavar="SECONDS", help="With --format tapn: a primitive's "
              "reports are at least this many seconds apart, the first at any time (default 1; "
              "0: any number at one instant).")
@PROPERTIES_SIZE_OPTION
@ATOMS_OPTION
@STRICT_OPTION
def compile_(mission: Path, output: Path | None, fmt: str, **options) -> int:
    """Compile MISSION (MCL) to one composed Petri net, from mission.B and mission.MTX.

    One shared net per task and per function, entered from every call site;
    time-outs and vehicle bindings travel in the PNML as toolspecific data.
    """
    pipeline.compile_mission(mission, output, fmt, note=_note, **options)
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=FILE)
@click.option("--engine", type=click.Choice(["petri", "reference"]), default="petri",
              show_default=True, help="petri: the executor plays the compiled net; "
              "reference: MCL interpreted directly. Both must give the same result.")
@click.option("--vehicle", default="sim", show_default=True,
              metavar="|".join(kind.name for kind in VEHICLES),
              help="The AUV simulator (it offers " + ", ".join(sorted(simulated()))
              + ", and those of --sim-primitives and installed packages; docs/simulator.md; "
              "a world NAME.world.json beside the mission is its default), a real vehicle "
              "through a mapping file and a bridge (see --connect), an autopilot over MAVLink "
              "(ArduSub; mavlink: takes another mapping; docs/ardusub.md), or a script "
              '({"PRIMITIVE": ["ok@5", "fail@3", "never"]}; each example of examples/ has one '
              "beside it, NAME.vehicle.json).")
@click.option("--connect", metavar="HOST:PORT", help="The bridge server, for --vehicle bridge: "
              "(a host name, an IPv4 address, or an IPv6 one in brackets: [::1]:7777); for "
              "--vehicle mavlink, the autopilot: tcp:HOST:PORT, udp:HOST:PORT (listen) or "
              "serial:DEVICE[:BAUD].")
@click.option("--secret", type=FILE, help="Authenticate every line of the bridge's link, both "
              "ways (HMAC-SHA256), with the shared secret in this file (mode 600, 16 bytes or "
              "more); the bridge server gets the same file.")
@click.option("--tls-ca", type=FILE, help="Talk TLS to the bridge, checking its certificate "
              "against this authority (PEM).")
@click.option("--tls-cert", type=FILE, help="With --tls-ca: this end's certificate (PEM), for "
              "a bridge that requires one.")
@click.option("--tls-key", type=FILE, help="The private key of --tls-cert (PEM).")
@click.option("--heartbeat", type=click.FloatRange(min=0, min_open=True), default=HEARTBEAT,
              show_default=True, help="Seconds between the heartbeats sent to the bridge (to an "
              "autopilot: of its clock, so faster on a simulator sped up).")
@click.option("--liveness", type=click.FloatRange(min=0, min_open=True), default=LIVENESS,
              show_default=True, help="Seconds without a line from the bridge (its heartbeats "
              "included; an autopilot's heartbeat) after which the link is lost: the run stops, "
              "with its safe stop.")
@click.option("--send-timeout", type=click.FloatRange(min=0, min_open=True),
              default=SEND_TIMEOUT, show_default=True, help="Seconds a line to the bridge may "
              "take to send before the link is lost (a bridge that does not read).")
@click.option("--max-line", type=click.IntRange(min=256), default=MAX_LINE, show_default=True,
              help="The longest line (bytes) the bridge may send; a longer one loses the link.")
@click.option("--json", "as_json", is_flag=True, help="Print only {outcome, time, trace} (and safe_stop, "
              "safe_state, problems where there are: docs/running.md).")
@click.option("--log", "log_path", type=OUTPUT, help="Also log the run here as JSON lines.")
@click.option("--world", type=FILE, help="The simulator's world (JSON: tank, start, cross, "
              "dock, obstacles, plumes, noise, seed, limits; docs/simulator.md). Default: "
              "NAME.world.json beside the mission if there is one, else the paper's "
              "16 x 8 x 5 m tank, a cross at (10, 4).")
@click.option("--sim-primitives", type=FILE, multiple=True, metavar="FILE.py",
              help="Python file registering simulated primitives of your own "
              "(@register on a SimulatedPrimitive, docs/simulator.md); may be repeated.")
@click.option("--transitions", is_flag=True, help="Show fired transitions in the live log.")
@click.option("--max-time", type=click.FloatRange(min=0), default=24 * 3600.0,
              show_default=True, help="Stop a mission still running at this time (virtual, or "
              "the wall clock's for a real vehicle, the autopilot's own for --vehicle mavlink): "
              "outcome TIMELIMIT, with the safe stop.")
@click.option("--journal", type=OUTPUT,
              help="Journal the run here as it happens (a new file), to resume it if killed.")
@click.option("--resume", type=FILE, help="Continue the killed run of this journal, with its "
              "engine, vehicle, world, simulated primitives and time limit: replay, check, go on, "
              "append.")
@NET_OPTION
@click.pass_context
def run(ctx: click.Context, mission: Path, as_json: bool, log_path: Path | None,
        net_id: str | None, **options) -> int:
    """Run MISSION (MCL, or a compiled PNML for the petri engine) against a vehicle.

    Time is virtual: a mission of hours runs in a moment. The live log shows each action
    and event; then the outcome (OK, FAIL, ABORTED, STALLED with what it waits for, or
    TIMELIMIT: cut short by --max-time) and the safe stop: every primitive still enabled
    is disabled, however the run ends (docs/faults.md). --journal writes the run as it
    goes; --resume continues it.

    \b
    Exit status, one per outcome: 0 OK, 1 FAIL, 4 ABORTED, 5 STALLED, 6 TIMELIMIT;
    2 bad input, 130 interrupted.
    """
    given = frozenset(k for k in options if ctx.get_parameter_source(k)
                      is click.core.ParameterSource.COMMANDLINE)
    result = pipeline.run_mission(
        mission, pipeline.RunOptions(**options, explicit=given),
        text=None if as_json else sys.stdout, log_path=log_path, net_id=net_id,
        note=_note)
    click.echo(json.dumps(result.as_json()) if as_json else "\n".join(result.report()))
    return result.outcome.exit_status


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
        click.echo(f"{file}: invalid PNML ({n} problem{'s' * (n != 1)}; {verdict.judges()})",
                   err=True)
        return 2
    click.echo(f"{file}: valid PNML P/T net ({verdict.judges()}): "
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
    pipeline.save_net(net, output, fmt, clusters=pipeline.template_clusters(name), expand=None)
    click.echo(f"wrote {output}: {net.summary()}", err=True)
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("what", metavar="MISSION.mcl|NET|TEMPLATE")
@click.option("-o", "--output", type=OUTPUT, help="Write the page here (default: NAME.html).")
@click.option("--run", "run_log", type=FILE, help="A run to follow: a log of `run --log`.")
@click.option("--graph-json", "graph_json", type=OUTPUT,
              help="Also write the reachability graph the page draws as JSON (up to 2,000 "
                   "markings; above, why there is none).")
@click.option("--live", "live_log", type=click.Path(dir_okay=False, path_type=Path),
              help="Serve the page on loopback (127.0.0.1, a random token in its URL) and "
                   "follow the run of this log as it is written (`run --log`); stops on "
                   "Ctrl-C or after the run's outcome has been shown (--linger).")
@click.option("--port", type=click.IntRange(0, 65535), default=0, show_default=True,
              help="With --live: the port (0: one the system picks).")
@click.option("--linger", type=click.FloatRange(min=0), default=10.0, show_default=True,
              metavar="SECONDS", help="With --live: stop this long after the page was handed "
                                      "the run's outcome.")
@NET_OPTION
def show(what: str, output: Path | None, run_log: Path | None, graph_json: Path | None,
         live_log: Path | None, port: int, linger: float, net_id: str | None) -> int:
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
        shown = pipeline.show_nets(what, with_run=True, net_id=net_id)

        def ready(url: str) -> None:
            click.echo(f"serving {shown.title} on {url} , following {live_log} "
                       f"(Ctrl-C stops)", err=True)
        pipeline.serve_show_live(shown, live_log, port=port, linger=linger, ready=ready)
        return 0
    shown = pipeline.show_nets(what, with_run=run_log is not None, net_id=net_id)
    output = output or Path(f"{shown.title}.html")
    check_outputs([("-o", output), ("--graph-json", graph_json)],
                  [("the run log (--run)", run_log),
                   ("the net or mission", what if Path(what).is_file() else None)])
    pipeline.save_show_page(output, shown, run_log)
    click.echo(f"wrote {output}: {shown.nets[0][0].summary()}", err=True)
    if graph_json is not None:
        graph = pipeline.save_reachability_json(shown.nets[0][0], graph_json)
        click.echo(f"wrote {graph_json}: " + (f"{len(graph['markings']):,} markings, "
                                              f"{len(graph['edges']):,} edges"
                                              if "markings" in graph else graph["reason"]),
                   err=True)
    return 0


@main.command(epilog=EXAMPLES)
@click.argument("mission", type=FILE)
@click.option("-o", "--output", type=OUTPUT, help="Write the certificate here "
              "(default: MISSION.cert.json).")
@click.option("--check", "net_file", type=FILE, metavar="NET.pnml",
              help="Do not certify: re-check the certificate MISSION (a .cert.json) against "
                   "this compiled net, without trusting the compiler.")
@click.option("--abort-pending", is_flag=True, help="Certify the mission started with "
              "mission.A marked too (an abort racing every step): its ends then include "
              "mission.ABORTED.")
@_certificate_size_option("With --check: refuse a certificate larger than this, before "
                          "reading it.")
@NET_OPTION
def certify(mission: Path, output: Path | None, net_file: Path | None,
            net_id: str | None, abort_pending: bool = False,
            max_cert: str = CERTIFICATE_SIZE) -> int:
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
                                                   abort_pending, max_cert, _note)
    click.echo("\n".join(pipeline.certificate_lines(net, cert, problems)))
    return 1 if problems else 0


def _note(line: str) -> None:
    """What a command says on the way (warnings, files written), on standard error."""
    click.echo(line, err=True)


def _progress(states: int, frontier: int) -> None:
    click.echo(f"\r  explored {states:,} markings, {frontier:,} to go...", err=True, nl=False)


@main.command(epilog=EXAMPLES)
@click.argument("file", type=FILE)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
@click.option("--initial", metavar="P,Q,...",
              help="Start from this marking instead of the file's (P*2 for two tokens).")
@click.option("--state-space", is_flag=True, help="The reachable markings only (no invariants).")
@click.option("--max-states", type=click.IntRange(min=1), default=5_000_000,
              show_default=True, help="Stop exploring past this many markings.")
@click.option("--progress/--no-progress", default=None,
              help="Show the progress of long explorations (default: on a terminal).")
@click.option("--explorer", type=click.Choice(EXPLORERS), default="auto", show_default=True,
              help="; ".join(f"{e.name}: {e.doc}" for e in EXPLORER_TABLE.values())
              + ". auto: the fastest for the net's kind and size.")
@click.option("--max-memory", metavar="SIZE", help="Memory budget: 4G, 500M (default: half free).")
@click.option("--properties", "properties", is_flag=False, flag_value="", default=None,
              metavar="[FILE]", help="Check a mission's properties (docs/properties.md) on its "
              "runs: the mission's, then FILE's (default: MISSION.props, if there is one); "
              "exit 1 if one fails, 3 if one is unknown.")
@click.option("--explore", is_flag=True, help="Explore the reachable markings even where a "
              "certificate beside FILE (FILE.cert.json, `mcl2pnml certify`) proves the "
              "behaviour.")
@_certificate_size_option("Refuse a certificate beside FILE larger than this, before "
                          "reading it.")
@click.option("--counterexamples", metavar="DIR",
              type=click.Path(file_okay=False, path_type=Path),
              help="With --properties: for each failing property write DIR/NAME.txt (its run "
                   "in the mission's terms), NAME.vehicle.json (a vehicle script that replays a "
                   "violation on both engines), NAME.log and NAME.html (a page stepping "
                   "through it). No file may be an input: a name that is one is refused "
                   "before anything is written.")
@click.option("--explain", is_flag=True,
              help="With --properties: tell each failing property's counterexample in the "
                   "mission's terms and replay it on both engines, with the vehicle script "
                   "that does (printed, and in --json). Without it (or --counterexamples), "
                   "a counterexample is its firing sequence only, which costs nothing more.")
@click.option("--max-counterexamples", metavar="N", type=click.IntRange(min=0),
              default=pipeline.MAX_COUNTEREXAMPLES, show_default=True,
              help="With --explain or --counterexamples: explain (print, and write) the "
                   "counterexamples of the first N failing properties only; the others are "
                   "given their verdict and firing sequence, and their number is said.")
@click.option("--stubborn", is_flag=True,
              help="With --untimed --properties: partial-order reduction (stubborn sets), on "
                   "a mission proven 1-safe by its certificate: the same verdicts from fewer "
                   "markings where the mission does things at once, a counterexample not "
                   "always the shortest (docs/properties.md).")
@click.option("--timed/--untimed", default=None,
              help="A mission's verdicts in the time it runs in (docs/time.md): whether every "
                   "run ends, its earliest and latest end times, and --properties on the "
                   "time-divergent runs, under the vehicle's assumptions below. The default "
                   "for a mission's --properties; --untimed: on every run of the net, as "
                   "other Petri-net tools read it.")
@click.option("--ack-within", metavar="SECONDS", default="0", show_default=True,
              help="With --timed: the vehicle acknowledges enable and disable within this.")
@click.option("--report-gap", metavar="SECONDS", default="1", show_default=True,
              help="With --timed: a primitive's reports are at least this far apart.")
@click.option("--fair-reports", is_flag=True,
              help="With --timed: a primitive that is on reports eventually (without it, a "
                   "vehicle may stay silent for ever).")
@click.option("--urgency-only", is_flag=True,
              help="With --timed: supervisor steps are urgent but vehicle events may come "
                   "first at their instant (the semantics of timed-arc tools).")
@PROPERTIES_SIZE_OPTION
@ATOMS_OPTION
@NET_OPTION
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
