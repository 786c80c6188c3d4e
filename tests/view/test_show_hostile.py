"""`mcl2pnml show` on hostile input: the page runs none of it, fetches nothing, and draws.

A net's file name, node ids and names, doc lines and a run log are written
by whoever made the files; they reach the page as text. Each payload here
would run script, navigate, fetch, or blank the page if it were read as
markup: ``<img onerror>``, ``</script><script>``, ``<!--<script>`` (which puts
the HTML parser in a state that swallows the page's own script), U+2028 and
U+2029, a meta refresh, and the names of the template's slots. The page is
opened in headless Chromium (as in test_show.py) with witnesses: a flag
and console calls the payloads would leave, dialogs, every request and
navigation, and a socket on this machine that the payloads aim at and that
must hear nothing. A page built without the defences trips them all
(:func:`test_the_witnesses_see_an_attack`).

The page builder's own guarantees (escaped JSON, one substitution pass, a
policy whose hash is the script's) and the refusal of NaN and infinities in
a run log are checked without a browser.
"""
from __future__ import annotations

import base64
import hashlib
import json
import math
import re
import socket
import threading
from pathlib import Path

import pytest

from helpers import run_cli as run
from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import NetBuilder
from mcl2pnml.io.pnml.reader import read_pnml
from mcl2pnml.io.pnml.writer import write_pnml
from mcl2pnml.view import show

#: What a payload does if it ever runs: leaves a flag, speaks, asks, and calls home.
SCRIPT = ("window.__pwned=1;console.log('pwned');alert('pwned');"
          "fetch('http://127.0.0.1:{port}/fetch')")
#: The template's slots, as names a file or a node may have.
SLOT_NAMES = [f"__{slot}__" for slot in show.SLOTS]


def payloads(port: int) -> list[str]:
    """Every hostile string, aimed at a listener on ``port``."""
    js = SCRIPT.format(port=port)
    return [f'<img src=x onerror="{js}">',
            f"</script><script>{js}</script>",
            "<!--<script>",
            f"<!--<script></script><script>{js}</script>",
            "line\u2028separator\u2029paragraph",
            f'<meta http-equiv="refresh" content="0;url=http://127.0.0.1:{port}/refresh">',
            f'<a href="http://127.0.0.1:{port}/link" id="data">x</a>',
            f'<svg onload="{js}"/>',
            *SLOT_NAMES]


def hostile_net(port: int, name: str = "net"):
    """A chain p0 -> t0 -> p1 -> ... with one hostile string per place and transition:
    in its id, its name and its doc line. Only t0 is enabled at first."""
    evil = payloads(port)
    b = NetBuilder(evil[1])
    for k, text in enumerate(evil):
        b.place(text, 1 if k == 0 else 0, name=evil[(k + 1) % len(evil)],
                payload={"doc": evil[(k + 2) % len(evil)]})
    for k, text in enumerate(evil[:-1]):
        t = f"{text} t"
        b.transition(t, name=evil[(k + 3) % len(evil)], payload={"doc": evil[(k + 4) % len(evil)]})
        b.arc(text, t)
        b.arc(t, evil[k + 1])
    return b.build()


def write_net(directory: Path, stem: str, port: int) -> Path:
    path = directory / f"{stem}.pnml"
    write_pnml(hostile_net(port), path)
    back = read_pnml(path)   # the reader gives every hostile id and name back as text
    assert [p.id for p in back.places] == payloads(port)
    return path


# -- witnesses -------------------------------------------------------------------------------

