"""Does the quick suite reach every line and branch of ours that the variants it leaves to
``make test-slow`` reach (``tests/support/sampling.py``'s ``variants``, marked ``variant``)?

    python tests/support/coverage_check.py        # two runs under coverage: about half an
                                                  # hour on two cores
    python tests/support/coverage_check.py tests/peers/test_crosscheck.py   # those tests only

Runs the quick suite (``make test``'s selection), then the quick suite with the variants,
each under coverage.py: branches measured, and every Python process the tests start (the
commands run in fresh interpreters, ``MCL2PNML_TEST_FRESH=1``, so that each is measured;
tests/commands/test_forkcli.py's comparisons fail so, as they say). Prints the arcs (file,
line -> line) of ``mcl2pnml`` and ``analysis`` that the second run reaches and the first does
not, and exits 1 if there is one: the variant that reaches it goes back to the quick suite.
An arc that only a moment reaches (a signal's, a link's time-out) can differ between any two
runs: one the quick suite's own tests reach in another run is not a variant's.
Needs coverage 7.10 or later and pytest-cov (``pip install coverage pytest-cov``); says so
and exits 2 where they are missing.
"""
from __future__ import annotations

import os
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: What is measured: the package and the analysis it installs as ``mcl2pnml.analysis``.
SOURCES = (ROOT / "mcl2pnml", ROOT / "analysis")
QUICK = "not slow"
WITH_VARIANTS = "not slow or variant"


def _arcs(selection: str, folder: Path, args: list[str]) -> set[tuple[str, int, int]]:
    """The arcs of ours that the tests ``-m selection`` (of ``args``, pytest's) reach."""
    from coverage import CoverageData

    folder.mkdir()
    rc = folder / "coveragerc"
    rc.write_text("[run]\nsource =\n" + "".join(f"    {s}\n" for s in SOURCES) +
                  "branch = True\nparallel = True\npatch = subprocess\n"
                  f"data_file = {folder / '.coverage'}\n")
    env = {**os.environ, "COVERAGE_RCFILE": str(rc), "MCL2PNML_TEST_FRESH": "1"}
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    command = [sys.executable, "-m", "pytest", "-n", "4", "--dist", "worksteal", "-q",
               "-p", "no:cacheprovider", "--cov", f"--cov-config={rc}", "--cov-report=",
               "-m", selection, *args]
    print(f"$ {shlex.join(command)}", flush=True)
    done = subprocess.run(command, cwd=ROOT, env=env, stdout=subprocess.PIPE, text=True)
    print(done.stdout.strip().splitlines()[-1] if done.stdout.strip() else "(no output)")
    data = CoverageData(basename=str(folder / ".coverage"))
    data.read()
    return {(str(Path(f).relative_to(ROOT)), a, b)
            for f in data.measured_files() for a, b in (data.arcs(f) or ())}


def main(args: list[str]) -> int:
    try:
        import coverage
        import pytest_cov  # noqa: F401  (the runs' --cov)
    except ImportError as e:
        print(f"coverage_check: {e.name} is missing: pip install coverage pytest-cov",
              file=sys.stderr)
        return 2
    if tuple(int(x) for x in coverage.__version__.split(".")[:2]) < (7, 10):
        print(f"coverage_check: coverage {coverage.__version__} cannot measure the "
              "processes the tests start: pip install 'coverage>=7.10'", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        quick = _arcs(QUICK, Path(tmp) / "quick", args)
        whole = _arcs(WITH_VARIANTS, Path(tmp) / "with-variants", args)
    missing = sorted(whole - quick)
    print(f"arcs reached: {len(quick)} by the quick suite, {len(whole)} with the variants")
    for file, a, b in missing:
        print(f"  only with the variants: {file}: {a} -> {b}")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
