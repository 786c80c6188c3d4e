"""The vehicles a mission can run against, one table entry each (``run --vehicle``).

The paper's missions run first against a simulated vehicle, then a real one
(section 3): each kind of vehicle behind the Architecture Abstraction Layer
(section 2.1) is one :class:`VehicleKind`, chosen by the ``--vehicle``
specification it recognises. Adding a kind of vehicle is one new module
(its adapter, implementing :class:`~mcl2pnml.runtime.aal.Vehicle` or
:class:`~mcl2pnml.runtime.aal.LiveVehicle`) and one entry in
:data:`VEHICLES`; the CLI and the run session take it from here.
"""
from __future__ import annotations

import random
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence

from mcl2pnml.core.settings import SettingError

if TYPE_CHECKING:   # the table names the kinds; building one imports what it needs
    from mcl2pnml.runtime.aal import LiveVehicle, Vehicle
    from mcl2pnml.runtime.link import LinkOptions


@dataclass(frozen=True)
class VehicleKind:
    """One kind of vehicle: how ``--vehicle`` names it and how it is built."""

    #: the name the help and the messages give it
    name: str
    #: does a ``--vehicle`` specification name this kind?
    matches: Callable[[str], bool]
    #: the vehicle, from the specification, the ``--connect`` address, the world file
    #: and the live link's bounds and security (``run --secret``, ``--heartbeat``...)
    build: Callable[[str, "str | None", "Path | None", "LinkOptions"], "Vehicle | LiveVehicle"]
    #: a real vehicle: driven on the wall clock, and a run of it cannot be replayed
    realtime: bool = False
    #: the simulator alone takes a world file
    takes_world: bool = False
    #: the file the vehicle is read from, whose digest a journal keeps (None: none)
    source: Callable[[str], "Path | None"] = lambda spec: None
    #: the primitives it offers, from the specification and the files of simulated
    #: primitives, read without making the vehicle (None: any, as a script answers for any)
    offers: Callable[[str, Sequence[Path]], "frozenset[str] | None"] = \
        lambda spec, files: None


def _simulator(spec: str, connect: str | None, world: Path | None,
               link: LinkOptions) -> Vehicle:
    """The simulator in ``world``; ``sim@SEED`` seeds its noise with SEED instead of the
    world's seed (a campaign's run, flown again alone)."""
    from mcl2pnml.runtime.simulator import AUVSimulator, World   # 20 ms: see VEHICLES
    seed = _sim_seed(spec)
    w = World.load(world) if world else World()
    return AUVSimulator(w if seed is None else replace(w, seed=seed))


def _sim_seed(spec: str) -> int | None:
    """The seed of ``sim@SEED`` (None: ``sim``, the world's), or why it is none."""
    seed = seed_of(spec)
    if spec != "sim" and seed is None:
        raise SettingError("vehicle", f"'{spec[:80]}': the seed after sim@ is a whole number "
                                      "(sim@SEED)")
    return seed


def _simulated(spec: str, files: Sequence[Path]) -> frozenset[str]:
    """The simulator's primitives: the built-ins, the installed packages', the files'."""
    from mcl2pnml.runtime.simprims import installed, load_file   # 22 ms: see VEHICLES
    _sim_seed(spec)
    table = installed()
    for path in files:
        table = load_file(path, table)
    return frozenset(table)


def seed_of(spec: str) -> int | None:
    """The seed after ``@`` in ``sim@SEED`` or ``model:FILE.json@SEED`` (None: none)."""
    _, at, seed = spec.rpartition("@")
    return int(seed) if at and seed.isdigit() and len(seed) <= 18 else None


def is_simulator(spec: str) -> bool:
    """Does ``spec`` name the simulator (``sim``, ``sim@SEED``)?"""
    return spec == "sim" or spec.startswith("sim@")


def _bridge(spec: str, connect: str | None, world: Path | None,
            link: LinkOptions) -> LiveVehicle:
    """The mapped vehicle; its link is checked (address, key file, certificates), not opened."""
    from mcl2pnml.runtime.bridge import MappedVehicle, TcpTransport, VehicleMapping   # 33 ms
    if connect is None:
        raise SettingError("connect", "a bridge needs --connect HOST:PORT (the bridge server "
                                      "on the vehicle)")
    transport = TcpTransport(connect, link)
    return MappedVehicle(VehicleMapping.load(spec[len("bridge:"):]), transport)


def _mavlink(spec: str, connect: str | None, world: Path | None,
             link: LinkOptions) -> LiveVehicle:
    """An autopilot over MAVLink; its address and mapping are checked, not yet connected."""
    # 40 ms with the autopilot's mapping and the simulator's world: see VEHICLES
    from mcl2pnml.runtime.autopilot import AutopilotMapping
    from mcl2pnml.runtime.mavlink import MavlinkVehicle
    from mcl2pnml.runtime.simulator import World
    if connect is None:
        raise SettingError("connect", "an autopilot needs --connect tcp:HOST:PORT (or "
                                      "udp:HOST:PORT, serial:DEVICE[:BAUD]); ArduSub's "
                                      "simulator serves tcp:127.0.0.1:5760")
    if link.secret or link.tls_ca or link.tls_cert or link.tls_key:
        raise SettingError("secret" if link.secret else "tls_ca",
                          "the bridge's link takes a secret and TLS; MAVLink does not")
    path = _mapping_path(spec)
    mapping = AutopilotMapping.load(path) if path else AutopilotMapping.ardusub()
    return MavlinkVehicle(connect, mapping, World.load(world) if world else World(), link)


