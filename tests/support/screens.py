"""The token-game page of the paper's mission on the screens a lecture has: a 1024 x 768
projector and a 1920 x 1080 screen, each at *Fit*.

Run as a script (``.venv/bin/python tests/support/screens.py``), it writes the pictures
of docs/show.md, ``docs/show_sauce_1024x768.png`` and ``docs/show_sauce_1920x1080.png``,
with headless Chromium as the browser tests drive it (``tests/conftest.py``: Debian's
``/usr/bin/chromium`` through Playwright, nothing downloaded). The tests
(``tests/view/test_show_screens.py``) measure the same pages with :data:`SMALLEST_TEXT`
and :data:`OVERLAPS`.
"""
from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: The screens, by name: (width, height) in CSS pixels.
SCREENS = {"1024x768": (1024, 768), "1920x1080": (1920, 1080)}
#: Chromium as the tests run it: headless, offline, as root in a container.
CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update",
                  "--disable-sync"]

#: The smallest text the page shows, in CSS pixels, and what it says: every text that is
#: rendered (an element not hidden, of some size), the drawing's at its scale (its font
#: size times the drawing's transform to the screen), the rest at its computed font size.
SMALLEST_TEXT = """() => {
  let least = Infinity, said = null;
  const shown = (e) => { const r = e.getBoundingClientRect(); return r.width > 0 && r.height > 0; };
  for (const t of document.querySelectorAll("svg:not([hidden]) text")) {
    if (!t.textContent.trim() || !shown(t)) continue;
    const m = t.getScreenCTM();
    const px = parseFloat(getComputedStyle(t).fontSize) * Math.hypot(m.a, m.b);
    if (px < least) { least = px; said = t.textContent; }
  }
  const texts = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
  for (let n = texts.nextNode(); n; n = texts.nextNode()) {
    const e = n.parentElement;
    if (!n.textContent.trim() || e.closest("svg, script, style") || !shown(e)) continue;
    const px = parseFloat(getComputedStyle(e).fontSize);
    if (px < least) { least = px; said = n.textContent.trim(); }
  }
  return {px: least, text: said};
}"""

#: Every two texts of the drawing whose boxes on the screen overlap (by more than half a
#: pixel), each said as its text and the node or box it is in.
OVERLAPS = """() => {
  const boxes = [];
  for (const t of document.querySelectorAll("#net text")) {
    const r = t.getBoundingClientRect();
    if (!t.textContent.trim() || !(r.width > 0 && r.height > 0)) continue;
    const owner = t.closest("[data-id], [data-name]");
    boxes.push([r, t.textContent + " (" + (owner ? owner.dataset.id || owner.dataset.name : "")
                + ")"]);
  }
  const found = [];
  for (let i = 0; i < boxes.length; i++) {
    for (let j = i + 1; j < boxes.length; j++) {
      const [a, x] = boxes[i], [b, y] = boxes[j];
      if (a.left < b.right - 0.5 && b.left < a.right - 0.5 &&
          a.top < b.bottom - 0.5 && b.top < a.bottom - 0.5) found.push(x + " on " + y);
    }
  }
  return found;
}"""

#: How many rows the header's controls take (their distinct tops), and whether it cuts
#: any of them (wider than the page).
HEADER = """() => {
  const h = document.querySelector("header");
  const tops = new Set([...h.children].filter((e) => e.getBoundingClientRect().width > 0)
    .map((e) => Math.round(e.getBoundingClientRect().top + e.getBoundingClientRect().height / 2)));
  return {rows: Math.max(...tops) - Math.min(...tops) > 8 ? tops.size : 1,
          cut: h.scrollWidth > h.clientWidth + 1};
}"""


def chromium() -> str | None:
    """Debian's Chromium, where it is installed."""
    return shutil.which("chromium") or shutil.which("chromium-browser")


def settled(page) -> None:
    """The page as a lecture shows it: the supervisor's first steps taken (the calls that
    run lit up), then back to the mission's own net (its breadcrumb's first name), at
    *Fit*."""
    # (Settle's button is in a panel that a narrow screen folds; openCall fits the view)
    page.evaluate("() => { settle(); openCall([V.calls.root]); }")


def shoot(browser, html: Path, folder: Path) -> list[Path]:
    """The page ``html`` at each screen of :data:`SCREENS`, as :func:`settled` leaves it,
    as PNG files in ``folder``; the files written."""
    written = []
    for name, (width, height) in SCREENS.items():
        page = browser.new_page(viewport={"width": width, "height": height})
        try:
            page.goto(html.resolve().as_uri())
            settled(page)
            path = folder / f"show_{html.stem}_{name}.png"
            page.screenshot(path=str(path))
            written.append(path)
        finally:
            page.close()
    return written


def main() -> int:
    """Write docs/show_sauce_*.png from the page ``mcl2pnml show examples/sauce.mcl`` writes."""
    from playwright.sync_api import sync_playwright   # the tests' extra: only to shoot
    executable = chromium()
    if executable is None:
        print("Chromium is needed: apt-get install chromium (make setup does)", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as folder:
        html = Path(folder) / "sauce.html"
        subprocess.run([sys.executable, "-m", "mcl2pnml", "show",
                        str(ROOT / "examples" / "sauce.mcl"), "-o", str(html)], check=True)
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=executable, headless=True,
                                        args=CHROMIUM_FLAGS)
            for path in shoot(browser, html, ROOT / "docs"):
                print(f"wrote {path.relative_to(ROOT)}")
            browser.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
