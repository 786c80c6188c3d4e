"""The options of each ``mcl2pnml`` command: their names, defaults, types and help.

Declarations only, no logic: :mod:`mcl2pnml.cli` applies them to its commands, which
parse and print. Each long option stack is one composed decorator (``RUN_OPTIONS``...),
its options in the order ``--help`` lists them. Each default is the command's options
dataclass's (:mod:`mcl2pnml.commands`), or a shared bound's, never written here.
"""
from __future__ import annotations

from pathlib import Path

import click

from mcl2pnml.analysis.statespace.explorers import CHOICES as EXPLORERS, EXPLORERS as EXPLORER_TABLE
from mcl2pnml.campaign import SchedulerTimeouts, scheduler_address
from mcl2pnml.commands.analyze import AnalyzeOptions
from mcl2pnml.commands.fly import CampaignOptions
from mcl2pnml.commands.certify import CertifyOptions
from mcl2pnml.commands.common import FORMAT, MISSION_SIZE, PROPERTIES_SIZE
from mcl2pnml.commands.compile import CompileOptions
from mcl2pnml.commands.lsp import LspOptions
from mcl2pnml.commands.weigh import OddsOptions
from mcl2pnml.commands.query import EXAMINATIONS, QueryOptions
from mcl2pnml.commands.page import ShowOptions
from mcl2pnml.core.bounds import MAX_PROPERTY_ATOMS as PROPERTY_ATOMS
from mcl2pnml.core.vocabulary import CAN_END
from mcl2pnml.io.formats import FORMATS
from mcl2pnml.io.mccquery import TOOLS as QUERY_TOOLS
from mcl2pnml.runtime.options import RunOptions
from mcl2pnml.runtime.simprims import built_in as simulated
from mcl2pnml.runtime.vehicles import VEHICLES
from mcl2pnml.view.layout import DOT_LIMIT, ENGINES, LAYERS_LIMIT

#: Each command's examples, its --help's epilog: each one a command line that works from
#: the repository's root, on files the repository holds (tests/commands/test_cli_help.py
#: parses every one); the files they write are the only ones not there.
EXAMPLES: dict[str, tuple[str, ...]] = {
    "check": (
        "mcl2pnml check examples/sauce.mcl",
        "mcl2pnml check examples/docking.mcl --vehicle sim",
        "mcl2pnml check examples/docking.mcl --properties --strict",
    ),
    "functional": (
        "mcl2pnml functional examples/sauce.mcl",
        "mcl2pnml functional examples/sampling.mcl --functions",
    ),
    "compile": (
        "mcl2pnml compile examples/sauce.mcl -o sauce.pnml",
        "mcl2pnml compile examples/sauce.mcl --format svg -o sauce.svg --expand all",
        "mcl2pnml compile examples/docking.mcl --format tapn -o docking.tapn",
        "mcl2pnml compile examples/sauce.mcl -o sauce.pnml --queries sauce.queries.xml",
    ),
    "run": (
        "mcl2pnml run examples/sauce.mcl",
        "mcl2pnml run examples/docking.mcl --vehicle examples/docking.vehicle.json "
        "--engine reference --json",
        "mcl2pnml run examples/sauce.mcl --vehicle model:examples/sauce.model.json@7 "
        "--log run.jsonl",
        "mcl2pnml run examples/lawnmower.mcl --journal run.journal",
        "mcl2pnml run examples/sauce.mcl --faults examples/sauce.faults.json",
    ),
    "validate": (
        "mcl2pnml validate tests/data/pnml/schema/valid/labels_in_any_order.pnml",
        "mcl2pnml validate tests/data/pnml/invalid/place_to_place.pnml",
        "MCL2PNML_PNML_GRAMMAR=../shared/pnml-grammar mcl2pnml validate "
        "tests/data/pnml/schema/valid/labels_in_any_order.pnml",
    ),
    "template": (
        "mcl2pnml template --list",
        "mcl2pnml template task -o task.pnml",
        "mcl2pnml template while --format svg -o while.svg",
    ),
    "show": (
        "mcl2pnml show examples/sauce.mcl -o sauce.html",
        "mcl2pnml show task -o task.html",
    ),
    "certify": (
        "mcl2pnml certify examples/dam_inspection.mcl -o dam.cert.json",
        "mcl2pnml certify examples/dam_inspection.mcl --abort-pending -o dam.abort.cert.json",
    ),
    "analyze": (
        "mcl2pnml analyze examples/sauce.mcl",
        "mcl2pnml analyze examples/docking.mcl --timed",
        "mcl2pnml analyze examples/docking.mcl --properties --explain",
        "mcl2pnml analyze tests/data/formats/foreign/buffer.net --json",
        "mcl2pnml analyze tests/data/pnml/foreign/pm4py_order_process.pnml --lenient",
    ),
    "query": (
        "mcl2pnml query tests/data/formats/foreign/mutex.lola --examination "
        "ReachabilityDeadlock --examination OneSafe",
    ),
    "odds": (
        "mcl2pnml odds examples/sauce.mcl --vehicle-model examples/sauce.model.json",
        "mcl2pnml odds examples/lawnmower.mcl --vehicle-model examples/lawnmower.model.json "
        "--sensitivity",
    ),
    "lsp": (
        "mcl2pnml lsp",
        "mcl2pnml lsp --max-document-size 4M",
    ),
    "campaign": (
        "mcl2pnml campaign examples/sauce.mcl --vehicle-model examples/sauce.model.json "
        "--runs 10000",
        "mcl2pnml campaign examples/sauce.mcl --faults examples/sauce.faults.json --runs 500 "
        "--target 0.9",
    ),
}


