"""``mcl2pnml compile MISSION``: the mission's net written in a format of the table, and
what goes beside it (the contest's queries, the properties in its categories, a
timed-arc net's queries)."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mcl2pnml import pipeline
from mcl2pnml.commands.common import FORMAT, MISSION_SIZE, PROPERTIES_SIZE, \
    properties_file, warned
from mcl2pnml.core.bounds import MAX_PROPERTY_ATOMS
from mcl2pnml.core.files import check_outputs
from mcl2pnml.core.net import Net
from mcl2pnml.core.progress import Notes
from mcl2pnml.core.settings import SettingError
from mcl2pnml.core.timing import Assumptions, seconds_setting
from mcl2pnml.io.formats import FORMATS
from mcl2pnml.io.mccquery import TOOLS as QUERY_TOOLS


@dataclass(frozen=True)
class CompileOptions:
    """``compile``'s settings, by the names of its options (``--help`` says each)."""

    #: where the net goes (None: MISSION with the format's suffix)
    output: Path | None = None
    fmt: str = FORMAT
    #: node positions: auto, dot, layers or none (:data:`mcl2pnml.view.layout.ENGINES`)
    layout_engine: str = pipeline.LAYOUT
    #: a drawing's calls drawn open: names, comma-separated, or "all"
    expand: str = ""
    #: the contest's queries of the mission, in this file
    queries: Path | None = None
    #: how the queries write a deadlock: the first of :data:`mcl2pnml.io.mccquery.TOOLS`,
    #: the tool its writers write for unless told
    tool: str = next(iter(QUERY_TOOLS))
    properties: str | None = None
    max_memory: str | None = None
    #: a timed-arc net's assumptions, as written (None: :class:`Assumptions`' own)
    ack_within: str | None = None
    report_gap: str | None = None
    max_props_size: str = PROPERTIES_SIZE
    max_atoms: int = MAX_PROPERTY_ATOMS
    strict: bool = False
    max_mission_size: str = MISSION_SIZE


@dataclass(frozen=True)
class CompileOutcome:
    """The net compiled and the files written (the net's first); ``compile`` prints nothing
    on standard output, what it wrote is said on standard error as it writes it."""

    net: Net
    written: tuple[Path, ...]

    def lines(self) -> list[str]:
        return []

    def as_json(self) -> dict[str, Any]:
        return {"net": self.net.name, "written": [str(p) for p in self.written]}


def compile_timing(fmt: str, ack_within: str | None, report_gap: str | None
                   ) -> Assumptions | None:
    """What the vehicle is assumed to do, for a format that says it (tapn; supervisor steps
    urgent, not first: the timed-arc tools' semantics); refused for any other."""
    if fmt == "tapn":
        return Assumptions(
            ack_within=Assumptions.ack_within if ack_within is None
            else seconds_setting(ack_within, "ack_within"),
            report_gap=Assumptions.report_gap if report_gap is None
            else seconds_setting(report_gap, "report_gap"), priority=False)
    if ack_within is not None or report_gap is not None:
        raise SettingError("ack_within" if ack_within is not None else "report_gap",
                           "only a timed-arc net (--format tapn) says what the vehicle is "
                           f"assumed to do, not {fmt}")
    return None


