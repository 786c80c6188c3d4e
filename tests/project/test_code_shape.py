"""The analysis (``analysis/``, installed as ``mcl2pnml.analysis``), the language, the
certificates, io, the view, the core, the runtime and the language server keep the shape
the project holds its code to: no function called a bare ``check`` (each says what it
checks), none over 80 lines without a comment saying why it is long, every import inside a
function headed by a comment saying what it costs and why it waits, and no module named as
another module of the package."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = (ROOT / "analysis", ROOT / "mcl2pnml" / "language", ROOT / "mcl2pnml" / "certify",
            *(ROOT / "mcl2pnml" / name for name in ("io", "view", "core", "runtime",
                                                    "langserver")))
LONGEST = 80


@pytest.fixture(scope="module")
def modules() -> tuple[tuple[Path, tuple[str, ...], ast.Module], ...]:
    """Every module, read and parsed once for the tests that read them all (each parsed the
    whole code base again); dropped after them: the trees held for the rest of a run
    made every later garbage collection of the test process walk them."""
    out = []
    for package in PACKAGES:
        for path in sorted(package.rglob("*.py")):
            text = path.read_text(encoding="utf-8")
            out.append((path, tuple(text.splitlines()), ast.parse(text)))
    return tuple(out)


def _functions(tree: ast.AST):
    return (n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)))


def _where(path: Path, line: int) -> str:
    return f"{path.relative_to(ROOT)}:{line}"


def test_no_function_is_called_a_bare_check(modules):
    """A method may be ``check`` (its class says what); a function names what it checks."""
    bare = [_where(path, n.lineno) for path, _, tree in modules for n in tree.body
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))
            and n.name in ("check", "check_all")]
    assert not bare, bare


def test_a_long_function_says_why_it_is_long(modules):
    """Over 80 lines, a comment at its head (above it, or among its first lines) says why."""
    unexplained = []
    for path, lines, tree in modules:
        for f in _functions(tree):
            if f.end_lineno - f.lineno + 1 <= LONGEST:
                continue
            head = lines[max(f.lineno - 3, 0):f.body[0].lineno + 2]
            if not any("#" in line and "long" in line for line in head):
                unexplained.append(f"{_where(path, f.lineno)} {f.name}")
    assert not unexplained, unexplained


def test_an_import_inside_a_function_says_why_it_waits(modules):
    """Imports are at the top; one in a function carries a comment, or heads a block of
    imports under one, saying what it costs (``python -X importtime``)."""
    silent = []
    for path, lines, tree in modules:
        for f in _functions(tree):
            for n in ast.walk(f):
                if not isinstance(n, (ast.Import, ast.ImportFrom)) or "#" in lines[n.lineno - 1]:
                    continue
                above = n.lineno - 2
                while above >= 0 and lines[above].strip().startswith(("import ", "from ")):
                    above -= 1
                if above < 0 or not lines[above].strip().startswith("#"):
                    silent.append(f"{_where(path, n.lineno)} {lines[n.lineno - 1].strip()}")
    assert not silent, silent


def test_no_module_is_named_as_another_of_the_package():
    """A module's name alone says which it is: none of these packages' shares its name with
    another module of the installed package (``__init__`` and ``__main__`` aside)."""
    ours = {path.name for package in PACKAGES for path in package.rglob("*.py")}
    seen: dict[str, list[str]] = {}
    for package in (ROOT / "mcl2pnml", ROOT / "analysis"):
        for path in package.rglob("*.py"):
            if path.name not in ("__init__.py", "__main__.py") and "__pycache__" not in path.parts:
                seen.setdefault(path.name, []).append(str(path.relative_to(ROOT)))
    twice = {name: paths for name, paths in seen.items() if len(paths) > 1 and name in ours}
    assert not twice, twice
