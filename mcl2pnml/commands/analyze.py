"""``mcl2pnml analyze FILE``: a net (or a mission, compiled first) analysed, its properties
checked, their counterexamples explained; one call that the CLI, the tests and a notebook
share, so that none of them decides anything again.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mcl2pnml import pipeline
from mcl2pnml.analysis.statespace.explorers import CHOICES as EXPLORER_CHOICES
from mcl2pnml.commands.common import CERTIFICATE_SIZE, MISSION_SIZE, PROPERTIES_SIZE, \
    properties_file
from mcl2pnml.commands.witnesses import (save_witness, verdicts_json, witness_files,
                                         witness_text, witnesses, make_folder)
from mcl2pnml.core.bounds import MAX_PROPERTY_ATOMS, MAX_STATES
from mcl2pnml.core.files import check_outputs
from mcl2pnml.core.net import Net
from mcl2pnml.core.progress import Notes, ProgressMeter
from mcl2pnml.core.settings import SettingError
from mcl2pnml.core.timing import Assumptions, seconds_setting
from mcl2pnml.core.vocabulary import CERTIFIED

if TYPE_CHECKING:   # for the annotations only: the analysis loads numpy
    from mcl2pnml.analysis.report import Analysis, CertifiedFacts
    from mcl2pnml.timed_verdicts import TimedEnds

#: How many failing properties ``analyze`` explains, unless told (``--max-counterexamples``):
#: each costs its replay on both engines, at times a search of the engines' own runs, and
#: four files, so that thousands of failing properties would take minutes to hours.
MAX_COUNTEREXAMPLES = 100


@dataclass(frozen=True)
class AnalyzeOptions:
    """``analyze``'s settings, by the names of its options (``--help`` says each)."""

    #: start from this marking (``P,Q*2``) instead of the file's
    initial: str | None = None
    #: the reachable markings only (no invariants)
    state_space: bool = False
    #: the minimal semi-positive invariants, siphons and traps even where the state space
    #: decides every property
    structure: bool = False
    max_states: int = MAX_STATES
    #: a name of :data:`mcl2pnml.analysis.statespace.explorers.EXPLORERS`, or auto (the
    #: first of its choices: the fastest for the net's kind and size)
    explorer: str = EXPLORER_CHOICES[0]
    #: the memory budget as written (4G, 500M); None: half the memory free
    max_memory: str | None = None
    #: ``--properties [FILE]``: None, or "" for MISSION.props, or FILE
    properties: str | None = None
    #: explore even where a certificate beside the file proves the behaviour
    explore: bool = False
    max_cert: str = CERTIFICATE_SIZE
    #: the folder of the failing properties' files
    counterexamples: Path | None = None
    #: explain each failing property in the mission's terms and replay it
    explain: bool = False
    max_counterexamples: int = MAX_COUNTEREXAMPLES
    #: partial-order reduction (untimed properties of a mission proven 1-safe)
    stubborn: bool = False
    #: the verdicts in time (None: for a mission's properties, unless --initial)
    timed: bool | None = None
    #: the vehicle's assumptions of the timed verdicts, as written (docs/time.md)
    ack_within: str = str(Assumptions.ack_within)
    report_gap: str = str(Assumptions.report_gap)
    fair_reports: bool = False
    urgency_only: bool = False
    max_props_size: str = PROPERTIES_SIZE
    max_atoms: int = MAX_PROPERTY_ATOMS
    net_id: str | None = None
    lenient: bool = False
    max_mission_size: str = MISSION_SIZE


