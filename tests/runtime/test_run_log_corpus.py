"""One corpus of bad run logs, refused alike by `show --run` and by the page's file chooser.

Both readers check a log against the same schema (mcl2pnml/view/runlog.schema.json,
embedded in the page): each log of tests/data/runlogs/bad.json is refused by the
Python reader with one message at its line, and by the page, in Chromium, with a
message naming the same line and fault, the page alive (no script error).
"""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.pipeline import compile_file
from mcl2pnml.view.show import check_run, read_run, run_log_schema

from helpers import ROOT, run_cli
from shown import shown

SAUCE = ROOT / "examples" / "sauce.mcl"
CORPUS = json.loads((ROOT / "tests" / "data" / "runlogs" / "bad.json").read_text())["logs"]
#: A line nested deeper than either reader goes: refused by both, whatever their stacks.
DEEP = {"name": "nested 100,000 deep", "line": 1, "fault": "not a run log's JSON line",
        "text": '{"t": 0, "args": ' + "[" * 100_000 + "]" * 100_000 + "}\n"}
LOGS = CORPUS + [DEEP]
#: The keywords the page's checker knows (show_page.html, schemaFault); the others only say.
CHECKED = {"type", "properties", "required", "items"}
ANNOTATIONS = {"$schema", "$id", "title", "description"}


def write_logs(folder: Path) -> list[Path]:
    paths = []
    for k, log in enumerate(LOGS):
        path = folder / f"bad-{k}.jsonl"
        path.write_text(log["text"])
        paths.append(path)
    return paths


def test_the_schema_uses_only_what_the_page_checks():
    def walk(schema: dict) -> set[str]:
        found = set(schema)
        for sub in schema.get("properties", {}).values():
            found |= walk(sub)
        if "items" in schema:
            found |= walk(schema["items"])
        return found
    schema = run_log_schema()
    assert walk(schema) <= CHECKED | ANNOTATIONS, walk(schema) - CHECKED - ANNOTATIONS


@pytest.fixture(scope="module")
def sauce():
    return compile_file(SAUCE)


@pytest.mark.parametrize("log", LOGS, ids=[log["name"] for log in LOGS])
def test_the_python_reader_refuses_each_bad_log_at_its_line(tmp_path, sauce, log):
    path = tmp_path / "bad.jsonl"
    path.write_text(log["text"])
    with pytest.raises(Mcl2PnmlError) as caught:
        check_run(sauce, read_run(path), str(path))
    message = str(caught.value)
    assert message.startswith(f"{path}:{log['line']}"), message
    assert log["fault"] in message, message


def test_the_command_refuses_a_log_with_prototype_keys_and_writes_no_page(tmp_path):
    log, page = tmp_path / "run.jsonl", tmp_path / "page.html"
    log.write_text(CORPUS[0]["text"])
    out = run_cli("show", SAUCE, "--run", log, "-o", page)
    assert out.returncode == 2 and "Traceback" not in out.stderr, out.stderr
    assert f"{log}:1:10: a run log's 'fire' is a transition id, a JSON string" in out.stderr
    assert not page.exists()


@pytest.mark.timeout(120)
def test_the_pages_file_chooser_refuses_each_bad_log_and_lives(tmp_path, tab,
                                                                tmp_path_factory):
    # the paper's mission's page as other modules open it, made once per run (shown.py),
    # in the shared tab (a new page costs Chromium a window of its own)
    page_file = shown(tmp_path_factory, "sauce.html", SAUCE)
    page = tab.page({"width": 1280, "height": 720})     # a new page's size
    errors: list[str] = []
    record = lambda e: errors.append(str(e))            # noqa: E731
    page.on("pageerror", record)
    page.goto(page_file.as_uri())
    from playwright.sync_api import expect
    for log, path in zip(LOGS, write_logs(tmp_path)):
        page.set_input_files("#run-file", str(path))
        expect(page.locator("#run-message")).to_contain_text(
            f"line {log['line']}: {log['fault']}", timeout=10_000)
        assert page.locator("#failure").count() == 0, log["name"]
        assert page.text_content("#run-position") == "no run loaded", log["name"]
    assert errors == []
    # and a good log is still read after them all
    good = tmp_path / "good.jsonl"
    good.write_text(json.dumps({"t": 0, "note": "a note"}) + "\n")
    page.set_input_files("#run-file", str(good))
    expect(page.locator("#run-entries li")).to_have_count(1)
    assert page.text_content("#run-message") == ""
    page.remove_listener("pageerror", record)
    tab.leave()
