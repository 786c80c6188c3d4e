"""The command line parses and prints: it imports the commands, click and its own options,
nothing of the layers below, and each of its functions is short (the work is the
commands'). The facade and the commands keep the project's code shape."""
from __future__ import annotations

import ast
from pathlib import Path

CLI = Path(__file__).resolve().parents[2] / "mcl2pnml" / "cli.py"
#: What the command line may import besides the standard library's few.
ALLOWED = ("click", "mcl2pnml.cli_options", "mcl2pnml.commands")
STANDARD = {"__future__", "json", "sys", "pathlib"}


def test_the_cli_imports_only_the_commands_and_click():
    tree = ast.parse(CLI.read_text(encoding="utf-8"))
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            imported.add(node.module)
    other = sorted(m for m in imported - STANDARD
                   if not any(m == a or m.startswith(a + ".") for a in ALLOWED))
    assert not other, f"the CLI imports past the commands: {other}"


def test_no_function_of_the_cli_is_long():
    """Forty lines at most: a command's help, its call and its printing."""
    tree = ast.parse(CLI.read_text(encoding="utf-8"))
    long = [(n.name, n.end_lineno - n.lineno + 1) for n in ast.walk(tree)
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
            and n.end_lineno - n.lineno + 1 > 40]
    assert not long, long


#: The facade, the commands and the modules under them that the project's code-shape test
#: (tests/project/test_code_shape.py) does not read: held to the same two rules here.
FACADE = [CLI.parent / name for name in ("pipeline.py", "cli.py", "cli_options.py",
                                         "__init__.py", "campaign.py", "odds.py",
                                         "counterexample.py", "timed_verdicts.py")]
FACADE += sorted((CLI.parent / "commands").glob("*.py"))


def test_the_facade_and_the_commands_keep_the_code_shape():
    """Over 80 lines, a function says why it is long; an import inside a function says what
    it costs: tests/project/test_code_shape.py's rules, on these modules."""
    import test_code_shape as shape

    modules = tuple((path, tuple(text.splitlines()), ast.parse(text))
                    for path in FACADE for text in [path.read_text(encoding="utf-8")])
    shape.test_a_long_function_says_why_it_is_long(modules)
    shape.test_an_import_inside_a_function_says_why_it_waits(modules)