def examples(command: str | None = None) -> str:
    """The epilog of ``command``'s --help: its examples; of ``mcl2pnml --help``
    (``command`` None), each command's first."""
    lines = [shown[0] for shown in EXAMPLES.values()] if command is None else \
        EXAMPLES[command]
    return "\b\nExamples:\n" + "".join(f"  {line}\n" for line in lines)


FILE, OUTPUT = (click.Path(exists=True, dir_okay=False, path_type=Path),
                click.Path(dir_okay=False, path_type=Path))
NET_OPTION = click.option("--net", "net_id", metavar="ID",
                          help="The net to read, of a PNML file that holds several.")
LENIENT_OPTION = click.option(
    "--lenient", is_flag=True,
    help="Read a PNML file the forgiving way: other tools' dialects (PIPE, pm4py's final "
         "markings, TAPAAL's own format, WoPeD's subprocesses, several nets) that the strict "
         "reading refuses (docs/pnml.md). A proof never rests on it: a certificate beside "
         "the file is not taken, and certify --check always reads strictly.")
MISSION_SIZE_OPTION = click.option(
    "--max-mission-size", "max_mission_size", metavar="SIZE", default=MISSION_SIZE,
    show_default=True, help="Refuse a mission (an .mcl file) larger than this, before "
    "reading it.")
PROPERTIES_SIZE_OPTION = click.option(
    "--max-properties-size", "max_props_size", metavar="SIZE", default=PROPERTIES_SIZE,
    show_default=True,
    help="With --properties: refuse a properties file larger than this, before reading it.")
ATOMS_OPTION = click.option(
    "--max-atoms", metavar="N", type=click.IntRange(min=1), default=PROPERTY_ATOMS,
    show_default=True, help="With --properties: refuse properties of more than N atoms in "
    "all (the mission's and the file's), before checking them.")
def _certificate_size_option(said: str):
    return click.option("--max-certificate-size", "max_cert", metavar="SIZE",
                        default=CertifyOptions.max_cert, show_default=True, help=said)


SIM_PRIMITIVES_OPTION = click.option(
    "--sim-primitives", type=FILE, multiple=True, metavar="FILE.py",
    help="Python file registering simulated primitives of your own (@register on a "
         "SimulatedPrimitive, docs/simulator.md); may be repeated.")
#: The vehicles --vehicle names, as the table of kinds of vehicle names them.
VEHICLE_SPECS = "|".join(kind.name for kind in VEHICLES)


