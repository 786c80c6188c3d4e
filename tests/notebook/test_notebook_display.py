"""Our values in Jupyter (mcl2pnml.notebook): each type's formatters registered with a real
IPython shell, a net drawn (or said too large to draw), missions and results shown as their
verdicts, and no input reaching the markup unescaped."""
from __future__ import annotations

import importlib
import json
from html.parser import HTMLParser

import pytest

from mcl2pnml import notebook, pipeline
from mcl2pnml.core.net import NetBuilder
from mcl2pnml.runtime.options import RunOptions

IPython = pytest.importorskip("IPython", reason="IPython comes with ipykernel, in the test "
                                                "extra (make setup)")
from IPython.core.interactiveshell import InteractiveShell  # noqa: E402

#: Markup an input may carry, and that must reach a page as text.
HOSTILE = '<script>alert(1)</script><img src=x onerror=alert(1)>'
#: The tags our HTML is made of (Pygments' spans and divs, for a mission's text).
TAGS = {"div", "p", "b", "table", "tr", "th", "td", "details", "summary", "pre", "code",
        "img", "span"}


class Markup(HTMLParser):
    """The tags of an HTML text, and its text."""

    def __init__(self, text: str):
        super().__init__()
        self.tags: set[str] = set()
        self.text: list[str] = []
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        self.tags.add(tag)
        self.attrs = getattr(self, "attrs", []) + attrs

    def handle_data(self, data):
        self.text.append(data)


def assert_escaped(html: str, *inputs: str) -> None:
    """``html`` is made of our tags alone, with no event handler, and shows each input as
    text."""
    found = Markup(html)
    assert found.tags <= TAGS, found.tags - TAGS
    assert not [name for name, _ in getattr(found, "attrs", []) if name.startswith("on")]
    for text in inputs:
        assert text in "".join(found.text)


@pytest.fixture(scope="module")
def shell():
    shell = InteractiveShell.instance()
    assert notebook.register(shell)
    return shell


def shown(shell, value) -> dict[str, str]:
    data, _ = shell.display_formatter.format(value)
    return data


@pytest.mark.parametrize("where", sorted(notebook.SHOWN))
def test_every_type_shown_is_a_class_of_ours(where):
    """A class renamed or moved is shown as plain text again: this test says so."""
    module, name = where
    assert isinstance(getattr(importlib.import_module(module), name), type)


def test_a_net_is_shown_as_its_drawing(shell):
    net = pipeline.template_net("task")
    data = shown(shell, net)
    assert data["text/plain"] == repr(net) and "text/html" not in data
    svg = data["image/svg+xml"]
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg
    assert f"<title>{net.name}</title>" in svg
    assert {p.id for p in net.places} <= set(Markup(svg).text)


def test_a_net_too_large_to_draw_says_so(shell, monkeypatch):
    net = pipeline.template_net("task")
    monkeypatch.setattr(notebook, "MAX_DRAWN", len(net.places) + len(net.transitions) - 1)
    data = shown(shell, net)
    assert "image/svg+xml" not in data
    assert f"{len(net.places) + len(net.transitions):,} nodes, over the" in data["text/html"]


def test_an_analysis_shows_each_verdict_in_its_colour(shell):
    analysis = pipeline.analyze(pipeline.template_net("task"), state_space_only=True)
    data = shown(shell, analysis)
    from mcl2pnml.analysis.report import verdict_rows
    rows = verdict_rows(analysis.as_json())
    for what, flag, said in rows:
        coloured = flag is not None or said == "not computed"
        cell = (f'<b style="color:{notebook.COLOURS[flag]}">{said}</b>' if coloured else said)
        assert f"<td style=\"text-align:left\">{what}</td><td style=\"text-align:left\">" \
               f"{cell}</td>" in data["text/html"]
    assert data["text/plain"].splitlines()[1:] == [f"  {w}: {s}" for w, _, s in rows]
    assert_escaped(data["text/html"], analysis.text())