@pytest.fixture
def listener():
    """A TCP socket on this machine; returns its port and what connected to it."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    server.settimeout(0.05)
    heard: list[bytes] = []
    stop = threading.Event()

    def serve():
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except OSError:
                continue
            with conn:
                conn.settimeout(1)
                try:
                    heard.append(conn.recv(4096) or b"(connected)")
                    # an answer, so that a navigation here lands here
                    conn.sendall(b"HTTP/1.0 200 OK\r\nContent-Type: text/plain\r\n"
                                 b"Content-Length: 5\r\n\r\nheard")
                except OSError:
                    heard.append(b"(connected)")
    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield server.getsockname()[1], heard
    stop.set()
    thread.join()
    server.close()


VIEWPORT = {"width": 1600, "height": 900}


class Witnessed:
    """A page opened with every witness: requests, navigations, dialogs, console, errors."""

    def __init__(self, page, path: Path):
        self.uri = path.resolve().as_uri()
        self.page = page
        self.requests: list[str] = []
        self.navigations: list[str] = []
        self.dialogs: list[str] = []
        self.console: list[str] = []
        self.errors: list[str] = []
        self.watch = {
            "request": lambda r: self.requests.append(r.url),
            "framenavigated": lambda f: self.navigations.append(f.url),
            "dialog": lambda d: (self.dialogs.append(d.message), d.dismiss()),
            "console": lambda m: self.console.append(f"{m.type}: {m.text}"),
            "pageerror": lambda e: self.errors.append(str(e))}
        for event, handler in self.watch.items():
            page.on(event, handler)
        # every request is let through, so that the listener is a witness of its own
        self.route = lambda route: route.continue_()
        page.route("**/*", self.route)
        page.goto(self.uri)
        page.wait_for_timeout(300)   # a refresh or a timer would have fired by now

    def detach(self) -> None:
        """The witnesses taken off the page (one the next test opens again)."""
        if self.page.is_closed():
            return
        for event, handler in self.watch.items():
            self.page.remove_listener(event, handler)
        self.page.unroute("**/*", self.route)

    def pwned(self) -> bool:
        return self.page.evaluate("window.__pwned !== undefined")

    def assert_nothing_happened(self, heard: list[bytes]) -> None:
        self.page.wait_for_timeout(200)
        assert not self.pwned(), "a payload ran"
        assert self.dialogs == [], f"a payload ran: dialogs {self.dialogs}"
        assert self.console == [], f"the console: {self.console}"
        assert self.errors == [], f"script errors: {self.errors}"
        assert self.requests == [self.uri], f"the page fetched {self.requests[1:]}"
        assert self.navigations == [self.uri], f"the page went to {self.navigations[1:]}"
        assert self.page.url == self.uri
        assert heard == [], f"the listener heard {heard}"


def drawn(page, places: int, transitions: int) -> None:
    """The net is drawn: every node in the SVG, and no failure shown."""
    assert page.locator("#net g.place").count() == places
    assert page.locator("#net g.transition").count() == transitions
    assert page.locator("#failure").count() == 0


# -- in the browser --------------------------------------------------------------------------

@pytest.fixture
def witnessed(browser, tab):
    """Opens a page file with every witness (:class:`Witnessed`): a test's first page is the
    shared tab navigated to the file (a new page costs Chromium a window of its own), any
    other a page of its own; afterwards the witnesses are taken off and the tab emptied."""
    made: list[Witnessed] = []

    def open_(path: Path) -> Witnessed:
        page = tab.page(VIEWPORT) if not made else browser.new_page(viewport=VIEWPORT)
        made.append(Witnessed(page, path))
        return made[-1]

    yield open_
    for k, w in enumerate(made):
        w.detach()
        if k == 0:
            tab.leave()
        elif not w.page.is_closed():
            w.page.close()


@pytest.mark.timeout(60)
@pytest.mark.parametrize("stem", [*SLOT_NAMES, '<img src=x onerror="window.__pwned=1">',
                                  "<!--<script>", "a\u2028b\u2029c"])
def test_a_hostile_net_is_drawn_and_played_as_text(tmp_path, witnessed, listener, stem):
    port, heard = listener
    evil = payloads(port)
    net = write_net(tmp_path, stem, port)
    out = run("show", net, "-o", tmp_path / "page.html")
    assert out.returncode == 0, out.stderr
    w = witnessed(tmp_path / "page.html")
    page = w.page
    assert page.title() == f"{stem} (mcl2pnml)"
    assert page.text_content("header h1") == stem
    drawn(page, len(evil), len(evil) - 1)
    assert page.text_content("#marking") == evil[0]
    labels = page.locator("#net g.place > text").all_text_contents()
    assert labels == evil[1:] + evil[:1]           # each place shows its name, as text
    titles = page.locator("#net g.transition > title").all_text_contents()
    assert titles[0] == f"{evil[0]} t: {evil[4]}"  # the id and the doc line, as text
    # the only enabled transition fires by a click in the drawing, then by its button
    page.locator("#net g.transition.enabled rect").click()
    assert page.locator("#history li").all_text_contents() == [f"{evil[0]} t"]
    assert page.text_content("#marking") == evil[1]
    page.locator("#enabled button").click()
    assert page.locator("#history li").all_text_contents() == [f"{evil[0]} t", f"{evil[1]} t"]
    assert page.text_content("#marking") == evil[2]
    page.click("#back")
    assert page.text_content("#marking") == evil[1]
    # the reachability graph: a marking per place of the chain, named by its place's id
    page.select_option("#view-kind", "graph")
    markings = page.locator("#graph g.marking > title").all_text_contents()
    assert markings == [f"M{k}: {e}" for k, e in enumerate(evil[:-1])] + [f"M{len(evil) - 1} (dead): {evil[-1]}"]
    assert page.locator("#graph line.edge > title").all_text_contents() == [f"{e} t" for e in evil[:-1]]
    page.click('#graph g.marking[data-index="2"] circle')
    assert page.text_content("#marking") == evil[2]
    # the supervisor's steps are named as text, and Settle takes them all
    assert f"({evil[2]} t)" in page.text_content("#supervisor")
    assert page.is_disabled("#advance")
    page.click("#settle")
    assert page.text_content("#marking") == evil[-1]
    assert page.locator("#history li").all_text_contents() == [f"{e} t" for e in evil[2:-1]]
    w.assert_nothing_happened(heard)


def mcl_string(text: str) -> str:
    """An MCL string literal (the functional form prints it so: language.functional)."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


