"""Our values shown in Jupyter (and any IPython front end): a net as its drawing, a
mission as its drawing, its warnings and its text, and the results (an analysis, the
verdicts of properties, the timed answer, a run, the odds, a certificate) as tables of
their verdicts.

The values are the layers' own and know nothing of this module: the core may not import
the view, nor the analysis the drawings. When :mod:`mcl2pnml` is imported under IPython,
:func:`register` gives IPython one formatter per type, named by its module and class
(``for_type_by_name``), so that nothing is imported before a value of the type is shown;
the types this layer may not import (the facade's, the timed verdicts', the odds') are
read by their fields alone (:data:`SHOWN`).

Every value put into HTML is escaped (:func:`html.escape`): a net's names, a mission's
text and a vehicle's words come from input. A drawing is graphviz's SVG (its labels
escaped by the drawing, :mod:`mcl2pnml.view.drawing`), shown as an image, where no
script of it runs.
"""
from __future__ import annotations

import base64
import html
import sys
from typing import Any, Callable, Iterable, Sequence

#: A net of more nodes than this is not drawn in a notebook: dot takes seconds for a
#: mission of 600 nodes and minutes for 4,000 (a survey of 100 calls).
MAX_DRAWN = 1_000
#: The longest firing sequence or trace shown; the rest is counted.
MAX_ROWS = 100
#: The colours of the verdicts: holds, fails, unknown.
COLOURS = {True: "#1a7f37", False: "#cf222e", None: "#6e7781"}


def e(value: Any) -> str:
    """``value`` as HTML text: every value reaches the markup through here."""
    return html.escape(str(value), quote=True)


def verdict(flag: bool | None, words: str) -> str:
    """``words`` in the colour of ``flag``: True holds, False fails, None unknown."""
    return f'<b style="color:{COLOURS[flag]}">{e(words)}</b>'


def table(rows: Iterable[Sequence[str]], head: Sequence[str] = ()) -> str:
    """A table of cells already made HTML (by :func:`e` or :func:`verdict`)."""
    top = "<tr>" + "".join(f"<th>{e(h)}</th>" for h in head) + "</tr>" if head else ""
    body = "".join("<tr>" + "".join(f'<td style="text-align:left">{c}</td>' for c in row)
                   + "</tr>" for row in rows)
    return f"<table>{top}{body}</table>"


def box(title: str, *parts: str) -> str:
    """One output: its title, then its parts (HTML already made)."""
    return f'<div class="mcl2pnml"><p><b>{e(title)}</b></p>{"".join(parts)}</div>'


def folded(summary: str, text: str) -> str:
    """Plain ``text`` shown when asked (a whole report, a trace)."""
    return f"<details><summary>{e(summary)}</summary><pre>{e(text)}</pre></details>"


def _counted(items: Sequence[Any], shown: Callable[[int, Any], Sequence[str]]) -> list:
    """The rows of the first :data:`MAX_ROWS` items, then one saying how many are left."""
    rows = [shown(k, item) for k, item in enumerate(items[:MAX_ROWS])]
    if len(items) > MAX_ROWS:
        rows.append(["", e(f"... and {len(items) - MAX_ROWS:,} more")])
    return rows


# -- nets and missions -------------------------------------------------------------------

def too_large(net) -> str | None:
    """Why ``net`` is not drawn here (None: it is)."""
    # graphviz's dot found on the PATH: only to draw
    from mcl2pnml.view.layout import dot_available
    nodes = len(net.places) + len(net.transitions)
    if nodes > MAX_DRAWN:
        return (f"{nodes:,} nodes, over the {MAX_DRAWN:,} drawn in a notebook: "
                "save_net(net, 'net.svg', 'svg') or `mcl2pnml show` draws it")
    if not dot_available():
        return "graphviz's dot is not installed: the net is not drawn"
    return None


def net_svg(net) -> str | None:
    """A net's drawing (:func:`mcl2pnml.view.drawing.drawing`), as graphviz's SVG; None
    where it is not drawn (:func:`too_large`), for :func:`net_html` to say why."""
    if too_large(net) is not None:
        return None
    # the drawing and graphviz, 65 ms: only when a net is shown
    from mcl2pnml.io.dot import to_svg
    from mcl2pnml.view.drawing import drawing
    return to_svg(drawing(net).source).decode()


def net_html(net) -> str | None:
    """What a net not drawn shows instead (None: it is drawn, :func:`net_svg`)."""
    why = too_large(net)
    return None if why is None else box(repr(net), f"<p>{e(why)}</p>")


def _image(svg: str) -> str:
    encoded = base64.b64encode(svg.encode()).decode()
    return f'<img alt="the drawing" src="data:image/svg+xml;base64,{encoded}">'


def mission_text(checked) -> str:
    """A checked mission in a terminal: what it declares."""
    return f"mission {checked.program.file}: {checked.summary()}"