STRICT_OPTION = click.option(
    "--strict", is_flag=True,
    help="Make the warnings (docs/warnings.md) errors: exit 2 if there is one. A warning "
    "that is meant is acknowledged in the mission: // mcl: allow W001 because ...")


FORMAT_OPTION = click.option("--format", "fmt", type=click.Choice(list(FORMATS)), default=FORMAT,
                             show_default=True,
                             help="; ".join(f"{f.name}: {f.says}" for f in FORMATS.values()))


def _composed(*options):
    """One decorator applying ``options`` as if stacked in this order above a function."""
    def apply(f):
        for option in reversed(options):   # click applies the nearest one first
            f = option(f)
        return f
    return apply


def _properties_options(what: str):
    """``--properties [FILE]`` (the mission's properties, then FILE's, default
    MISSION.props beside it) and its bounds; ``what`` says what the command does
    with them."""
    return _composed(
        click.option("--properties", "properties", is_flag=False, flag_value="", default=None,
                     metavar="[FILE]", help=f"{what} (docs/properties.md): the mission's, then "
                     "FILE's (default: MISSION.props, if there is one)."),
        PROPERTIES_SIZE_OPTION,
        ATOMS_OPTION)


CHECK_OPTIONS = _composed(  # check MISSION
    click.argument("mission", type=FILE),
    click.option("--vehicle", metavar=VEHICLE_SPECS,
                 help="Also check that this vehicle, as run --vehicle names it, offers every "
                      "primitive the mission's tasks call: each one it does not offer is an "
                      "error at its first call, all at once (the simulator's primitives: "
                      "docs/simulator.md; a script or a vehicle model answers for any)."),
    SIM_PRIMITIVES_OPTION,
    _properties_options("Also print each property compiled to place formulas"),
    STRICT_OPTION,
    MISSION_SIZE_OPTION,
)


FUNCTIONAL_OPTIONS = _composed(  # functional MISSION
    click.argument("mission", type=FILE),
    click.option("--functions", "functions", is_flag=True,
                 help="Also print each function's body in functional form."),
    MISSION_SIZE_OPTION,
)


VALIDATE_OPTIONS = _composed(  # validate FILE
    click.argument("file", type=FILE),
    click.option("--grammar", type=click.Path(exists=True, file_okay=False, path_type=Path),
                 help="Directory of the official PNML RELAX NG grammar (ptnet.pntd...), "
                      "applied as well as mcl2pnml's own schema. Default: "
                      "$MCL2PNML_PNML_GRAMMAR, else none (it is never looked for)."),
    NET_OPTION,
)


TEMPLATE_OPTIONS = _composed(  # template [NAME]
    click.argument("name", required=False),
    click.option("--list", "list_", is_flag=True, help="List the template nets and exit."),
    click.option("-o", "--output", type=OUTPUT,
                 help="Write here (default: PNML to standard output)."),
    FORMAT_OPTION,
)