@pytest.mark.timeout(60)
def test_a_hostile_mission_tree_is_text(tmp_path, witnessed, listener):
    """A mission's string arguments reach the tree view as text (the lines U+2028 and
    U+2029 aside: MCL's strings are read with Python's unicode_escape)."""
    port, heard = listener
    evil = [e for e in payloads(port) if e.isascii()]
    calls = "".join(f"    T({mcl_string(e)});\n" for e in evil)
    mission = tmp_path / "evil.mcl"
    mission.write_text(f"primitive P(x);\ntask T(x) = AchieveGoal(P(x));\nmission {{\n{calls}}}\n")
    out = run("show", mission, "-o", tmp_path / "page.html")
    assert out.returncode == 0, out.stderr
    w = witnessed(tmp_path / "page.html")
    labels = w.page.locator("#tree div.call > span:first-child").all_text_contents()
    assert labels == [f"T({mcl_string(e)})" for e in evil]
    # a call clicked in the tree opens its net, named as text above the drawing
    w.page.click("#tree div.call >> nth=0")
    assert w.page.locator("#crumbs button").last.text_content() == f"T({mcl_string(evil[0])})"
    assert w.page.locator("#net g.transition").count() > 0
    w.assert_nothing_happened(heard)


@pytest.mark.timeout(60)
def test_a_hostile_run_log_is_followed_as_text(tmp_path, witnessed, listener):
    port, heard = listener
    evil = payloads(port)
    img, script, comment, sep, meta = evil[:5]
    net = write_net(tmp_path, "__DATA__", port)
    entries = [{"journal": comment},
               {"t": 0, "action": img, "primitive": script, "args": [comment, sep]},
               {"t": 1, "event": meta, "primitive": comment},
               {"t": 2, "ignored": {"event": img, "primitive": script}, "reason": comment},
               {"t": 3, "fire": f"{evil[0]} t", "note": "</script><!--<script>"},
               {"t": 3.5, "breach": img, "primitive": script, "message": comment},
               {"t": 4, "outcome": script}]
    log = tmp_path / "run.jsonl"
    log.write_text("".join(json.dumps(e, ensure_ascii=False) + "\n" for e in entries))
    out = run("show", net, "--run", log, "-o", tmp_path / "page.html")
    assert out.returncode == 0, out.stderr
    w = witnessed(tmp_path / "page.html")
    page = w.page
    drawn(page, len(evil), len(evil) - 1)
    assert page.locator("#run-entries li").count() == len(entries) - 1
    shown = page.locator("#run-entries li").all_text_contents()
    args = ",".join(json.dumps(a, ensure_ascii=False) for a in (comment, sep))
    assert shown[0] == f"t=0  {img} {script}({args})"
    assert shown[-2] == f"t=3.5  breach {comment}"      # a breach, said as the run said it
    page.click("#run-next")                              # up to the first firing
    assert page.locator("#history li").all_text_contents() == [f"{evil[0]} t"]
    assert page.text_content("#run-message") == ""
    page.click("#run-end")
    assert page.text_content("#run-position") == f"step {len(entries) - 1} of {len(entries) - 1}"
    # a log the student picks in the page is checked as --run checks one (a line that is
    # no object, a firing of no transition refused, the run shown before kept), and read
    # the same way: as data, never markup
    from playwright.sync_api import expect
    picked = tmp_path / "picked.jsonl"
    picked.write_text("null\n[1]\n")
    page.set_input_files("#run-file", str(picked))
    expect(page.locator("#run-message")).to_have_text("line 1: a run log's line is a JSON "
                                                      "object")
    assert page.locator("#run-entries li").count() == len(entries) - 1
    ignored = json.dumps({"t": 0, "ignored": {"event": img, "primitive": script},
                          "reason": script}) + "\n"
    picked.write_text(ignored + json.dumps({"t": 1, "fire": "__proto__"}) + "\n")
    page.set_input_files("#run-file", str(tmp_path / "page.html"))    # a change, then back
    page.set_input_files("#run-file", str(picked))
    expect(page.locator("#run-message")).to_contain_text(
        "line 2: the run fires '__proto__', which is no transition of")
    picked.write_text(ignored + json.dumps({"t": 1, "note": comment}) + "\n")
    page.set_input_files("#run-file", str(tmp_path / "page.html"))
    page.set_input_files("#run-file", str(picked))
    expect(page.locator("#run-entries li")).to_have_count(2)
    assert script in page.locator("#run-entries li").first.text_content()
    assert page.text_content("#run-message") == ""
    w.assert_nothing_happened(heard)


