"""The layer rules of docs/ARCHITECTURE.md, held by import-linter and by the import graph.

The contracts live in pyproject.toml (``[tool.importlinter]``): the core
imports nothing of ours; the language, io and analysis import only the core;
the runtime the core (and the reference engine the language); the view the
core, io and analysis; only the facade and the CLI import everything; and no
import circle anywhere. A contract that no longer fails when it is broken
proves nothing, so one test breaks it on purpose, in a copy of the code.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import networkx as nx
import pytest

ROOT = Path(__file__).resolve().parents[2]
LINT = Path(sys.executable).with_name("lint-imports")


def installed_tree(where: Path) -> Path:
    """The package as installed: ``analysis/`` sits at the top of the repository but installs
    as ``mcl2pnml.analysis``, and the import tools read packages from the file system."""
    ignore = shutil.ignore_patterns("__pycache__", "*.so")
    shutil.copytree(ROOT / "mcl2pnml", where / "mcl2pnml", ignore=ignore)
    shutil.copytree(ROOT / "analysis", where / "mcl2pnml" / "analysis", ignore=ignore)
    shutil.copy(ROOT / "pyproject.toml", where)
    return where


@pytest.fixture(scope="module")
def tree(tmp_path_factory) -> Path:
    return installed_tree(tmp_path_factory.mktemp("installed"))


def lint(where: Path) -> subprocess.CompletedProcess:
    if not LINT.exists():
        pytest.fail(f"import-linter is not installed ({LINT} is missing): run `make setup`")
    env = {**os.environ, "PYTHONPATH": str(where)}
    return subprocess.run([str(LINT), "--no-cache", "--no-logo"], cwd=where, env=env,
                          capture_output=True, text=True, timeout=120)


def test_the_layer_contracts_hold(tree: Path):
    out = lint(tree)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "Contracts: 5 kept, 0 broken." in out.stdout, out.stdout


@pytest.mark.parametrize("importer, imported, contract", [
    ("mcl2pnml/core/net.py", "mcl2pnml.view.layout", "The CLI over the facade"),
    ("mcl2pnml/runtime/engine.py", "mcl2pnml.io.pnml.reader", "The runtime reads no file"),
    ("mcl2pnml/analysis/structure/invariants.py", "mcl2pnml.language.compiler",
     "The CLI over the facade"),
    ("mcl2pnml/analysis/structure/siphons.py", "mcl2pnml.analysis.statespace.explore",
     "Inside the analysis"),
    ("mcl2pnml/core/errors.py", "mcl2pnml.core.net", "No import circle"),
])
def test_a_forbidden_import_breaks_a_contract(tmp_path: Path, importer: str, imported: str,
                                              contract: str):
    installed_tree(tmp_path)
    with (tmp_path / importer).open("a") as f:
        f.write(f"\nimport {imported}  # forbidden on purpose\n")
    out = lint(tmp_path)
    assert out.returncode == 1, out.stdout + out.stderr
    broken = out.stdout.split("Broken contracts", 1)[-1]
    assert contract in broken, out.stdout
    assert imported.rpartition(".")[2] in broken, out.stdout   # the offending import is named


GRAPH = """
import json, grimp
graph = grimp.build_graph("mcl2pnml", cache_dir=None)
print(json.dumps({m: sorted(graph.find_modules_directly_imported_by(m)) for m in graph.modules}))
"""


@pytest.fixture(scope="module")
def import_graph(tree: Path) -> nx.DiGraph:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, "-c", GRAPH], cwd=tree, env=env, capture_output=True,
                         text=True, timeout=120, check=True)
    g = nx.DiGraph()
    for module, imported in json.loads(out.stdout).items():
        g.add_node(module)
        g.add_edges_from((module, m) for m in imported)
    return g


def test_no_module_imports_one_that_imports_it_back(import_graph: nx.DiGraph):
    """Stricter than the sibling contract: any circle, between any two modules of ours."""
    g = import_graph
    cycles = list(nx.simple_cycles(g))
    assert not cycles, f"import circles: {cycles[:5]}"


def test_the_core_imports_nothing_of_ours_but_the_core(import_graph: nx.DiGraph):
    g = import_graph
    for module in g:
        if module.startswith("mcl2pnml.core"):
            outside = [m for m in g.successors(module) if not m.startswith("mcl2pnml.core")]
            assert not outside, f"{module} imports {outside}"


def test_serialising_never_lays_out(tmp_path: Path):
    """``--layout none``: no layout is computed and graphviz is never imported."""
    out = subprocess.run([sys.executable, "-X", "importtime", "-m", "mcl2pnml", "compile",
                          str(ROOT / "examples" / "sauce.mcl"), "-o", str(tmp_path / "s.pnml"),
                          "--layout", "none"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    imported = [line.rsplit("|", 1)[-1].strip() for line in out.stderr.splitlines()
                if line.startswith("import time:")]
    assert "mcl2pnml.io.pnml.writer" in imported
    assert not [m for m in imported if m.split(".")[0] == "graphviz"
                or m in ("mcl2pnml.io.dot", "mcl2pnml.view.drawing")]
    assert "<graphics>" not in (tmp_path / "s.pnml").read_text()


def layer_modules() -> list[str]:
    """The modules the layers contract names, each layer's alternatives apart."""
    import tomllib
    contracts = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    layers = next(c for c in contracts["contracts"] if c["type"] == "layers")["layers"]
    return [name.strip() for layer in layers for name in layer.split("|")]


def test_every_module_is_in_a_layer(import_graph: nx.DiGraph):
    """A module in no layer is held by no layer rule: any import into or out of it passes."""
    named = layer_modules()
    ours = [m for m in import_graph if m.startswith("mcl2pnml.") and m != "mcl2pnml.__main__"]
    outside = [m for m in ours if not any(m == n or m.startswith(n + ".") for n in named)]
    assert not outside, f"modules in no layer of pyproject.toml's layers contract: {outside}"