COMPILE_OPTIONS = _composed(  # compile MISSION
    click.argument("mission", type=FILE),
    click.option("-o", "--output", type=OUTPUT, help="Write here (default: MISSION.suffix)."),
    FORMAT_OPTION,
    click.option("--layout", "layout_engine", type=click.Choice(ENGINES),
                 default=CompileOptions.layout_engine,
                 show_default=True,
                 help="Node positions in the PNML: graphviz dot, BFS layers, or none "
                      f"(auto: dot up to {DOT_LIMIT:,} nodes, layers up to {LAYERS_LIMIT:,})."),
    click.option("--expand", metavar="NAME[,NAME...]|all", default=CompileOptions.expand,
                 help="For a drawing (svg, png, dot): the calls drawn, by the names on "
                      "their boxes (the instance's, or as MCL writes the call), each with the "
                      "calls it makes shut, one box each; by default the mission's own net; "
                      "all: the whole net."),
    click.option("--queries", type=OUTPUT, metavar="FILE.xml",
                 help=f"Also write the mission's properties (a deadlock, {CAN_END}) in the "
                      "Model Checking Contest's XML, for the tools that read the PNML."),
    click.option("--queries-for", "tool", type=click.Choice(list(QUERY_TOOLS)),
                 default=CompileOptions.tool,
                 show_default=True, help="How --queries writes a deadlock inside a formula: "
                 + "; ".join(f"{name}: {form}" for name, form in QUERY_TOOLS.items())),
    click.option("--properties", "properties", is_flag=False, flag_value="", default=None,
                 metavar="[FILE]", help="Also write the mission's properties (its own, then "
                 "FILE's; default: MISSION.props, if there is one) in the Model Checking Contest's "
                 "categories beside the output, OUTPUT.LTLCardinality.xml, .CTLCardinality.xml "
                 "and .ReachabilityCardinality.xml (docs/properties.md)."),
    click.option("--max-memory", metavar="SIZE", help="Memory budget: 4G, 500M (default: half "
                 "free). A mission whose net would not fit is one message, exit 2."),
    click.option("--ack-within", metavar="SECONDS", help="With --format tapn: the vehicle "
                 "acknowledges an enable or a disable within this many seconds of the moment "
                 "it can (default 0: at once)."),
    click.option("--report-gap", metavar="SECONDS", help="With --format tapn: a primitive's "
                 "reports are at least this many seconds apart, the first at any time "
                 "(default 1; 0: any number at one instant)."),
    PROPERTIES_SIZE_OPTION,
    ATOMS_OPTION,
    STRICT_OPTION,
    MISSION_SIZE_OPTION,
)