def test_the_verdicts_of_properties_show_each_and_a_counterexample(shell):
    net, props = pipeline.properties_of(
        notebook_root() / "examples" / "sauce.mcl",
        extra=notebook_root() / "examples" / "sauce.false.props")
    verdicts = pipeline.check_properties(net, props)
    table = shown(shell, verdicts)
    failing = [v for v in verdicts if v.shape is not None]
    assert failing, "sauce.false.props holds properties that fail"
    for v in verdicts:
        assert f"property {v.property.name}: {v.status.value}" in table["text/plain"]
        assert f"<td style=\"text-align:left\">{v.property.name}</td>" in table["text/html"]
    one = shown(shell, failing[0])["text/html"]
    assert [t.strip() for t in Markup(one).text if t.strip() in failing[0].transitions] \
        == list(failing[0].transitions)
    assert "the cycle starts here" in one   # a lasso: each is, on an untimed net


def test_a_mission_and_its_run_show_their_inputs_as_text(shell, tmp_path):
    mission = tmp_path / "<img src=x onerror=alert(1)>.mcl"
    mission.write_text(f'const Evil = {json.dumps(HOSTILE)};\nprimitive Go(x);\n'
                       "task T(x) = AchieveGoal(Go(x)) timeout 5;\nmission { T(Evil); }\n")
    script = tmp_path / "vehicle.json"
    script.write_text('{"Go": ["fail@1"]}')
    checked = pipeline.check_file(mission)
    page = shown(shell, checked)["text/html"]
    assert_escaped(page, str(mission), HOSTILE)
    assert "data:image/svg+xml;base64," in page
    run = pipeline.run_mission(mission, RunOptions(vehicle=str(script)))
    data = shown(shell, run)
    assert data["text/plain"] == "\n".join(run.report())
    assert_escaped(data["text/html"], HOSTILE, run.outcome.value)
    assert f'<b style="color:{notebook.COLOURS[False]}">FAIL</b>' in data["text/html"]


def test_hostile_names_of_a_net_reach_an_analysis_as_text(shell):
    b = NetBuilder(HOSTILE)
    b.place("<p>", 1)
    b.transition("</table>")
    b.arc("<p>", "</table>")
    net = b.build()
    assert_escaped(shown(shell, pipeline.analyze(net, state_space_only=True))["text/html"],
                   HOSTILE, "<p>")
    assert "text/html" not in shown(shell, net)   # drawn: graphviz escapes its labels


def test_timed_answer_odds_and_certificate_show_their_verdicts(shell):
    from mcl2pnml.runtime.vehicle_model import VehicleModel
    net = pipeline.compile_source("primitive KeepDepth(d); task Dive(d) = AchieveGoal("
                                  "KeepDepth(d)) timeout 60; mission { Dive(10); }")
    ends = pipeline.timed_ends(net)
    data = shown(shell, ends)
    assert data["text/plain"] == "\n".join(ends.lines())
    colour = notebook.COLOURS[ends.always_ends]
    assert f'<b style="color:{colour}">{ends.lines()[1].strip()}</b>' in data["text/html"]
    model = VehicleModel.from_json('{"primitives": {"KeepDepth": {"achieve": "2/3", '
                                   '"fail": "1/3", "after": {"fixed": 5}}}}')
    odds = shown(shell, pipeline.exact_odds(net, model))
    assert "<td style=\"text-align:left\">2/3</td>" in odds["text/html"]
    assert odds["text/plain"].startswith("P(OK) = 0.666667, P(FAIL) = 0.333333")
    certified = pipeline.certify_file(notebook_root() / "examples" / "sauce.mcl")
    said = shown(shell, certified)
    assert not certified.problems and said["text/plain"] == "the certificate holds"
    assert f'<b style="color:{notebook.COLOURS[True]}">the certificate holds' \
        in said["text/html"]


def notebook_root():
    from helpers import ROOT
    return ROOT