@pytest.mark.timeout(60)
def test_the_witnesses_see_an_attack(tmp_path, witnessed, listener):
    """The same witnesses on a page made without the defences: every one of them trips,
    so their silence above means something."""
    port, heard = listener
    bare = tmp_path / "bare.html"
    bare.write_text("<!DOCTYPE html><title>x</title><body>" + payloads(port)[0] + "</body>")
    w = witnessed(bare)
    w.page.wait_for_function("window.__pwned !== undefined", polling=50)   # not every frame
    w.page.wait_for_timeout(300)
    assert w.pwned() and w.dialogs == ["pwned"] and "log: pwned" in w.console
    assert f"http://127.0.0.1:{port}/fetch" in w.requests
    assert any(b"GET /fetch" in h for h in heard)
    w.page.close()
    refresh = tmp_path / "refresh.html"
    refresh.write_text("<!DOCTYPE html><title>x</title>" + payloads(port)[5])
    w = witnessed(refresh)
    w.page.wait_for_timeout(300)
    assert f"http://127.0.0.1:{port}/refresh" in w.navigations
    assert any(b"GET /refresh" in h for h in heard)
    w.page.close()


@pytest.mark.timeout(60)
def test_a_broken_page_says_so(tmp_path, tab):
    """A page whose script fails shows why, instead of a blank drawing."""
    html = show.page("t", [])           # no net at all: the script cannot draw one
    (tmp_path / "empty.html").write_text(html)
    page = tab.page({"width": 1280, "height": 720})     # a new page's size
    page.goto((tmp_path / "empty.html").resolve().as_uri())
    assert "This page failed" in page.text_content("#failure")
    tab.leave()


# -- the command line: a run log with NaN or infinities ----------------------------------------

@pytest.mark.parametrize("line, token", [
    ('{"t": 1, "note": "NaN", "x": NaN}', "NaN"),
    ('{"t": Infinity}', "Infinity"),
    ('{"t": 1, "args": [1, -Infinity]}', "-Infinity"),
    ('{"t": 1e999, "fire": "x"}', "1e999"),
    ('{"t": 1, "args": [-1.5E+400]}', "-1.5E+400"),
])
def test_a_run_log_with_nan_or_infinity_is_refused_where_it_stands(tmp_path, line, token):
    net = tmp_path / "net.pnml"
    write_pnml(hostile_net(9), net)
    log = tmp_path / "run.jsonl"
    log.write_text('{"t": 0, "action": "start", "primitive": "P"}\n' + line + "\n")
    out = run("show", net, "--run", log, "-o", tmp_path / "page.html")
    column = line.rindex(token) + 1    # the last: an earlier one is inside a string
    assert out.returncode == 2
    assert f"{log}:2:{column}: '{token}' is " in out.stderr
    assert "Traceback" not in out.stderr and out.stdout == ""
    assert not (tmp_path / "page.html").exists()


def test_a_run_log_read_as_data(tmp_path):
    log = tmp_path / "run.jsonl"
    log.write_text('{"fire": ["t1"]}\n')
    with pytest.raises(Mcl2PnmlError, match="transition id"):
        show.read_run(log)
    log.write_text('{"t": ' + "9" * 5000 + "}\n")
    with pytest.raises(Mcl2PnmlError, match=r":1:1: not a run log's JSON line"):
        show.read_run(log)
    log.write_text('{"t": 1.5, "note": "NaN Infinity 1e999"}\n')
    assert show.read_run(log) == [{"t": 1.5, "note": "NaN Infinity 1e999"}]


# -- the page builder, without a browser -------------------------------------------------------

HOSTILE = ["<", ">", "&", "</script>", "</SCRIPT >", "<!--", "-->", "<script>", "\u2028",
           "\u2029", '"', "'", "\\", "\ud800", "é", "\x00", "]]>", *SLOT_NAMES]


