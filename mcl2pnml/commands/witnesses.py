"""A failing property's counterexample as ``analyze`` tells it: explained in the mission's
terms and replayed (:mod:`mcl2pnml.counterexample`), printed, in ``--json``, and in files.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from mcl2pnml import pipeline
from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import atomic_write_text
from mcl2pnml.core.net import Net
from mcl2pnml.core.timing import Assumptions


def witnesses(mission: Path, net: Net, verdicts, most: int | None = None,
              timing: Assumptions | None = None,
              max_mission_size: int | str | None = None) -> list:
    """For each verdict, its :class:`~mcl2pnml.counterexample.Witness` when it fails
    (the counterexample in the mission's terms, the vehicle script that replays a violation
    on both engines, or why none does), else None. ``net`` is ``mission``'s compiled net.
    ``most``: only the first ``most`` failing verdicts are explained, the others' are None,
    and cost nothing."""
    # the replay's engines and vehicles: 30 ms at start-up; only an explained property
    from mcl2pnml.counterexample import witness
    checked = pipeline.check_file(mission, max_mission_size)
    out, left = [], most
    for v in verdicts:
        if v.shape is None or left == 0:
            out.append(None)
            continue
        out.append(witness(net, checked, v.property, v.transitions, shape=v.shape.value,
                           loop=v.loop, timing=timing))
        left = None if left is None else left - 1
    return out


def verdicts_json(verdicts, witnesses=None) -> list[dict[str, Any]]:
    """Verdicts as ``analyze --json`` prints them: each failing one with its counterexample
    as the checker found it, ``explained`` saying whether its witness was computed (given
    here, ``analyze --explain``), and the witness's parts when it was."""
    out = []
    for k, v in enumerate(verdicts):
        w = witnesses[k] if witnesses else None
        cex = None if v.shape is None else {
            "shape": v.shape.value, "transitions": list(v.transitions),
            "loop": v.loop, "markings": [dict(m) for m in v.markings],
            "explained": w is not None}
        if cex is not None and w is not None:
            cex["mission"] = w.run.lines()
            cex["vehicle_script"] = None if w.replayed is None else w.replayed.script
            cex["replayed"] = None if w.replayed is None else {
                "same_run": w.replayed is w.run, "mission": w.replayed.lines(),
                "transitions": [s.transition for s in w.replayed.steps],
                "detail": w.replay.detail}
            cex["why_not"] = w.why_not
        out.append({"name": v.property.name, "text": v.property.text,
                    "location": v.property.location.prefix() if v.property.location else None,
                    "status": v.status.value, "states": v.states, "reason": v.reason,
                    "counterexample": cex})
    return out


#: What ``analyze`` says under a counterexample it did not explain, unasked.
EXPLAIN_HINT = ("  (--explain: this run in the mission's terms, and a vehicle script that "
                "replays it on both engines)")


def witness_text(v, w, hint: bool = False) -> list[str]:
    """A verdict as ``analyze --properties`` prints it: the firing sequence, the same run in
    the mission's terms, and the vehicle script that replays a violation, or why none does;
    without a witness, ``hint``: how to ask for it (:data:`EXPLAIN_HINT`)."""
    where = v.property.location.prefix() if v.property.location else "-"
    line = f"property {v.property.name} ({where}): {v.status.value}"
    if v.reason:
        line += f" ({v.reason}, {v.states:,} states)"
    out = [line]
    if v.shape is None:
        return out
    out.append(f"  counterexample ({v.shape.value}):")
    for k, t in enumerate(v.transitions, 1):
        loop = "  <- the cycle starts here" if v.loop is not None and k == v.loop + 1 else ""
        out.append(f"  {k:4}. {t}{loop}")
    if v.loop is not None:
        out.append(f"  then again from step {v.loop + 1}, forever")
    if w is None:
        return out + [EXPLAIN_HINT] * hint
    out.append("  in the mission's terms (step numbers in brackets):")
    out += [f"  {line}" for line in w.run.lines()]
    if w.replayed is not None and w.replayed is not w.run:
        out.append(f"  a vehicle script cannot lead the engines along it: {w.why_not}")
        out.append(f"  a run the engines take that violates it too ({w.replayed.shape}, "
                   f"{len(w.replayed.steps)} firings):")
        out += [f"  {line}" for line in w.replayed.lines()]
    if w.replayed is not None:
        out.append("  vehicle script (run --vehicle; both engines reach the violation): "
                   + json.dumps(w.replayed.script))
        if w.replayed.loop is not None:
            from mcl2pnml.counterexample import CYCLE_REPEATS   # as witness() above
            out.append(f"  (the cycle's replies {CYCLE_REPEATS} times over: a vehicle that goes "
                       "on answering so keeps the mission in the cycle forever)")
    else:
        out.append(f"  no vehicle script replays it: {w.why_not}")
    return out


def make_folder(folder: Path) -> Path:
    """``folder`` made if missing (with its parents), or one error naming it."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise Mcl2PnmlError(f"cannot make the folder: {e.strerror or e}",
                            Location(str(folder))) from None
    return folder


def witness_files(folder: Path, name: str) -> dict[str, Path]:
    """The files :func:`save_witness` may write for the property ``name`` in ``folder``,
    by what they hold: every one, so that they can be checked against the inputs before
    anything is written."""
    return {kind: folder / f"{name}.{suffix}" for kind, suffix in
            (("text", "txt"), ("script", "vehicle.json"), ("log", "log"), ("page", "html"))}


def save_witness(folder: Path, mission: Path, v, w,
                 shown: pipeline.Shown | None = None) -> list[Path]:
    """A failing property's files in ``folder``: NAME.txt (:func:`witness_text`),
    NAME.vehicle.json (the script, if any), NAME.log (the run as ``run --log`` writes it:
    the replayed run if any, else the counterexample) and NAME.html (``show``'s page
    following that run step by step). ``shown``: the mission's page content
    (:func:`~mcl2pnml.pipeline.show_nets`), when the caller writes several and has it
    already."""
    make_folder(folder)
    files = witness_files(folder, v.property.name)
    written = [files["text"]]
    atomic_write_text(files["text"], "\n".join(witness_text(v, w)) + "\n")
    run = w.replayed or w.run
    if w.replayed is not None:
        written.append(files["script"])
        atomic_write_text(files["script"], w.replayed.script_json())
    atomic_write_text(files["log"], "".join(json.dumps(e) + "\n" for e in run.run_log()))
    pipeline.save_show_page(files["page"], shown or pipeline.show_nets(str(mission), with_run=True),
                            files["log"])
    return [*written, files["log"], files["page"]]