def _mapping_path(spec: str) -> Path | None:
    return Path(spec[len("mavlink:"):]) if spec.startswith("mavlink:") else None


def _autopilot_offers(spec: str, files: Sequence[Path]) -> frozenset[str]:
    """The primitives the autopilot's mapping binds (ArduSub's, without a mapping file)."""
    from mcl2pnml.runtime.autopilot import AutopilotMapping   # 40 ms: see VEHICLES
    path = _mapping_path(spec)
    return frozenset((AutopilotMapping.load(path) if path else AutopilotMapping.ardusub())
                     .bindings)


def _bridge_offers(spec: str, files: Sequence[Path]) -> frozenset[str]:
    """The primitives the bridge's mapping binds."""
    from mcl2pnml.runtime.bridge import VehicleMapping   # 33 ms: see VEHICLES
    return frozenset(VehicleMapping.load(spec[len("bridge:"):]).bindings)


def _model_spec(spec: str) -> tuple[Path, int]:
    """``model:FILE.json`` or ``model:FILE.json@SEED``: the model's file and the seed."""
    seed = seed_of(spec)
    if seed is not None:
        return Path(spec[len("model:"):].rpartition("@")[0]), seed
    return Path(spec[len("model:"):]), 0


def _model(spec: str, connect: str | None, world: Path | None,
           link: LinkOptions) -> Vehicle:
    from mcl2pnml.runtime.vehicle_model import Draw, ModelVehicle, VehicleModel   # 35 ms
    path, seed = _model_spec(spec)
    return ModelVehicle(VehicleModel.load(path), Draw(random.Random(seed)))


def _script(spec: str, connect: str | None, world: Path | None,
            link: LinkOptions) -> Vehicle:
    from mcl2pnml.runtime.aal import ScriptedVehicle   # 22 ms: see VEHICLES
    return ScriptedVehicle.load(spec)


def _any(build: Callable) -> Callable[[str, Sequence[Path]], None]:
    """The offer of a vehicle that answers for any primitive (a script, a model): its file
    read, so that a fault in it is said where it is, and no primitive refused."""
    def offers(spec: str, files: Sequence[Path]) -> None:
        build(spec, None, None, None)
    return offers


# (Each kind's module is imported when a vehicle of that kind is made, 20 to 40 ms each,
# measured with python -X importtime: the CLI imports this table at its start, for
# --vehicle's help.)
#: Every kind of vehicle, the first that matches wins: the kinematic AUV
#: simulator, a real vehicle through a mapping file and a bridge server, an
#: autopilot over MAVLink (ArduSub, docs/ardusub.md), a vehicle model drawing its
#: answers (docs/odds.md; the seed after @ replays a run), and (whatever else is
#: given) a vehicle script (docs/running.md).
VEHICLES: tuple[VehicleKind, ...] = (
    VehicleKind("sim[@SEED]", is_simulator, _simulator, takes_world=True, offers=_simulated),
    VehicleKind("bridge:MAPPING.json", lambda spec: spec.startswith("bridge:"), _bridge,
                realtime=True, offers=_bridge_offers),
    VehicleKind("mavlink[:MAPPING.json]",
                lambda spec: spec == "mavlink" or spec.startswith("mavlink:"), _mavlink,
                realtime=True, takes_world=True, source=_mapping_path,
                offers=_autopilot_offers),
    VehicleKind("model:MODEL.json[@SEED]", lambda spec: spec.startswith("model:"), _model,
                source=lambda spec: _model_spec(spec)[0], offers=_any(_model)),
    VehicleKind("SCRIPT.json", lambda spec: True, _script, source=Path, offers=_any(_script)),
)


def kind_of(spec: str) -> VehicleKind:
    """The kind of vehicle ``spec`` names (the script, when nothing else matches)."""
    return next(kind for kind in VEHICLES if kind.matches(spec))


def refuse_sim_primitives(kind: VehicleKind, files: Sequence[Path]) -> None:
    """Files of simulated primitives are for a vehicle that simulates (sim, mavlink)."""
    if files and not kind.takes_world:
        raise SettingError("sim_primitives", "simulated primitives are for the simulator "
                                             "(--vehicle sim)")


def offered(spec: str, sim_primitives: Sequence[Path] = ()) -> frozenset[str] | None:
    """The primitives the vehicle ``spec`` (as ``run --vehicle`` names it) offers, with the
    simulated primitives of the files ``sim_primitives``; None when it answers for any (a
    script, a vehicle model). Read from its table or its files, without making the
    vehicle: no link is opened, no world read (``check --vehicle``)."""
    kind = kind_of(spec)
    refuse_sim_primitives(kind, sim_primitives)
    return kind.offers(spec, sim_primitives)
