"""Every default is written once: in a command's options dataclass, or as a named constant
(:mod:`mcl2pnml.core.bounds` for the bounds several commands share), never as the same
literal in two places that must agree.

The package's source is read as syntax trees: the defaults of every function's parameters
and of every dataclass field, and the ``default=`` of every option of the command line.
"""
from __future__ import annotations

import ast
from collections import defaultdict
from functools import lru_cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: the package as installed: mcl2pnml, and analysis/ as mcl2pnml.analysis
SOURCES = sorted([*(ROOT / "mcl2pnml").rglob("*.py"), *(ROOT / "analysis").rglob("*.py")])
#: Literals too plain to say one thing (nothing, zero, one, off, empty), which two
#: parameters may share without being one default.
PLAIN = {None, 0, 1, 0.0, 1.0, True, False, "", -1}
#: Numeric defaults of 1,000 and more written where they are used, each the only one of its
#: kind (a parameter of one function that no command sets: an internal limit of the
#: analysis, not a bound a user sets).
LOCAL = {
    ("analysis/markov.py", "horizon"),
    ("analysis/contest/answers.py", "max_states", 2 ** 31),
    ("analysis/checking/contract.py", "max_states"),
    ("analysis/statespace/packedmarkings.py", "sample"),
}
#: Literals two modules share on purpose, each a name the readers of a format give to text
#: read without a file, or a value the layers below use among themselves: not a setting
#: of a command.
SHARED = {("filename", "'<input>'"), ("filename", "'<mcl>'"), ("filename", "'<mapping>'"),
          ("goal", "'C'"), ("bits", "12")}


def _literal(node: ast.AST | None):
    """The value of a literal default (a constant, or arithmetic on constants), else a
    marker that it names something (a constant, a field of an options class)."""
    try:
        return ast.literal_eval(node) if node is not None else None
    except ValueError:
        if isinstance(node, ast.BinOp):
            try:
                return eval(compile(ast.Expression(node), "<default>", "eval"), {})  # noqa: S307
            except Exception:   # noqa: BLE001 (names something: not a literal)
                pass
        return NAMED


NAMED = object()


@lru_cache(maxsize=1)
def defaults() -> tuple[tuple[str, int, str, object], ...]:
    """(file, line, name, literal) of every parameter default and dataclass field default
    of the package whose value is a literal."""
    # read once for the two tests that look at every default: each parsed the whole
    # package again (a second of CPU each)
    found = []
    for path in SOURCES:
        where = str(path.relative_to(ROOT))
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            pairs = []
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                a = node.args
                positional = a.posonlyargs + a.args
                pairs += zip(positional[len(positional) - len(a.defaults):], a.defaults)
                pairs += [(k, d) for k, d in zip(a.kwonlyargs, a.kw_defaults) if d is not None]
                pairs = [(arg.arg, d) for arg, d in pairs]
            elif isinstance(node, ast.ClassDef):
                pairs = [(s.target.id, s.value) for s in node.body
                         if isinstance(s, ast.AnnAssign) and isinstance(s.target, ast.Name)
                         and s.value is not None]
            for name, value in pairs:
                literal = _literal(value)
                if literal is not NAMED and not isinstance(literal, (list, tuple, dict, set)):
                    found.append((where, value.lineno, name, literal))
    return tuple(found)


def test_no_default_is_written_twice():
    """One name, one literal, in two modules: two defaults that must agree and may not."""
    places = defaultdict(set)
    for where, line, name, literal in defaults():
        if literal not in PLAIN or type(literal) is float and literal not in (0.0, 1.0):
            places[name, repr(literal)].add(f"{where}:{line}")
    twice = {key: sorted(at) for key, at in places.items()
             if len({a.split(":")[0] for a in at}) > 1 and key not in SHARED}
    assert not twice, f"the same default written in several modules: {twice}"


def test_large_numeric_defaults_are_named():
    """A bound (a number of states, a size, a time) is a named constant, so that the
    option that sets it and every function that defaults to it say one number."""
    written = [(where, line, name, literal) for where, line, name, literal in defaults()
               if isinstance(literal, (int, float)) and not isinstance(literal, bool)
               and abs(literal) >= 1000 and (where, name) not in LOCAL
               and (where, name, literal) not in LOCAL]
    assert not written, f"numeric defaults written as literals: {written}"


def test_the_options_take_their_defaults_from_the_commands():
    """Every ``default=`` of the command line names where the default lives (an options
    dataclass's field, a shared bound); none is a literal of its own."""
    tree = ast.parse((ROOT / "mcl2pnml" / "cli_options.py").read_text(encoding="utf-8"))
    literal = [(node.lineno, ast.unparse(kw.value)) for node in ast.walk(tree)
               if isinstance(node, ast.Call) for kw in node.keywords
               if kw.arg == "default" and isinstance(kw.value, ast.Constant)
               and kw.value.value is not None]
    assert not literal, f"option defaults written in cli_options.py: {literal}"


@pytest.mark.parametrize("command", ["analyze", "query", "odds", "campaign", "run", "show",
                                     "compile", "certify", "check", "lsp"])
def test_each_option_default_is_its_options_dataclass_default(command: str):
    """The default ``--help`` shows is the one the command takes when the option is not
    given: the options dataclass's field of the same name."""
    import dataclasses

    from mcl2pnml.cli import main
    from mcl2pnml.commands import (analyze, certify, check, compile, fly, lsp, page, query,
                                   run, weigh)
    options = {"analyze": analyze.AnalyzeOptions, "query": query.QueryOptions,
               "odds": weigh.OddsOptions, "campaign": fly.CampaignOptions,
               "run": run.RunOptions, "show": page.ShowOptions,
               "compile": compile.CompileOptions, "certify": certify.CertifyOptions,
               "check": check.CheckOptions, "lsp": lsp.LspOptions}[command]
    fields = {f.name: f.default for f in dataclasses.fields(options)}
    compared = 0
    for param in main.commands[command].params:
        if param.name in fields and isinstance(param.default, (int, float, str)) \
                and not isinstance(param.default, bool):
            default = fields[param.name]
            assert param.default == (str(default) if isinstance(param.default, str)
                                     and not isinstance(default, str) else default), param.name
            compared += 1
    assert compared, f"{command}: no option compared with its options dataclass"
