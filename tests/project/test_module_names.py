"""No two modules of the package share a name, so that a name says which module it is
(``mcl2pnml.campaign`` the runs on Dask, ``mcl2pnml.commands.fly`` the command)."""
from __future__ import annotations

from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_no_two_modules_share_a_name():
    where = defaultdict(list)
    for folder in (ROOT / "mcl2pnml", ROOT / "analysis"):
        for path in folder.rglob("*.py"):
            if path.name not in ("__init__.py", "__main__.py"):
                where[path.stem].append(str(path.relative_to(ROOT)))
    shared = {name: paths for name, paths in where.items() if len(paths) > 1}
    assert not shared, shared
