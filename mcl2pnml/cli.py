"""The ``mcl2pnml`` command (click), as ``mcl2pnml --help`` and README's Commands table document it.

It parses options and prints; what each command does is its module's in
:mod:`mcl2pnml.commands`, called with the command's options dataclass. Errors are handled
once, in :meth:`Cli.main`: a bad argument is one line, a bad input file its located message
(file:line:col, the line, a caret); both exit 2, with no traceback or partial file; a
setting refused (:class:`~mcl2pnml.core.settings.SettingError`) shows as the option typed.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import click

from mcl2pnml.cli_options import (
    ANALYZE_OPTIONS, CAMPAIGN_OPTIONS, CERTIFY_OPTIONS, CHECK_OPTIONS, COMPILE_OPTIONS,
    FUNCTIONAL_OPTIONS, ODDS_OPTIONS, QUERY_OPTIONS, RUN_OPTIONS, SHOW_OPTIONS, TEMPLATE_OPTIONS,
    VALIDATE_OPTIONS, examples)
from mcl2pnml.commands import (analyze as analyzing, certify as certifying, check as checking,
                               compile as compiling, fly as campaigning, page as showing,
                               query as querying, run as running, template as templating,
                               validate as validating, weigh as weighing)
from mcl2pnml.cli_options import LSP_OPTIONS
from mcl2pnml.commands import lsp as serving
from mcl2pnml.commands.common import (VERSION, Mcl2PnmlError, Notes, ProgressMeter, RunsBar,
                                      SettingError, UsageProblem, visible)


def option_of(ctx: click.Context, setting: str) -> str:
    """The option (or argument) typed for ``setting``, as click's errors name it (``-o``,
    ``--net``, ``MISSION``); a setting of no parameter: ``--`` and its name, ``-`` for ``_``."""
    for param in ctx.command.params:
        if param.name == setting:
            return param.human_readable_name if isinstance(param, click.Argument) \
                else param.opts[0]
    return "--" + setting.replace("_", "-")


class Command(click.Command):
    """A command that shows the setting errors of the layers below as its own options'."""

    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except SettingError as e:   # raised below the CLI: shown as click shows its own
            raise click.BadParameter(e.worded(lambda setting: option_of(ctx, setting)), ctx,
                                     param_hint=option_of(ctx, e.setting)) from None
        except UsageProblem as e:
            raise click.UsageError(e.message, ctx) from None


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
            sys.exit(running.interrupted_status(e.__cause__))
        except BrokenPipeError:  # e.g. `mcl2pnml ... | head`
            sys.exit(0)
        sys.exit(code if isinstance(code, int) else 0)


def _notes() -> Notes:   # what a command says on the way: warnings, files written
    return Notes(sys.stderr)


def _print(outcome, as_json: bool = False, indent: int | None = 2) -> None:   # stdout
    click.echo(json.dumps(outcome.as_json(), indent=indent) if as_json
               else "\n".join(outcome.lines()))


def _shown(progress: bool | None) -> bool:   # a progress display: as asked, or on a tty
    return sys.stderr.isatty() if progress is None else progress