@dataclass(frozen=True)
class AnalyzeOutcome:
    """What one :func:`analyze` found and did, for the CLI to print and a test or a
    notebook to read.

    ``result``: the analysis (:class:`mcl2pnml.analysis.report.Analysis`, with a
    certificate's facts where one beside the file holds; None for a timed one);
    ``verdicts``: the properties' (None without ``properties``); ``witnesses``: beside
    them, each failing one's explanation (:func:`~mcl2pnml.commands.witnesses.witnesses`),
    None for those not explained, and None in all when none was asked for; ``timed``: the
    timed ends (:func:`mcl2pnml.pipeline.timed_ends`) of a timed analysis; ``messages``:
    what was said on the way, standard error's, in order; ``written``: the counterexample
    files; ``status``: the exit status (0 ok, 1 a property fails, 3 a partial answer, a
    property unknown, or the ends undecided).
    """

    result: Analysis | None
    verdicts: tuple | None = None
    witnesses: tuple | None = None
    timed: TimedEnds | None = None
    messages: tuple[str, ...] = ()
    written: tuple[Path, ...] = ()
    status: int = 0
    #: The text says, under a counterexample not explained, how to ask (``--explain``):
    #: no explanation was asked for, and one could be (the run starts at the mission's start).
    hint: bool = False

    def as_json(self) -> dict[str, Any]:
        """The object ``analyze --json`` prints."""
        out = {} if self.result is None else self.result.as_json()
        if self.verdicts is not None:
            out["properties"] = verdicts_json(self.verdicts, self.witnesses)
        if self.timed is not None:
            out["timed"] = self.timed.as_json()
        return out

    def lines(self) -> list[str]:
        """What ``analyze`` prints: the analysis (or the timed ends), then each verdict."""
        out = ["\n".join(self.timed.lines()) if self.timed is not None
               else self.result.text()]
        for k, v in enumerate(self.verdicts or ()):
            out += witness_text(v, self.witnesses[k] if self.witnesses else None, self.hint)
        return out


def analyze(file: str | Path, options: AnalyzeOptions = AnalyzeOptions(), *,
            notes: Notes | None = None, progress: ProgressMeter | None = None
            ) -> AnalyzeOutcome:
    """``mcl2pnml analyze FILE`` with ``options``.

    It decides what the command does: timed or not (a mission's properties are about
    the runs it has, in time, unless ``timed`` says otherwise), a certificate beside the
    file taken instead of exploring, the properties checked, and the counterexamples
    explained (in the mission's terms, replayed on both engines: the costly part) only
    when ``explain`` or ``counterexamples`` asks, up to ``max_counterexamples``, and
    written in the folder ``counterexamples``. Each message is said to ``notes`` when it
    is said and kept in the outcome; ``progress`` is shown the exploration's. An input
    or a setting that does not fit raises the project's errors
    (:class:`~mcl2pnml.core.settings.SettingError`,
    :class:`~mcl2pnml.core.errors.Mcl2PnmlError`) before anything is explored or written.
    """
    o, file = options, Path(file)
    notes = Notes() if notes is None else notes
    said = len(notes.said)
    folder = o.counterexamples
    _explanations_possible(o)
    # a mission's properties are about the runs it has: in time
    timed = o.timed if o.timed is not None else \
        o.properties is not None and file.suffix == ".mcl" and o.initial is None
    assumptions = timed_assumptions(timed, o)
    if timed and o.initial is not None:
        raise SettingError("timed", "a timed verdict starts the mission from its start (its "
                                    "clocks at 0): leave out --initial")
    if o.stubborn and (timed or o.properties is None):
        raise SettingError("stubborn", "the reduction is of the untimed check of properties: "
                                       "add --untimed --properties")
    net, props, extra = _analyzed_net(file, o)
    if folder is not None:      # before the analysis: a folder that cannot be is said at once
        _counterexample_folder(file, folder, props, extra)
    start = None if o.initial is None else pipeline.parse_marking(o.initial, net, str(file))
    result = ends = verdicts = None
    if timed:   # the runs in time: the timed answers alone, the untimed ones with --untimed
        ends = pipeline.timed_ends(net, assumptions, o.max_states, o.max_memory)
        if ends.cycle and file.suffix == ".mcl":   # the cycle told by the mission's calls
            ends = ends.placed(pipeline.call_sites(pipeline.check_file(file,
                                                                       o.max_mission_size)))
        if props is not None:
            verdicts = pipeline.check_properties_timed(net, props, assumptions, o.max_states,
                                                       o.max_memory)
    else:
        result = _explored(file, net, start, notes, progress, o)
        if progress is not None:
            progress.end()
        if props is not None:
            verdicts = _untimed_verdicts(file, net, props, start, o)
            result = replace(result, stubborn=True) if o.stubborn else result
    asked = o.explain or folder is not None
    explained = None
    if verdicts is not None and asked:
        explained = witnesses(file, net, verdicts, o.max_counterexamples,
                              assumptions if timed else None, o.max_mission_size)
        _say_left_out(verdicts, explained, notes)
    written = [] if folder is None or explained is None else \
        _save_witnesses(folder, file, verdicts, explained, notes, o.max_mission_size)
    return AnalyzeOutcome(
        result, None if verdicts is None else tuple(verdicts),
        None if explained is None else tuple(explained), ends, tuple(notes.said[said:]),
        tuple(written), _analyze_status(result, verdicts, ends),
        hint=not asked and start is None)


