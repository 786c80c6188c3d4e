"""`pip install .` gives a working command from any directory, templates included."""
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

from helpers import ROOT


def test_wheel_installs_the_command_and_the_templates(tmp_path):
    wheel_dir, target, source = tmp_path / "wheel", tmp_path / "site", tmp_path / "src"
    # build from a copy: setuptools' build/ directory may hold stale files
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(
        ".venv", ".git", "build", "out", "*.egg-info", "__pycache__", ".hypothesis"))
    # uv where make setup installed it: it builds with the same backend (setuptools, from
    # pyproject.toml) in an environment it keeps, where pip downloads setuptools each time
    uv = Path(sys.executable).parent / "uv"
    build = [str(uv), "build", "--quiet", "--wheel", "--out-dir", str(wheel_dir), str(source)] \
        if uv.exists() else [sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps",
                             "-w", str(wheel_dir), str(source)]
    subprocess.run(build, check=True, timeout=300)
    wheel = next(wheel_dir.glob("mcl2pnml-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    templates = sorted(n for n in names if n.startswith("mcl2pnml/templates/"))
    shipped = sorted(f"mcl2pnml/templates/{p.name}" for p in (ROOT / "templates").iterdir()
                     if p.suffix in (".py", ".pnt") or p.name == "proofs.json")
    assert templates == shipped
    assert any(n.startswith("mcl2pnml/analysis/statespace/") for n in names)
    # no top-level package of ours but mcl2pnml: a user's analysis.py shadows no module of ours
    assert {n.split("/")[0] for n in names if not n.startswith("mcl2pnml-")} == {"mcl2pnml"}, \
        sorted({n.split("/")[0] for n in names})
    assert "mcl2pnml/certify/recheck.py" in names
    # the commands the CLI imports, and the language server `lsp` starts
    assert {"mcl2pnml/commands/check.py", "mcl2pnml/langserver/server.py"} <= set(names)
    assert "mcl2pnml/io/pnml/ptnet.rng" in names   # our PNML schema: validate needs it
    assert any(n.endswith("entry_points.txt") for n in names)
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--target", str(target), str(wheel)], check=True, timeout=300)
    # run from an unrelated directory, importing only the installed copy
    env = {**os.environ, "PYTHONPATH": str(target)}
    out = subprocess.run([sys.executable, "-P", "-c",
                          "import mcl2pnml, mcl2pnml.templates as t; print(mcl2pnml.__file__); "
                          "print(t.__file__)"],
                         capture_output=True, text=True, cwd=tmp_path, env=env, timeout=60)
    assert out.returncode == 0, out.stderr
    assert all(line.startswith(str(target)) for line in out.stdout.split())
    out = subprocess.run([str(target / "bin" / "mcl2pnml"), "--version"], capture_output=True,
                         text=True, cwd=tmp_path, env=env, timeout=60)
    assert out.returncode == 0 and out.stdout.startswith("mcl2pnml "), out.stderr
    # the installed copy validates with its own schema, the official grammar set aside
    pnml = ROOT / "tests" / "data" / "pnml" / "schema" / "valid" / "labels_in_any_order.pnml"
    out = subprocess.run([str(target / "bin" / "mcl2pnml"), "validate", str(pnml)],
                         capture_output=True, text=True, cwd=tmp_path, timeout=60,
                         env={**env, "MCL2PNML_PNML_GRAMMAR": "none"})
    assert out.returncode == 0 and "(mcl2pnml's ISO/IEC 15909-2 schema)" in out.stdout, out.stderr
    # the installed copy certifies from its own stored proofs
    out = subprocess.run([str(target / "bin" / "mcl2pnml"), "certify",
                          str(ROOT / "examples" / "sauce.mcl"), "-o", str(tmp_path / "s.json")],
                         capture_output=True, text=True, cwd=tmp_path, timeout=60, env=env)
    assert out.returncode == 0 and "certified from its parts" in out.stdout, out.stderr
