"""The drawings' layouts shared by this folder's test processes (see drawcheck.SHARED)."""
from __future__ import annotations

import pytest

import drawcheck
from sessioncache import folder as shared_folder


@pytest.fixture(scope="session", autouse=True)
def shared_layouts(tmp_path_factory):
    folder = shared_folder(tmp_path_factory) / "dot"
    folder.mkdir(exist_ok=True)
    drawcheck.SHARED = folder
    yield folder
    drawcheck.SHARED = None