RUN_OPTIONS = _composed(  # run MISSION
    click.argument("mission", type=FILE),
    click.option("--engine", type=click.Choice(["petri", "reference"]),
                 default=RunOptions.engine,
                 show_default=True, help="petri: the executor plays the compiled net; "
                 "reference: MCL interpreted directly. Both must give the same result."),
    click.option("--vehicle", default=RunOptions.vehicle, show_default=True,
                 metavar=VEHICLE_SPECS,
                 help="The AUV simulator (it offers " + ", ".join(sorted(simulated()))
                 + ", and those of --sim-primitives and installed packages; docs/simulator.md; "
                 "a world NAME.world.json beside the mission is its default), a real vehicle "
                 "through a mapping file and a bridge (see --connect), an autopilot over MAVLink "
                 "(ArduSub; mavlink: takes another mapping; docs/ardusub.md), a vehicle model "
                 "drawing its answers (docs/odds.md; @SEED picks the run), or a script "
                 '({"PRIMITIVE": ["ok@5", "fail@3", "never"]}; each example of examples/ has one '
                 "beside it, NAME.vehicle.json)."),
    click.option("--connect", metavar="HOST:PORT", help="The bridge server, for --vehicle bridge: "
                 "(a host name, an IPv4 address, or an IPv6 one in brackets: [::1]:7777); for "
                 "--vehicle mavlink, the autopilot: tcp:HOST:PORT, udp:HOST:PORT (listen) or "
                 "serial:DEVICE[:BAUD]."),
    click.option("--secret", type=FILE, help="Authenticate every line of the bridge's link, both "
                 "ways (HMAC-SHA256), with the shared secret in this file (mode 600, 16 bytes or "
                 "more); the bridge server gets the same file."),
    click.option("--tls-ca", type=FILE, help="Talk TLS to the bridge, checking its certificate "
                 "against this authority (PEM)."),
    click.option("--tls-cert", type=FILE, help="With --tls-ca: this end's certificate (PEM), for "
                 "a bridge that requires one."),
    click.option("--tls-key", type=FILE, help="The private key of --tls-cert (PEM)."),
    click.option("--heartbeat", type=click.FloatRange(min=0, min_open=True),
                 default=RunOptions.heartbeat, show_default=True, help="Seconds between the heartbeats sent to the bridge (to an "
                 "autopilot: of its clock, so faster on a simulator sped up)."),
    click.option("--liveness", type=click.FloatRange(min=0, min_open=True),
                 default=RunOptions.liveness, show_default=True, help="Seconds without a line from the bridge (its heartbeats "
                 "included; an autopilot's heartbeat) after which the link is lost: the run "
                 "stops, with its safe stop."),
    click.option("--send-timeout", type=click.FloatRange(min=0, min_open=True),
                 default=RunOptions.send_timeout, show_default=True,
                 help="Seconds a line to the bridge may "
                 "take to send before the link is lost (a bridge that does not read)."),
    click.option("--max-line", type=click.IntRange(min=256), default=RunOptions.max_line,
                 show_default=True,
                 help="The longest line (bytes) the bridge may send; a longer one loses the link."),
    click.option("--json", "as_json", is_flag=True, help="Print only {outcome, time, trace} "
                 "(and safe_stop, safe_state, problems where there are: docs/running.md)."),
    click.option("--log", "log_path", type=OUTPUT, help="Also log the run here as JSON lines."),
    click.option("--world", type=FILE, help="The simulator's world (JSON: tank, start, cross, "
                 "dock, obstacles, plumes, noise, seed, limits; docs/simulator.md). Default: "
                 "NAME.world.json beside the mission if there is one, else the paper's "
                 "16 x 8 x 5 m tank, a cross at (10, 4)."),
    SIM_PRIMITIVES_OPTION,
    click.option("--faults", type=FILE, metavar="FAULTS.json",
                 help="Inject these faults into a simulated vehicle's events (sim, a model, "
                      "a script; docs/faults.md), drawn with the seed of sim@SEED or "
                      "model:MODEL.json@SEED (else 0): a campaign's run flown again alone."),
    click.option("--transitions", is_flag=True, help="Show fired transitions in the live log."),
    click.option("--max-time", type=click.FloatRange(min=0), default=RunOptions.max_time,
                 show_default=True, help="Stop a mission still running at this time (virtual, or "
                 "the wall clock's for a real vehicle, the autopilot's own for --vehicle "
                 "mavlink): outcome TIMELIMIT, with the safe stop."),
    click.option("--ack-within", metavar="SECONDS", default=RunOptions.ack_within,
                 show_default=True,
                 help="The assumption analyze --timed proved its verdicts under: the vehicle "
                      "acknowledges enable and disable within this. A later one is said as a "
                      "breach (docs/time.md)."),
    click.option("--report-gap", metavar="SECONDS", default=RunOptions.report_gap,
                 show_default=True,
                 help="The assumption analyze --timed proved its verdicts under: a primitive's "
                      "reports are at least this far apart. Closer ones are said as a breach."),
    click.option("--stop-on-breach", is_flag=True,
                 help="Stop the run at the first breach of --ack-within or --report-gap: "
                      "outcome BREACH (exit 7), with the safe stop."),
    click.option("--journal", type=OUTPUT,
                 help="Journal the run here as it happens (a new file), to resume it if killed."),
    click.option("--resume", type=FILE, help="Continue the killed run of this journal, with its "
                 "engine, vehicle, world, simulated primitives, time limit and assumptions: "
                 "replay, check, go on, append."),
    NET_OPTION,
    LENIENT_OPTION,
    MISSION_SIZE_OPTION,
)


SHOW_OPTIONS = _composed(  # show WHAT
    click.argument("what", metavar="MISSION.mcl|NET|TEMPLATE"),
    click.option("-o", "--output", type=OUTPUT, help="Write the page here (default: NAME.html)."),
    click.option("--run", "run_log", type=FILE, help="A run to follow: a log of `run --log`."),
    click.option("--graph-json", "graph_json", type=OUTPUT,
                 help="Also write the reachability graph the page draws as JSON (up to 2,000 "
                      "markings; above, why there is none)."),
    click.option("--live", "live_log", type=click.Path(dir_okay=False, path_type=Path),
                 help="Serve the page on loopback (127.0.0.1, a random token in its URL) and "
                      "follow the run of this log as it is written (`run --log`); stops on "
                      "Ctrl-C or after the run's outcome has been shown (--linger)."),
    click.option("--port", type=click.IntRange(0, 65535), default=ShowOptions.port,
                 show_default=True,
                 help="With --live: the port (0: one the system picks)."),
    click.option("--linger", type=click.FloatRange(min=0), default=ShowOptions.linger,
                 show_default=True,
                 metavar="SECONDS", help="With --live: stop this long after the page was handed "
                                         "the run's outcome."),
    NET_OPTION,
    LENIENT_OPTION,
    MISSION_SIZE_OPTION,
)