@click.group(cls=Cli, epilog=examples(), context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(VERSION, "--version", prog_name="mcl2pnml", message="%(prog)s %(version)s")
def main() -> None:
    """Compile AUV missions written in MCL to Petri nets, analyse them, run them.

    Nets are read and written as ISO/IEC 15909-2 PNML (P/T nets).
    """


@main.command(epilog=examples("check"))
@CHECK_OPTIONS
def check(mission: Path, **options) -> int:
    """Parse and check MISSION (MCL): names, arities, patterns, recursion, properties.

    Every error of the file is reported at once, each with file:line:col; then the
    warnings (docs/warnings.md), on standard error.
    """
    settings = checking.CheckOptions(**options)
    checked = checking.check(mission, settings, notes=_notes())
    _print(checked)
    if settings.properties is not None:
        _print(checking.properties(checked, settings))
    return 0


@main.command(epilog=examples("functional"))
@FUNCTIONAL_OPTIONS
def functional(mission: Path, **options) -> int:
    """Print the functional form of MISSION (the paper's Algorithm 2).

    Structures are written sequence, parallel, if-then-else, while and
    monitor; an empty block or a missing else is NULL; functions stay calls.
    """
    _print(checking.functional(mission, checking.FunctionalOptions(**options)))
    return 0


@main.command("compile", epilog=examples("compile"))
@COMPILE_OPTIONS
def compile_(mission: Path, **options) -> int:
    """Compile MISSION (MCL) to one composed Petri net, from mission.B and mission.MTX.

    One shared net per task and per function, entered from every call site;
    time-outs and vehicle bindings travel in the PNML as toolspecific data.
    """
    compiling.compile_mission(mission, compiling.CompileOptions(**options), notes=_notes())
    return 0


@main.command(epilog=examples("run"))
@RUN_OPTIONS
@click.pass_context
def run(ctx: click.Context, mission: Path, as_json: bool, log_path: Path | None,
        net_id: str | None, lenient: bool, max_mission_size: str, **options) -> int:
    """Run MISSION (MCL, or a compiled PNML for the petri engine) against a vehicle.

    Time is virtual: a mission of hours runs in a moment. The live log shows each action
    and event; then the outcome (OK, FAIL, ABORTED, STALLED with what it waits for, or
    TIMELIMIT: cut short by --max-time, INTERRUPTED: by SIGINT, SIGTERM or SIGHUP,
    BREACH: by --stop-on-breach) and the safe stop: every primitive still enabled is
    disabled, however the run ends (docs/faults.md); a second signal meanwhile is
    ignored, a third cuts it short. Each event the vehicle sends that breaks an
    assumption of the timed verdicts (--ack-within, --report-gap; docs/time.md) is said.
    --journal writes the run as it goes; --resume continues it.

    \b
    Exit status, one per outcome: 0 OK, 1 FAIL, 4 ABORTED, 5 STALLED, 6 TIMELIMIT,
    7 BREACH; 2 bad input; interrupted: 128 + the signal (130 SIGINT, 143 SIGTERM,
    129 SIGHUP).
    """
    given = frozenset(k for k in options if ctx.get_parameter_source(k)
                      is click.core.ParameterSource.COMMANDLINE)
    settings = running.RunCommandOptions(running.RunOptions(**options, explicit=given),
                                         as_json, log_path, net_id, lenient, max_mission_size)
    outcome = running.run(mission, settings, live=None if as_json else sys.stdout,
                          notes=_notes())
    with running.printing():
        _print(outcome, as_json, indent=None)
    return outcome.status


@main.command(epilog=examples("validate"))
@VALIDATE_OPTIONS
def validate(file: Path, **options) -> int:
    """Check FILE against mcl2pnml's PNML schema, the official grammar where it is
    given (--grammar, or $MCL2PNML_PNML_GRAMMAR), and the P/T net rules.

    The rules catch what no schema can say (an arc from a place to a place, a
    reference loop). Exit 0 when valid, 2 with every problem when not.
    """
    outcome = validating.validate(file, validating.ValidateOptions(**options))
    for line in outcome.problems():
        click.echo(line, err=True)
    if outcome.status == 0:
        _print(outcome)
    return outcome.status


@main.command(epilog=examples("template"))
@TEMPLATE_OPTIONS
def template(name: str | None, list_: bool, **options) -> int:
    """Write the paper's net NAME, from the paper's initial marking M0.

    A pattern (task) comes fused with its primitive, a structure with
    reduced tasks in its slots: the nets the paper analyses.
    """
    if list_:
        _print(templating.templates())
        return 0
    written = templating.template(name, templating.TemplateOptions(**options), notes=_notes())
    if written.pnml is not None:
        click.echo(written.pnml, nl=False)
    return 0


@main.command(epilog=examples("show"))
@SHOW_OPTIONS
def show(what: str, **options) -> int:
    """Write one self-contained HTML page to play the token game on a net.

    WHAT is a mission (.mcl), a net (.pnml, TINA .net, LoLA .lola) or a
    template (see `template --list`). Click an enabled transition to fire it;
    step back, reset; see the marking and every P-invariant at each step,
    the reduced model (Fig. 3), a recorded run step by step on a clock, the
    mission's tree, the reachability graph. The page needs no server and
    fetches nothing. With --live LOG, the page is served on loopback instead
    and follows a run as `run --log LOG` writes it.
    """
    showing.show(what, showing.ShowOptions(**options), notes=_notes())
    return 0


@main.command(epilog=examples("certify"))
@CERTIFY_OPTIONS
def certify(mission: Path, **options) -> int:
    """Prove MISSION from its parts, without exploring: write its certificate.

    Every task pattern and control structure was proven once against the
    interface contract (docs/ARCHITECTURE.md, mcl2pnml.certify); the
    certificate says, instance by instance, which proof and which rule make
    the mission 1-safe, a proper end always reachable, and reusable, and
    which ends it has, and is re-checked at once against the compiled net. Exit status 1:
    it does not hold; 2: the mission cannot be certified (a loop that can
    never end: the message points at it; or, with --check, a certificate that is
    not one: too large, not JSON, or not of the certificate's shape).
    """
    outcome = certifying.certify(mission, certifying.CertifyOptions(**options), notes=_notes())
    _print(outcome)
    return outcome.status


@main.command(epilog=examples("analyze"))
@ANALYZE_OPTIONS
def analyze(file: Path, as_json: bool, progress: bool | None, **options) -> int:
    """Analyse FILE: a P/T net (PNML, TINA .net, LoLA) or a mission (MCL, compiled first).

    Invariants, siphons, reachable markings, on any P/T net: PNML from TAPAAL,
    PIPE, pm4py..., TINA and LoLA files (by suffix: .pnml or .xml, .net, .lola).
    Exit status 3: a partial answer (the memory budget was reached).
    """
    meter = ProgressMeter(sys.stderr) if _shown(progress) else None
    outcome = analyzing.analyze(file, analyzing.AnalyzeOptions(**options), notes=_notes(),
                                progress=meter)
    _print(outcome, as_json)
    return outcome.status


@main.command(epilog=examples("query"))
@QUERY_OPTIONS
def query(net: Path, formulas: tuple[Path, ...], as_json: bool, **options) -> int:
    """Answer the Model Checking Contest's formula files (FORMULAS.xml: reachability, CTL,
    LTL, upper bounds) and generic examinations on NET, one answer line each in the
    contest's format; exit 3 if one is not answered (docs/interop.md)."""
    settings = querying.QueryOptions(**options)
    if as_json:
        outcome = querying.query(net, formulas, settings)
        _print(outcome, as_json)
        return outcome.status
    answers = querying.query_as_found(net, formulas, settings)
    for a in answers:   # each line as it is settled: a run cut short keeps them
        click.echo(a.line())
    return answers.status


@main.command(epilog=examples("odds"))
@ODDS_OPTIONS
def odds(mission: Path, model: Path, as_json: bool, **options) -> int:
    """The exact odds of MISSION with a vehicle model: how likely it ends OK, FAIL or
    ABORTED, or never, and when (docs/odds.md).

    The mission runs as the engines run it (the supervisor first, time-outs
    exact); every choice of the vehicle is weighed by its probability.
    """
    _print(weighing.odds(mission, model, weighing.OddsOptions(**options), notes=_notes()),
           as_json)
    return 0


@main.command(epilog=examples("campaign"))
@CAMPAIGN_OPTIONS
def campaign(mission: Path, as_json: bool, progress: bool | None, **options) -> int:
    """Fly MISSION many times, on Dask, with a vehicle model or on the kinematic
    simulator, faults injected if asked: each ending's frequency with its interval, the
    end times, how often each property holds, and optionally a sequential test
    (docs/odds.md)."""
    settings = campaigning.CampaignOptions(**options)
    with RunsBar(settings.runs, _shown(progress), sys.stderr) as bar:
        flown = campaigning.campaign(mission, settings, notes=bar.notes, progress=bar)
    _print(flown, as_json)
    return 0


@main.command(epilog=examples("lsp"))
@LSP_OPTIONS
def lsp(stdio: bool, **options) -> int:
    """Serve MCL to an editor: a language server (LSP) on standard input and output.

    Diagnostics as you type (every error, the warnings with their codes), completion,
    hover (a task's pattern, time-out and results; a primitive on the simulated
    vehicle), go to definition, document symbols and quick fixes. docs/editors.md sets
    it up in VS Code, Neovim, Helix and Emacs.
    """
    serving.serve(serving.LspOptions(**options))   # stdio: the one transport
    return 0
