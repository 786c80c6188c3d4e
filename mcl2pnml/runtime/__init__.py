"""The runtime: missions run against a vehicle (the paper's sections 2.1 and 3).

Owns the Architecture Abstraction Layer (actions, events, the vehicle
interface), the engine interface and the loops that drive an engine, the
Petri-net executor, the reference engine, the simulated AUV, the bridge to
real vehicles, the run log, the journal, and the run session that wires a
vehicle, an engine, the log and the journal together.

May import: :mod:`mcl2pnml.core`; the reference engine, which interprets
MCL directly, also :mod:`mcl2pnml.language`.
"""