CERTIFY_OPTIONS = _composed(  # certify MISSION
    click.argument("mission", type=FILE),
    click.option("-o", "--output", type=OUTPUT, help="Write the certificate here "
                 "(default: MISSION.cert.json)."),
    click.option("--check", "net_file", type=FILE, metavar="NET.pnml",
                 help="Do not certify: re-check the certificate MISSION (a .cert.json) against "
                      "this compiled net, without trusting the compiler."),
    click.option("--abort-pending", is_flag=True, help="Certify the mission started with "
                 "mission.A marked too (an abort racing every step): its ends then include "
                 "mission.ABORTED."),
    _certificate_size_option("With --check: refuse a certificate larger than this, before "
                             "reading it."),
    MISSION_SIZE_OPTION,
    NET_OPTION,
)


ANALYZE_OPTIONS = _composed(  # analyze FILE
    click.argument("file", type=FILE),
    click.option("--json", "as_json", is_flag=True, help="Print one JSON object."),
    click.option("--initial", metavar="P,Q,...",
                 help="Start from this marking instead of the file's (P*2 for two tokens)."),
    click.option("--state-space", is_flag=True,
                 help="The reachable markings only (no invariants)."),
    click.option("--structure", is_flag=True,
                 help="Enumerate the minimal semi-positive invariants, siphons and traps "
                      "even where the state space decides every property they bear on "
                      "(there, past 100 places, they are left out; exponential in the "
                      "worst case)."),
    click.option("--max-states", type=click.IntRange(min=1),
                 default=AnalyzeOptions.max_states,
                 show_default=True, help="Stop exploring past this many markings."),
    click.option("--progress/--no-progress", default=None,
                 help="Show the progress of long explorations (default: on a terminal)."),
    click.option("--explorer", type=click.Choice(EXPLORERS), default=AnalyzeOptions.explorer,
                 show_default=True,
                 help="; ".join(f"{e.name}: {e.doc}" for e in EXPLORER_TABLE.values())
                 + ". auto: the fastest for the net's kind and size."),
    click.option("--max-memory", metavar="SIZE",
                 help="Memory budget: 4G, 500M (default: half free)."),
    click.option("--properties", "properties", is_flag=False, flag_value="", default=None,
                 metavar="[FILE]", help="Check a mission's properties (docs/properties.md) on its "
                 "runs: the mission's, then FILE's (default: MISSION.props, if there is one); "
                 "exit 1 if one fails, 3 if one is unknown."),
    click.option("--explore", is_flag=True, help="Explore the reachable markings even where a "
                 "certificate beside FILE (FILE.cert.json, `mcl2pnml certify`) proves the "
                 "behaviour."),
    _certificate_size_option("Refuse a certificate beside FILE larger than this, before "
                             "reading it."),
    click.option("--counterexamples", metavar="DIR",
                 type=click.Path(file_okay=False, path_type=Path),
                 help="With --properties: for each failing property write DIR/NAME.txt (its run "
                      "in the mission's terms), NAME.vehicle.json (a vehicle script that replays a "
                      "violation on both engines), NAME.log and NAME.html (a page stepping "
                      "through it). No file may be an input: a name that is one is refused "
                      "before anything is written."),
    click.option("--explain", is_flag=True,
                 help="With --properties: tell each failing property's counterexample in the "
                      "mission's terms and replay it on both engines, with the vehicle script "
                      "that does (printed, and in --json). Without it (or --counterexamples), "
                      "a counterexample is its firing sequence only, which costs nothing more."),
    click.option("--max-counterexamples", metavar="N", type=click.IntRange(min=0),
                 default=AnalyzeOptions.max_counterexamples, show_default=True,
                 help="With --explain or --counterexamples: explain (print, and write) the "
                      "counterexamples of the first N failing properties only; the others are "
                      "given their verdict and firing sequence, and their number is said."),
    click.option("--stubborn", is_flag=True,
                 help="With --untimed --properties: partial-order reduction (stubborn sets), on "
                      "a mission proven 1-safe by its certificate: the same verdicts from fewer "
                      "markings where the mission does things at once, a counterexample not "
                      "always the shortest (docs/properties.md)."),
    click.option("--timed/--untimed", default=None,
                 help="A mission's verdicts in the time it runs in (docs/time.md): whether every "
                      "run ends, its earliest and latest end times, and --properties on the "
                      "time-divergent runs, under the vehicle's assumptions below. The default "
                      "for a mission's --properties; --untimed: on every run of the net, as "
                      "other Petri-net tools read it."),
    click.option("--ack-within", metavar="SECONDS", default=AnalyzeOptions.ack_within,
                 show_default=True,
                 help="With --timed: the vehicle acknowledges enable and disable within this."),
    click.option("--report-gap", metavar="SECONDS", default=AnalyzeOptions.report_gap,
                 show_default=True,
                 help="With --timed: a primitive's reports are at least this far apart."),
    click.option("--fair-reports", is_flag=True,
                 help="With --timed: a primitive that is on reports eventually (without it, a "
                      "vehicle may stay silent for ever)."),
    click.option("--urgency-only", is_flag=True,
                 help="With --timed: supervisor steps are urgent but vehicle events may come "
                      "first at their instant (the semantics of timed-arc tools)."),
    PROPERTIES_SIZE_OPTION,
    ATOMS_OPTION,
    NET_OPTION,
    LENIENT_OPTION,
    MISSION_SIZE_OPTION,
)


