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

from . import __version__
from .errors import Mcl2PnmlError

EXAMPLES = """\b
Examples:
  mcl2pnml validate mission.pnml
  mcl2pnml validate mission.pnml --grammar ~/pnml/grammar
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
    from .pnml.grammar import validate as run
    from .pnml.reader import load_pnml

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


if __name__ == "__main__":  # pragma: no cover
    main()
