"""`mcl2pnml show MISSION --live LOG`: the page served on loopback follows a run as its
log is written, in headless Chromium.

The server binds 127.0.0.1 only, on a port the system picks, under a random
token in the URL: a request without it (or for another host name) is
refused. The page asks its own origin for the log's new entries (its policy
allows connect-src 'self', the static page's none) and plays them; the
server stops a moment (--linger) after the page has been handed the run's
outcome.
"""
from __future__ import annotations

import json
import os
import re
import select
import time
import urllib.error
import urllib.request
from contextlib import contextmanager
from typing import Iterator

import pytest

from helpers import ROOT, run_cli as run
from served import Served
from test_show import marking

SAUCE = ROOT / "examples" / "sauce.mcl"
#: Wall seconds a wait for the page or the server may last: each ends as soon as what it
#: waits for happens, so a loaded machine's seconds cost a quiet one nothing.
WAIT = 60
#: Milliseconds between two looks of a wait in the page: by default it looks at every
#: frame, which keeps Chromium drawing 60 frames a second for as long as the wait lasts.
POLL = 50


@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> list[str]:
    """A run of the paper's mission on the simulated AUV: its log's lines."""
    log = tmp_path_factory.mktemp("live") / "recorded.jsonl"
    done = run("run", SAUCE, "--log", log)
    assert done.returncode == 0, done.stderr
    return log.read_text().splitlines(keepends=True)


@contextmanager
def serving(log, *options) -> Iterator[tuple[Served, str]]:
    """`show --live LOG` started, a process of its own forked from the tests' command server
    (served.py: a fresh interpreter imported the command again, a core-second); the process
    and the URL it prints on its standard error; killed if still up."""
    read_end, write_end = os.pipe()
    with os.fdopen(write_end, "w") as err, open(os.devnull, "w") as out:
        proc = Served(["show", SAUCE, "--live", log, *options], os.getcwd(), out, err)
    stderr = os.fdopen(read_end)
    try:
        deadline, said, url = time.monotonic() + 60, "", None
        while url is None and time.monotonic() < deadline:
            if not select.select([stderr], [], [], 0.5)[0]:
                continue
            line = stderr.readline()
            said += line
            found = re.search(r"http://127\.0\.0\.1:\d+/[A-Za-z0-9_-]{20,}/", line)
            if found:
                url = found.group()
            elif not line:
                break
        if url is None:
            pytest.fail(f"no URL printed: {said}")
        yield proc, url
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        stderr.close()


def status(url: str, host: str | None = None) -> int:
    request = urllib.request.Request(url, headers={"Host": host} if host else {})
    try:
        with urllib.request.urlopen(request, timeout=5) as answer:
            return answer.status
    except urllib.error.HTTPError as e:
        return e.code


def test_the_page_follows_a_run_as_it_is_written(tmp_path, tab, recorded):
    log = tmp_path / "run.jsonl"                  # not there yet: the run has not started
    with serving(log, "--linger", "1") as (proc, url):
        origin, token = url.rsplit("/", 2)[0], url.rsplit("/", 2)[1]
        # refused: no token, a wrong one, another host name (DNS rebinding)
        assert status(origin + "/") == 403
        assert status(origin + "/" + "x" * len(token) + "/") == 403
        assert status(origin + "/" + "x" * len(token) + "/log?from=0") == 403
        assert status(url, host="attacker.example:80") == 403
        assert status(url + "log?from=0") == 200
        # the shared tab (a new page costs Chromium a window of its own)
        page = tab.page({"width": 1400, "height": 900})
        requests, errors = [], []
        watch = {"request": lambda r: requests.append(r.url),
                 "pageerror": lambda e: errors.append(str(e)),
                 "console": lambda m: errors.append(m.text) if m.type == "error" else None}
        for event, handler in watch.items():
            page.on(event, handler)
        answer = page.goto(url)
        policy = answer.headers["content-security-policy"]
        assert "connect-src 'self'" in policy and "default-src 'none'" in policy
        assert "mission.B" in marking(page)
        fires = [json.loads(line)["fire"] for line in recorded if '"fire"' in line]
        half = len(recorded) // 2
        with log.open("a") as out:                # the run, line by line
            for line in recorded[:half]:
                out.write(line)
                out.flush()
                time.sleep(0.002)
            so_far = sum('"fire"' in line for line in recorded[:half])
            page.wait_for_function(f"() => history.length === {so_far}", timeout=WAIT * 1000,
                                   polling=POLL)
            assert "mission.OK" not in marking(page)
            for line in recorded[half:]:
                out.write(line)
                out.flush()
                time.sleep(0.002)
        page.wait_for_function("() => /ended/.test(document.getElementById('live-status')"
                               ".textContent)", timeout=WAIT * 1000, polling=POLL)
        assert "mission.OK" in marking(page)
        assert page.locator("#history li").all_text_contents() == fires
        assert page.text_content("#run-message") == ""
        assert proc.wait(timeout=WAIT) == 0       # the outcome served, then --linger: stopped
        for event, handler in watch.items():
            page.remove_listener(event, handler)
        tab.leave()
        assert requests and all(r.startswith(url) for r in requests), requests
        assert not errors, errors


def test_a_bad_line_stops_the_following_and_is_shown(tmp_path, tab, recorded):
    log = tmp_path / "run.jsonl"
    log.write_text(recorded[0] + '{"t": 1, "fire": "nowhere.t9"}\n' + "".join(recorded[1:]))
    with serving(log, "--linger", "0.5") as (proc, url):
        page = tab.page({"width": 1280, "height": 720})     # a new page's size
        page.goto(url)
        page.wait_for_function("() => /error/.test(document.getElementById('live-status')"
                               ".textContent)", timeout=WAIT * 1000, polling=POLL)
        assert "'nowhere.t9', which is no transition" in page.text_content("#run-message")
        assert page.locator("#history li").count() == 1
        assert proc.wait(timeout=WAIT) == 0
        tab.leave()