def _untimed_verdicts(file: Path, net: Net, props, start, o: AnalyzeOptions) -> list:
    """The properties' verdicts on the net's runs; with ``stubborn`` the reduction, once
    the mission's certificate proves the net 1-safe (from its own start only: another
    start needs a P-invariant to), or refused saying why."""
    # the on-the-fly checker: numpy, 0.1 s at start-up; only a check of properties
    from mcl2pnml.analysis.checking.on_the_fly import NotProvenSafe
    safe = o.stubborn and start is None and pipeline.proven_safe_by_certificate(
        file, net, o.max_mission_size)
    try:
        return pipeline.check_properties(net if start is None else net.with_initial(start),
                                         props, o.max_states, stubborn=o.stubborn, safe=safe)
    except NotProvenSafe as e:
        raise SettingError("stubborn", f"{e}: the reduction could skip the firing that "
                                       "shows a second token") from None


def _explanations_possible(o: AnalyzeOptions) -> None:
    """Refuse an explanation asked for where there can be none: without properties, or
    from another start than the mission's (the mission's terms and the replay start
    there)."""
    for setting, asked in (("counterexamples", o.counterexamples is not None),
                           ("explain", o.explain)):
        if asked and o.properties is None:
            raise SettingError(setting, "counterexamples are of properties: add --properties")
        if asked and o.initial is not None:
            raise SettingError(setting, "a replay starts the mission from its start: leave "
                                        "out --initial")


def _analyzed_net(file: Path, o: AnalyzeOptions) -> tuple[Net, tuple | None, Path | None]:
    """The net ``analyze`` reads, and with ``--properties`` the properties and their side
    file, read, counted and checked before the analysis, which they may make long. A net
    read with ``lenient`` is explored: a certificate beside it is never taken for it."""
    if o.properties is None:
        return pipeline.load_net(file, o.net_id, o.max_memory, o.lenient,
                                 o.max_mission_size), None, None
    if o.lenient:
        raise SettingError("lenient", "properties are a mission's, compiled, not read as "
                                      "PNML; leave out --lenient")
    if file.suffix != ".mcl":
        raise SettingError("properties", "properties are a mission's (an .mcl file)")
    if o.net_id is not None:
        raise SettingError("net_id", "properties are a mission's, which compiles to one net; "
                                     "leave out --net")
    extra = properties_file(file, o.properties)
    net, props = pipeline.properties_of(file, extra=extra, max_memory=o.max_memory,
                                        max_size=o.max_props_size, max_atoms=o.max_atoms,
                                        max_mission_size=o.max_mission_size)
    return net, props, extra


def _counterexample_folder(file: Path, folder: Path, props, extra: Path | None) -> None:
    """The folder of ``--counterexamples`` made, once no property's file in it is found
    to be an input: refused before anything is written."""
    inputs = [("the mission", file), ("the properties file (--properties)", extra),
              ("the certificate beside it", pipeline.certificate_beside(file))]
    check_outputs([("counterexamples", path) for prop in props for path in
                   witness_files(folder, prop.name).values()], inputs,
                  "give another folder, or rename the property")
    make_folder(folder)


