"""What several commands share: the sizes they read within, the side file of properties,
a mission's warnings."""
from __future__ import annotations

from pathlib import Path

from mcl2pnml import pipeline
from mcl2pnml.core.bounds import (MAX_CERTIFICATE_SIZE, MAX_MISSION_SIZE,
                                  MAX_PROPERTIES_SIZE)
from mcl2pnml.core.errors import Mcl2PnmlError, visible
from mcl2pnml.core.progress import Notes, ProgressMeter, RunsBar
from mcl2pnml.core.settings import SettingError, UsageProblem
from mcl2pnml.core.version import __version__ as VERSION
from mcl2pnml.core.vocabulary import counted
from mcl2pnml.runtime.options import RunOptions

#: What the command line takes of the layers below, through the commands alone: the
#: errors it shows, how it quotes what a user typed, what a command says on its way.
__all__ = ["Mcl2PnmlError", "SettingError", "UsageProblem", "Notes",
           "ProgressMeter", "RunsBar", "VERSION", "visible", "MISSION_SIZE", "PROPERTIES_SIZE", "CERTIFICATE_SIZE",
           "FORMAT", "ENGINE", "size_text", "properties_file", "mission_net", "warned"]


def size_text(size: int) -> str:
    """A size of whole MiB as a size option writes it: ``16M``."""
    return f"{size >> 20}M"


#: The sizes as the options write them (``--max-mission-size 16M``...).
MISSION_SIZE = size_text(MAX_MISSION_SIZE)
PROPERTIES_SIZE = size_text(MAX_PROPERTIES_SIZE)
CERTIFICATE_SIZE = size_text(MAX_CERTIFICATE_SIZE)
#: The format a net is written in unless told (``--format``): the facade's.
FORMAT = pipeline.FORMAT
#: The engine a mission runs on unless told (``--engine``): the executor on its net.
ENGINE = RunOptions.engine


def properties_file(mission: Path, properties: str) -> Path | None:
    """The side file of ``--properties [FILE]``: FILE, else MISSION.props if there is one."""
    extra = Path(properties) if properties else mission.with_suffix(".props")
    if properties and not extra.is_file():
        raise SettingError("properties", f"no file '{properties}'")
    return extra if extra.is_file() else None


def mission_net(mission: Path, extra: Path | None, options) -> tuple:
    """The mission's compiled net, and its properties if ``options`` asks for them (those it
    declares, then ``extra``'s), read within the options' bounds."""
    o = options
    if o.properties is None:
        return pipeline.compile_checked(pipeline.check_file(mission, o.max_mission_size)), ()
    return pipeline.properties_of(mission, extra=extra, max_size=o.max_props_size,
                                  max_atoms=o.max_atoms, max_mission_size=o.max_mission_size)


def warned(mission: Path, checked, strict: bool, notes: Notes) -> list:
    """The mission's warnings (:func:`mcl2pnml.pipeline.warnings_of`), each line said; with
    ``strict``, one or more refuse the mission (exit 2), before anything is written."""
    from mcl2pnml.language.lint import shown   # lark, 40 ms: only a mission read
    found = pipeline.warnings_of(checked)
    for line in shown(found):
        notes(line)
    if strict and found:
        raise Mcl2PnmlError(f"{mission}: {counted(len(found), 'warning')}, which --strict makes "
                            "errors (fix them, or acknowledge one that is meant with "
                            "// mcl: allow CODE because ... on the line before it)")
    return found
