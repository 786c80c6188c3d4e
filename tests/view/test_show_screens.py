"""The paper's mission's page on a lecture's screens, at *Fit*, in headless Chromium: a
1024 x 768 projector and a 1920 x 1080 screen (the pictures of docs/show.md,
``tests/support/screens.py`` shoots them).

On both, the header is one row, the side panels fold away where the screen is narrow,
the drawing gets most of the width, and in the view of every call of the mission no text
is smaller than :data:`LEAST` and no two of the drawing's texts overlap. Every text is
measured as Chromium renders it (:data:`screens.SMALLEST_TEXT`), not as dot meant it.
"""
from __future__ import annotations

import pytest

from helpers import ROOT
from screens import HEADER, OVERLAPS, SCREENS, SMALLEST_TEXT, chromium, settled
from shown import shown

#: The least height of any text of the page, in CSS pixels, on each screen. 12 px is the
#: panels' smallest font; on the projector the widest call's view (a structure with three
#: calls beside its own net) is fitted to 1024 pixels, and its text is at least 10 px:
#: a 1920 x 1080 slide's 14 px (tests/view/test_drawings.py) is 7.5 px there.
LEAST = {"1024x768": 10.0, "1920x1080": 12.0}
#: The drawing has at least this share of the page's width.
ROOM = 0.65
#: A screen narrower than this starts with its side panels folded (show_page.html).
NARROW = 1500


@pytest.fixture(scope="module")
def sauce(tmp_path_factory):
    """The paper's mission (examples/sauce.mcl) as a page."""
    return shown(tmp_path_factory, "sauce.html", ROOT / "examples" / "sauce.mcl")


@pytest.fixture
def screen(request):
    """Opens a page at a screen's size in the tests' Chromium (the shared tab); skipped,
    saying why, where Chromium or Playwright is missing."""
    if chromium() is None:
        pytest.skip("Chromium is not installed (apt-get install chromium; make setup does): "
                    "the page's text is measured as it renders")
    pytest.importorskip("playwright", reason="Playwright drives Chromium: pip install -e "
                                             "'.[test]' (make setup does)")
    tab = request.getfixturevalue("tab")
    errors: list[str] = []

    def open_(path, size):
        page = tab.page({"width": size[0], "height": size[1]})
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(path.resolve().as_uri())
        return page

    yield open_
    tab.leave()
    assert not errors, errors


@pytest.mark.parametrize("name", list(SCREENS))
def test_every_call_of_the_papers_mission_is_readable_at_fit(sauce, screen, name):
    width, height = SCREENS[name]
    page = screen(sauce, (width, height))
    assert page.evaluate(HEADER) == {"rows": 1, "cut": False}
    folded = page.locator(".panel.folded").count()
    assert folded == (2 if width < NARROW else 0)
    assert page.locator("#net").bounding_box()["width"] >= ROOM * width
    settled(page)
    views = page.evaluate("() => Object.keys(V.calls.views)")
    assert len(views) == 21
    for call in views:
        page.evaluate("(name) => openCall(callPath(name))", call)
        least = page.evaluate(SMALLEST_TEXT)
        assert least["px"] >= LEAST[name], (call, least)
        assert page.evaluate(OVERLAPS) == [], call
    # the whole net is no reading matter (a poster), but its texts keep apart too
    page.select_option("#view-kind", "whole")
    assert page.evaluate(OVERLAPS) == []