def _explored(file: Path, net: Net, start, notes: Notes, progress: ProgressMeter | None,
              o: AnalyzeOptions) -> Analysis:
    """The untimed analysis of ``net``; a certificate beside the file, if it holds for the
    net and the run starts at M0, proves the behaviour without exploring
    (:mod:`mcl2pnml.certify`), and ``explore`` (or ``lenient``) explores anyway."""
    beside = pipeline.certificate_beside(file)
    certified = None
    if beside.is_file() and start is None and not (o.explore or o.lenient):
        certified, problems = certified_facts(net, beside, o.max_cert)
        if problems:
            notes(f"{beside}: the certificate does not hold for this net ({problems[0]}"
                  + (f"; {len(problems) - 1} more" if len(problems) > 1 else "")
                  + "): exploring instead")
    result = pipeline.analyze(net, start, state_space_only=o.state_space, progress=progress,
                              explore_states=certified is None, max_states=o.max_states,
                              explorer=o.explorer, max_memory=o.max_memory,
                              enumerate_all=o.structure)
    if certified is not None:
        result = result.certified(certified)
        notes(f"{beside}: the certificate holds: {', '.join(CERTIFIED)}, proven from the "
              "mission's parts; the markings were not explored (--explore to explore them)")
    return result


def certified_facts(net: Net, cert_path: Path, max_size: int | str
                    ) -> tuple[CertifiedFacts | None, list[str]]:
    """The certificate beside a net, as ``analyze`` takes it, if it holds for ``net``
    (:meth:`mcl2pnml.analysis.report.Analysis.certified`); else None and what the checker
    found. The ends are the checker's: the certificate must say exactly those to hold."""
    from mcl2pnml.analysis.report import CertifiedFacts   # numpy, 0.1 s: only to analyse
    cert = pipeline.load_certificate(cert_path, max_size)
    problems = pipeline.check_certificate(net, cert, shaped=True)
    if problems:
        return None, problems
    return CertifiedFacts(str(cert_path), cert["conclusion"]["ends"]), []


def _say_left_out(verdicts, explained, notes: Notes) -> None:
    failing = sum(v.shape is not None for v in verdicts)
    done = sum(w is not None for w in explained)
    if done < failing:
        notes(f"counterexamples of {failing - done:,} of the {failing:,} failing properties "
              f"left out: the first {done:,} are explained (--max-counterexamples to raise "
              "the limit)")


def _save_witnesses(folder: Path, file: Path, verdicts, explained, notes: Notes,
                    max_mission_size: int | str | None = None) -> list[Path]:
    """Each explained counterexample's files (:func:`save_witness`); one page content for
    all, since a run does not change the mission's drawing."""
    written: list[Path] = []
    if not any(w is not None for w in explained):
        return written
    page = pipeline.show_nets(str(file), with_run=True, max_mission_size=max_mission_size)
    for v, w in zip(verdicts, explained):
        if w is not None:
            for path in save_witness(folder, file, v, w, page):
                notes(f"wrote {path}")
                written.append(path)
    return written


def _analyze_status(result, verdicts, ends) -> int:
    statuses = {v.status.value for v in verdicts or ()}
    if "fails" in statuses:
        return 1
    undecided = ends is not None and ends.always_ends is None
    partial = result is not None and result.partial is not None
    return 3 if partial or "unknown" in statuses or undecided else 0


def timed_assumptions(timed: bool, o: AnalyzeOptions = AnalyzeOptions()) -> Assumptions:
    """The vehicle's assumptions of ``--timed`` (docs/time.md), from the settings as
    written; one given without ``timed`` is refused."""
    given = [name for name, said in (("ack_within", o.ack_within != DEFAULT.ack_within),
                                     ("report_gap", o.report_gap != DEFAULT.report_gap),
                                     ("fair_reports", o.fair_reports),
                                     ("urgency_only", o.urgency_only))
             if said]
    if given and not timed:
        raise SettingError(given[0], "an assumption of the timed verdicts: add --timed")
    return Assumptions(seconds_setting(o.ack_within, "ack_within"),
                       seconds_setting(o.report_gap, "report_gap"), o.fair_reports,
                       not o.urgency_only)


#: The settings left as they are.
DEFAULT = AnalyzeOptions()