QUERY_OPTIONS = _composed(  # query NET [FORMULAS.xml...]
    click.argument("net", type=FILE),
    click.argument("formulas", type=FILE, nargs=-1),
    click.option("--examination", "examinations", multiple=True,
                 type=click.Choice(list(EXAMINATIONS)),
                 help="Also a generic examination of the contest (may be repeated)."),
    click.option("--json", "as_json", is_flag=True, help="Print one JSON object."),
    click.option("--max-states", type=click.IntRange(min=1), default=QueryOptions.max_states,
                 show_default=True,
                 help="Build no reachability graph past this many markings: then the "
                      "reachability questions are searched on the fly (up to as many), and "
                      "what the P-invariants settle is answered; the rest is not."),
    click.option("--max-memory", metavar="SIZE",
                 help="Memory budget: 4G, 500M (default: half free)."),
    click.option("--stubborn", is_flag=True,
                 help="Search the reachability questions of a 1-safe net on the fly under "
                      "partial-order reduction (stubborn sets), once a P-invariant proves the "
                      "net safe: the same answers from fewer markings where the net does "
                      "things at once (docs/interop.md)."),
    NET_OPTION,
    LENIENT_OPTION,
    MISSION_SIZE_OPTION,
)


ODDS_OPTIONS = _composed(  # odds MISSION
    click.argument("mission", type=FILE),
    click.option("--vehicle-model", "model", type=FILE, required=True, metavar="MODEL.json",
                 help="How likely each primitive is to achieve or fail, and when it answers "
                      "(docs/odds.md)."),
    click.option("--json", "as_json", is_flag=True, help="Print one JSON object."),
    click.option("--sensitivity", is_flag=True,
                 help="Also P(OK) with each primitive always achieving, and never: which "
                      "primitive's reliability matters most (the odds again, twice per "
                      "primitive)."),
    click.option("--prism", type=OUTPUT, metavar="FILE.pm",
                 help="Write the chain in PRISM's language (PRISM and Storm read it)."),
    _properties_options("Also the probability that each property holds"),
    click.option("--max-states", type=click.IntRange(min=1), default=OddsOptions.max_states,
                 show_default=True, help="Refuse a chain of more states than this."),
    MISSION_SIZE_OPTION,
)


class SchedulerAddress(click.ParamType):
    """A Dask scheduler's address, checked as it is parsed (tcp://HOST:PORT)."""

    name = "address"

    def convert(self, value, param, ctx):
        try:
            return scheduler_address(value)
        except ValueError as e:
            self.fail(str(e), param, ctx)