def test_the_data_is_json_no_html_parser_can_read_as_markup():
    for text in HOSTILE:
        data = show.json_for_html({"k": text, text: [text]})
        assert data.isascii()
        assert not set(data) & set("<>&\u2028\u2029")
        assert json.loads(data) == {"k": text, text: [text]}
    with pytest.raises(ValueError):
        show.json_for_html({"x": math.nan})
    with pytest.raises(ValueError):
        show.json_for_html([math.inf])


def test_the_template_is_filled_in_one_pass():
    template = show.template()
    for slot in SLOT_NAMES:
        assert slot in template
    # no slot in the script or the style: their hashes are the template's
    for m in re.finditer(r"<(script|style)>(.*?)</\1>", template, re.S):
        assert not re.search("__[A-Z]+__", m.group(2))
    # each value spells another slot: none is filled again
    values = {"TITLE": "__DATA__", "CSP": "__TITLE__", "DATA": "__CSP__"}
    filled = show.fill(template, values)
    assert filled.count("__DATA__") == template.count("__TITLE__")
    assert filled == (template.replace("__TITLE__", "\0T").replace("__CSP__", "\0C")
                      .replace("__DATA__", "\0D").replace("\0T", "__DATA__")
                      .replace("\0C", "__TITLE__").replace("\0D", "__CSP__"))


def _hostile_page() -> str:
    net = hostile_net(9)
    # a file name that is not UTF-8 comes as lone surrogates: the page must still encode
    return show.page("__DATA__ </title><!--<script>\udcff", [show.variant(net, "__TITLE__")],
                     [{"t": 0, "action": p, "primitive": p} for p in payloads(9)])


def test_hostile_data_adds_no_markup():
    html = _hostile_page()
    template = show.template()
    for markup in ("<script", "</script", "<!--", "-->", "<img", "<meta", "<a ", "<svg",
                   "</title", "<h1", "</h1"):
        assert html.lower().count(markup) == template.lower().count(markup), markup
    assert "\u2028" not in html and "\u2029" not in html
    html.encode("utf-8")


def test_the_policy_lets_run_only_the_pages_own_script_and_style():
    html = _hostile_page()
    policy = re.search(r'<meta http-equiv="Content-Security-Policy" content="([^"]*)">', html)
    assert policy
    directives = dict(d.strip().split(" ", 1) for d in policy.group(1).split(";"))
    assert "unsafe" not in policy.group(1)
    assert directives["default-src"] == "'none'"
    for name in ("connect-src", "img-src", "form-action", "base-uri", "object-src"):
        assert directives[name] == "'none'", name
    assert directives["require-trusted-types-for"] == "'script'"
    scripts = re.findall(r"<script>(.*?)</script>", html, re.S)
    styles = re.findall(r"<style>(.*?)</style>", html, re.S)
    assert len(scripts) == 1 and len(styles) == 1
    assert len(re.findall(r"<script\b", html)) == 2   # the script and the data
    for source, text in ((directives["script-src"], scripts[0]),
                         (directives["style-src"], styles[0])):
        digest = base64.b64encode(hashlib.sha256(text.encode()).digest()).decode()
        assert source == f"'sha256-{digest}'"
    # the script makes no markup from data, and sets no style or URL but one: the
    # download links of the drawing (SVG, PNG) get a blob: URL that the browser mints for
    # a Blob the page made itself (never data:, never a URL the input spells). So every
    # `href` in the script must be that assignment, `.href = URL.createObjectURL(`; any
    # other (a read, an href attribute, setAttribute("href"...), xlink:href) is refused
    script = scripts[0]
    hrefs = [m.start() for m in re.finditer("href", script, re.I)]
    minted = [m.start() + 1 for m in re.finditer(r"\.href = URL\.createObjectURL\(", script)]
    assert hrefs and hrefs == minted, [script[k - 30:k + 40] for k in set(hrefs) - set(minted)]
    for sink in ("innerHTML", "outerHTML", "insertAdjacentHTML", "document.write", "eval(",
                 "Function(", "style:", ".style", "setTimeout(\"", "location"):
        assert sink not in script, sink


def test_a_doc_that_is_not_text_is_shown_as_text():
    b = NetBuilder("n")
    b.place("p", 1, payload={"doc": {"x": "<!--<script>"}})
    b.transition("t", payload={"doc": [1.5]})
    b.arc("p", "t")
    page = show.page("n", [show.variant(b.build(), "the net")])
    data = json.loads(re.search(r'<script type="application/json" id="data">(.*?)</script>',
                                page, re.S).group(1))
    assert data["variants"][0]["places"][0]["doc"] == '{"x": "<!--<script>"}'
    assert data["variants"][0]["transitions"][0]["doc"] == "[1.5]"