def mission_html(checked) -> str:
    """A checked mission (:func:`mcl2pnml.pipeline.check_file`): what it declares, its
    functional form (the paper's Algorithm 2), its warnings (docs/warnings.md), its
    net's drawing and its text, highlighted."""
    # the language's compiler, lint and highlighter, and Pygments: only when shown
    from pygments import highlight
    from pygments.formatters import HtmlFormatter
    from mcl2pnml.language.compiler import compile_checked
    from mcl2pnml.language.functional import format_node, mission_expression
    from mcl2pnml.language.highlight import MclLexer
    from mcl2pnml.language.lint import lint
    found = lint(checked)
    said = ([[verdict(False, w.code), e(f"{w.location.prefix()} {w.message}; {w.fix}")]
             for w in found] or [[verdict(True, "no warning"), ""]])
    net = compile_checked(checked)
    svg = net_svg(net)
    source = highlight(checked.program.source, MclLexer(), HtmlFormatter(noclasses=True))
    return box(mission_text(checked),
               f"<p><code>{e(format_node(mission_expression(checked.mission)))}</code></p>",
               table(said), _image(svg) if svg else f"<p>{e(too_large(net))}</p>",
               f"<details><summary>the mission's text</summary>{source}</details>")


# -- results -------------------------------------------------------------------------------

def analysis_html(analysis) -> str:
    """An analysis (:class:`mcl2pnml.analysis.report.Analysis`): its verdicts, then the
    whole report as ``mcl2pnml analyze`` prints it."""
    rows = [[e(what), verdict(flag, said) if flag is not None or said == "not computed"
             else e(said)] for what, flag, said in _verdict_rows(analysis)]
    proven = ([f"<p>proven by the certificate {e(analysis.certificate.file)}</p>"]
              if analysis.certificate is not None else [])
    limits = [f"<p>{e(key)}: not computed ({e(why)})</p>" for key, why in analysis.limits.items()]
    return box(_net_line(analysis), table(rows, ("property", "holds")), *proven, *limits,
               folded("the whole report", analysis.text()))


def analysis_text(analysis) -> str:
    """An analysis in a terminal: its verdicts (the whole report: ``analysis.text()``)."""
    return "\n".join([_net_line(analysis)] + [f"  {what}: {said}"
                                              for what, _, said in _verdict_rows(analysis)])


def _verdict_rows(analysis) -> list:
    from mcl2pnml.analysis.report import verdict_rows   # the report's words: only when shown
    return verdict_rows(analysis.as_json())


def _net_line(analysis) -> str:
    f = analysis.facts
    return f"net {f.net}: {f.places:,} places, {f.transitions:,} transitions, {f.arcs:,} arcs"


#: A property's verdict (:class:`mcl2pnml.analysis.checking.observers.Status`) as a flag.
STATUS = {"holds": True, "fails": False, "unknown": None}


def _said(v) -> str:
    return v.status.value + (f" ({v.reason})" if v.reason else "")


def _counterexample(v) -> str:
    return "" if v.shape is None else f"{v.shape.value}, {len(v.transitions):,} firings"


def _steps(v) -> list:
    def step(k: int, t: str) -> list[str]:
        starts = v.loop is not None and k == v.loop
        return [e(k + 1), e(t) + (" <b>&larr; the cycle starts here</b>" if starts else "")]
    return _counted(v.transitions, step)


def verdict_html(v) -> str:
    """A property's verdict (:class:`mcl2pnml.analysis.checking.observers.Verdict`): holds,
    fails with its counterexample (a firing sequence, its cycle marked), or unknown."""
    parts = [f"<p>{verdict(STATUS[v.status.value], _said(v))} ({v.states:,} states)</p>"]
    if v.shape is not None:
        parts += [f"<p>counterexample ({e(v.shape.value)}):</p>", table(_steps(v))]
    return box(f"property {v.property.name}: {v.property.text}", *parts)


def verdict_text(v) -> str:
    cex = _counterexample(v)
    return f"property {v.property.name}: {_said(v)}" + (f" (counterexample: {cex})" * bool(cex))


def verdicts_html(verdicts) -> str:
    """Each property's verdict, in order (:class:`mcl2pnml.pipeline.Verdicts`), one row each;
    a counterexample's shape and length beside a property that fails."""
    rows = [[e(v.property.name), e(v.property.text), verdict(STATUS[v.status.value], _said(v)),
             e(_counterexample(v))] for v in verdicts]
    return box(f"{len(verdicts):,} properties",
               table(rows, ("property", "as written", "verdict", "counterexample")))


def verdicts_text(verdicts) -> str:
    return "\n".join(map(verdict_text, verdicts)) or "no property"


def timed_html(ends) -> str:
    """The timed answer (:class:`mcl2pnml.timed_verdicts.TimedEnds`): whether every run
    ends, a stall, the earliest and latest end times, as ``analyze --timed`` says them."""
    first, always, *rest = ends.lines()
    rows = [[verdict(ends.always_ends, always.strip())], *([e(line.strip())] for line in rest)]
    return box(first, table(rows))


def timed_text(ends) -> str:
    return "\n".join(ends.lines())


#: A run's outcome as a flag: OK holds, ABORTED is neither, FAIL and the rest fail.
OUTCOMES = {"OK": True, "ABORTED": None}