class SchedulerTimeoutsType(click.ParamType):
    """``HANDSHAKE[,SILENCE]`` in seconds, to a :class:`SchedulerTimeouts`."""

    name = "seconds"

    def convert(self, value, param, ctx):
        if isinstance(value, SchedulerTimeouts):
            return value
        try:
            return SchedulerTimeouts.parse(value)
        except ValueError as e:
            self.fail(str(e), param, ctx)


CAMPAIGN_OPTIONS = _composed(  # campaign MISSION
    click.argument("mission", type=FILE),
    click.option("--vehicle-model", "model", type=FILE, metavar="MODEL.json",
                 help="The vehicle model the runs draw their answers from (docs/odds.md); "
                      "without it, the runs fly the kinematic simulator."),
    click.option("--world", type=FILE, metavar="WORLD.json",
                 help="The simulator's world (docs/simulator.md; default: MISSION.world.json "
                      "beside the mission, if there is one, else the paper's tank). Its "
                      "\"noise\" makes runs differ; run k seeds it with SEED+k."),
    click.option("--faults", type=FILE, metavar="FAULTS.json",
                 help="Inject these faults into every run (docs/faults.md): reports lost, "
                      "repeated, late, goals failed."),
    _properties_options("Judge each run on the properties, how often each holds"),
    click.option("--runs", type=click.IntRange(min=1, max=10_000_000),
                 default=CampaignOptions.runs,
                 show_default=True, help="How many runs (fewer if --target decides first)."),
    click.option("--engine", type=click.Choice(["petri", "reference"]),
                 default=CampaignOptions.engine,
                 show_default=True, help="The engine that runs the mission."),
    click.option("--seed", type=click.IntRange(min=0), default=CampaignOptions.seed,
                 show_default=True,
                 help="Run k draws with seed SEED+k (run --vehicle model:MODEL.json@SEED, "
                      "or sim@SEED, flies it again alone)."),
    click.option("--confidence", type=click.FloatRange(0.5, 0.999999),
                 default=CampaignOptions.confidence,
                 show_default=True, help="Of the intervals and the sequential test."),
    click.option("--target", type=click.FloatRange(0.0, 1.0, min_open=True, max_open=True),
                 help="Stop as soon as P(OK) >= TARGET is decided, either way (Wald's "
                      "sequential test)."),
    click.option("--workers", type=click.IntRange(min=1, max=256),
                 help="Processes of the local Dask cluster (default: one per core)."),
    click.option("--scheduler", type=SchedulerAddress(), metavar="tcp://HOST:8786",
                 help="Send the runs to this Dask scheduler instead of a local cluster."),
    click.option("--scheduler-timeout", type=SchedulerTimeoutsType(),
                 metavar="HANDSHAKE[,SILENCE]", default=str(CampaignOptions.scheduler_timeout),
                 show_default=True,
                 help="Seconds a scheduler may take to complete Dask's handshake; and "
                      "seconds mid-run with no batch done and no answer from the scheduler "
                      "(or no worker on it) before the campaign ends. Either is one message, "
                      "exit 2, nothing written."),
    click.option("--table", type=OUTPUT, metavar="FILE.csv|FILE.parquet",
                 help="Write every run (seed, outcome, end time)."),
    click.option("--plot", type=OUTPUT, metavar="FILE.png|FILE.svg|FILE.pdf",
                 help="Draw the outcomes with their intervals and the end times."),
    click.option("--json", "as_json", is_flag=True, help="Print one JSON object."),
    click.option("--progress/--no-progress", default=None,
                 help="Show a bar of the runs done, their rate and the time left (default: "
                      "on a terminal)."),
    MISSION_SIZE_OPTION,
)


LSP_OPTIONS = _composed(  # lsp
    click.option("--stdio", is_flag=True,
                 help="Talk on standard input and output, as it always does (editors' "
                      "clients pass it)."),
    click.option("--max-document-size", metavar="SIZE",
                 default=LspOptions.max_document_size, show_default=True,
                 help="Check no document larger than this: one diagnostic says it is not "
                      "checked."),
)