def compile_mission(mission: Path, options: CompileOptions = CompileOptions(), *,
                    notes: Notes | None = None) -> CompileOutcome:
    """``mcl2pnml compile`` with ``options``: the net and what goes beside it, every output
    checked against the inputs and each other before anything is written; each line said
    to ``notes``."""
    # the contest's and verifydtapn's query writers: 25 ms each at start-up; only compile
    from mcl2pnml.io.mccquery import property_query_files
    from mcl2pnml.io.tapn import query_paths
    o, notes = options, Notes() if notes is None else notes
    output = o.output or mission.with_suffix(FORMATS[o.fmt].suffixes[0])
    if o.queries is not None and o.queries.resolve() == output.resolve():
        raise SettingError("queries", "the queries go in a file of their own, not the net's")
    if o.expand and "drawing" not in FORMATS[o.fmt].options:
        raise SettingError("expand", f"only a drawing has boxes to open, not {o.fmt}: "
                                     "--format svg, png or dot")
    timing = compile_timing(o.fmt, o.ack_within, o.report_gap)
    stem = output.with_suffix("") if output.suffix else output
    extra = None if o.properties is None else properties_file(mission, o.properties)
    inputs = [("the mission", mission), ("the properties file (--properties)", extra)]
    outputs = [("output", output), ("queries", o.queries)]
    check_outputs(outputs + [("properties", path) for path in
                             (property_query_files(stem).values() if o.properties is not None
                              else ())], inputs)
    # its warnings before anything is written
    checked = pipeline.check_file(mission, o.max_mission_size)
    warned(mission, checked, o.strict, notes)
    net, props = _compiled_with_properties(mission, checked, extra, o)
    if timing is not None:   # the queries beside the net: none of them an input
        check_outputs(outputs + [("output", path) for path in
                                 query_paths(net, output, timing, props)],
                      inputs)
    opened = None if o.expand == "all" else expand_names(o.expand)
    labels = pipeline.call_labels(checked) if "drawing" in FORMATS[o.fmt].options else None
    pipeline.save_net(net, output, o.fmt, layout=o.layout_engine, title=mission.name,
                      mission=True, expand=opened, timing=timing, note=notes, labels=labels)
    notes(f"wrote {output}: {net.summary()}")
    beside = _saved_beside(net, output, timing, o.queries, o.tool, props, stem, notes)
    return CompileOutcome(net, (output, *beside))


def expand_names(text: str) -> tuple[str, ...]:
    """The calls ``--expand`` names, split at its commas outside parentheses: a call as MCL
    writes it (``monitor(Survey(), FindCross())``) is one name."""
    names, depth, start = [], 0, 0
    for k, c in enumerate(text + ","):
        depth += (c == "(") - (c == ")")
        if c == "," and depth <= 0:
            names.append(text[start:k].strip())
            start = k + 1
    return tuple(n for n in names if n)


def _compiled_with_properties(mission: Path, checked, extra: Path | None, o: CompileOptions):
    """The compiled net, and with ``--properties`` the properties, at least one."""
    if o.properties is None:
        return pipeline.compile_file(mission, max_memory=o.max_memory, checked=checked), ()
    net, props = pipeline.properties_of(mission, extra=extra, max_memory=o.max_memory,
                                        max_size=o.max_props_size, max_atoms=o.max_atoms,
                                        checked=checked)
    if not props:
        raise SettingError("properties", f"{mission} declares no property, and there is no "
                                         f"{o.properties or mission.with_suffix('.props')} "
                                         "beside it")
    return net, props


def _saved_beside(net: Net, output: Path, timing, queries: Path | None, tool: str, props,
                  stem: Path, notes: Notes) -> list[Path]:
    """What ``compile`` writes beside the net: a timed-arc net's queries, the Model
    Checking Contest's queries, the properties in its categories."""
    # verifydtapn's query writer: 25 ms at start-up; only compile
    from mcl2pnml.io.tapn import write_queries
    written = []
    if timing is not None:   # every run ends, no stall...
        notes(f"timed semantics: {timing.words()}")
        for path, query, bound in write_queries(net, output, timing, props):
            notes(f"wrote {path}: {query.description} (verifydtapn -k {bound} {output} "
                  f"{path})")
            written.append(Path(path))
    if queries is not None:
        saved = pipeline.save_queries(net, queries, tool)
        notes(f"wrote {queries}: {', '.join(p.id for p in saved)} (for {tool})")
        written.append(queries)
    for path, qs in pipeline.save_property_queries(props, stem) if props else ():
        notes(f"wrote {path}: {len(qs)} {'query' if len(qs) == 1 else 'queries'}")
        written.append(Path(path))
    return written