def run_html(run) -> str:
    """A run (:class:`mcl2pnml.runtime.engine.Run`): its outcome, why, and its trace."""
    outcome, trace = run.outcome.value, run.as_json()["trace"]
    head, *why = run.report()
    rows = _counted(trace, lambda k, x: [
        e(x["t"]), e(x.get("action") or x.get("event")), e(x.get("primitive", "")),
        e(", ".join(map(str, x.get("args", []))) or x.get("why", ""))])
    return box(f"run: {head}", f"<p>{verdict(OUTCOMES.get(outcome, False), outcome)}</p>",
               *(f"<p>{e(line.strip())}</p>" for line in why),
               table(rows, ("t (s)", "what", "primitive", "arguments")))


def run_text(run) -> str:
    return "\n".join(run.report())


def _endings(odds) -> list[tuple[str, float, Any]]:
    exact = odds.exact or {}
    return ([(f"P({name})", p, exact.get(name)) for name, p in odds.outcomes.items()]
            + [(f"P({p.name} holds)", p.holds, p.exact) for p in odds.properties])


def _end_time(odds) -> str:
    if odds.mean is None:
        return "the mission never ends"
    return (f"end time, if it ends: mean {odds.mean:.2f} s, standard deviation "
            f"{odds.spread:.2f} s; " + ", ".join(f"{k} {v} s" for k, v in odds.quantiles.items()))


def odds_html(odds) -> str:
    """The exact odds (:class:`mcl2pnml.odds.Odds`): each ending's probability (exactly,
    for a small chain), each property's of holding, the end time."""
    rows = [[e(what), e(f"{p:.6f}"), e("" if exact is None else exact)]
            for what, p, exact in _endings(odds)]
    return box(f"odds ({odds.states:,} states, {odds.transitions:,} transitions)",
               table(rows, ("", "probability", "exactly")), f"<p>{e(_end_time(odds))}</p>")


def odds_text(odds) -> str:
    return "\n".join([", ".join(f"{what} = {p:.6f}" for what, p, _ in _endings(odds)),
                      _end_time(odds)])


def _holds(certified) -> str:
    problems = certified.problems
    return ("the certificate holds" if not problems else
            f"the certificate does not hold ({len(problems):,} problems)")


def certified_html(certified) -> str:
    """A certificate and its check (:class:`mcl2pnml.pipeline.Certified`): whether the
    independent checker finds it holds for the net, and what is wrong where not."""
    return box(f"certificate of {certified.certificate.get('mission')} for {certified.net!r}",
               f"<p>{verdict(not certified.problems, _holds(certified))}</p>",
               *(f"<p>{e(p)}</p>" for p in certified.problems))


def certified_text(certified) -> str:
    return "\n".join([_holds(certified), *certified.problems])


#: Each type shown richly, by its module and class (IPython imports neither to register
#: it): each MIME type it is shown in, and how.
SHOWN: dict[tuple[str, str], dict[str, Callable[[Any], str | None]]] = {
    ("mcl2pnml.core.net", "Net"): {"image/svg+xml": net_svg, "text/html": net_html},
    ("mcl2pnml.language.semantics", "Checked"): {"text/html": mission_html,
                                                  "text/plain": mission_text},
    ("mcl2pnml.analysis.report", "Analysis"): {"text/html": analysis_html,
                                               "text/plain": analysis_text},
    ("mcl2pnml.analysis.checking.observers", "Verdict"): {"text/html": verdict_html,
                                                          "text/plain": verdict_text},
    ("mcl2pnml.pipeline", "Verdicts"): {"text/html": verdicts_html, "text/plain": verdicts_text},
    ("mcl2pnml.timed_verdicts", "TimedEnds"): {"text/html": timed_html, "text/plain": timed_text},
    ("mcl2pnml.runtime.engine", "Run"): {"text/html": run_html, "text/plain": run_text},
    ("mcl2pnml.odds", "Odds"): {"text/html": odds_html, "text/plain": odds_text},
    ("mcl2pnml.pipeline", "Certified"): {"text/html": certified_html,
                                         "text/plain": certified_text},
}


def register(shell: Any = None) -> bool:
    """Show our values richly in ``shell`` (None: the running IPython's, if there is one);
    whether there was a shell. :mod:`mcl2pnml` calls it when imported under IPython."""
    if shell is None:
        ipython = sys.modules.get("IPython")
        shell = ipython.get_ipython() if ipython is not None else None
    if shell is None:
        return False
    formatters = shell.display_formatter.formatters
    for (module, name), shown in SHOWN.items():
        for mime, formatter in shown.items():
            if mime == "text/plain":    # IPython's pretty printer hands a printer to write to
                formatter = _printed(formatter)
            formatters[mime].for_type_by_name(module, name, formatter)
    return True


def _printed(text: Callable[[Any], str]) -> Callable[[Any, Any, bool], None]:
    def printer(value: Any, p: Any, cycle: bool) -> None:
        p.text(text(value))
    return printer
