"""Textbook nets whose answers are known by hand, built to any size: the tests check
the analyses on them, the benchmarks time the explorers on them.

* :func:`cycle`: one marked circuit of ``n`` places, the simplest live and
  safe marked graph (Murata, "Petri nets: properties, analysis and
  applications", Proc. IEEE 77(4), 1989): one P-invariant over every
  place, one T-invariant over every transition, ``n`` markings.
* :func:`cycles`: ``k`` independent 4-place circuits, one token each:
  ``4**k`` markings, the state explosion of concurrent components in its
  purest form (Valmari, "The state explosion problem", Lectures on Petri
  Nets I, LNCS 1491, 1998).
* :func:`philosophers`: Dijkstra's dining philosophers ("Hierarchical
  ordering of sequential processes", Acta Informatica 1(2), 1971) as Petri
  net textbooks draw them (Reisig, "Petri Nets: An Introduction", Springer,
  1985): a philosopher takes both forks at once, eats, puts both back; live,
  no deadlock.
* :func:`philosophers_left_first`: the same table where each philosopher
  takes the left fork, then the right one (Dijkstra's original): it
  deadlocks when every philosopher holds a left fork.
* :func:`token_ring`: ``n`` stations passing one token around a ring
  (Le Lann, "Distributed systems: towards a formal approach", IFIP
  Congress 1977): a station does local work while it waits, enters its
  critical section only with the token, and passes the token on when it
  leaves or when it is not ready; about ``n * 2**n`` markings.
* :func:`shared_memory`: ``n`` processors, each with its own memory, sharing
  one more memory through one bus (Ajmone Marsan, Balbo and Conte, "A class
  of generalized stochastic Petri nets for the performance evaluation of
  multiprocessor systems", ACM TOCS 2(2), 1984; a model of the Model
  Checking Contest): a processor is active, asks for the bus to reach its
  own or the shared memory, and gives it back.
* :func:`kanban`: the Kanban manufacturing system of Ciardo and Tilgner
  ("On the use of Kronecker operators for the solution of generalized
  stochastic Petri nets", ICASE report 96-35, 1996; a model of the Model
  Checking Contest): four cells, ``n`` kanban cards each, a part that may
  be redone; bounded (P-invariants) but not safe: 160, 4,600, 58,400 and
  454,475 markings for ``n`` = 1 to 4.

Ids are the ones the tests name in their assertions (``p0``, ``c0t1``,
``think0``, ``fork2``, ...), so a net's places and transitions stay where
those assertions look for them.
"""
from __future__ import annotations

from mcl2pnml.core.net import Net, NetBuilder

__all__ = ["cycle", "cycles", "philosophers", "philosophers_left_first", "token_ring",
           "shared_memory", "kanban"]


def cycle(n: int = 4, name: str | None = None, interface: str | None = None) -> Net:
    """p0 -> t0 -> p1 -> t1 -> ... -> p{n-1} -> t{n-1} -> p0, one token in p0.

    ``interface`` makes p0 an interface place of that name, so that copies of
    the circuit can be joined on it.
    """
    b = NetBuilder(name or f"cycle{n}")
    for i in range(n):
        b.place(f"p{i}", 1 if i == 0 else 0, interface=interface if i == 0 else None)
        b.transition(f"t{i}")
    for i in range(n):
        b.arc(f"p{i}", f"t{i}")
        b.arc(f"t{i}", f"p{(i + 1) % n}")
    return b.build()


def cycles(k: int = 1) -> Net:
    """k independent 4-place cycles: 4**k markings."""
    b = NetBuilder(f"cycles{k}")
    for c in range(k):
        for i in range(4):
            b.place(f"c{c}p{i}", 1 if i == 0 else 0)
            b.transition(f"c{c}t{i}")
        for i in range(4):
            b.arc(f"c{c}p{i}", f"c{c}t{i}")
            b.arc(f"c{c}t{i}", f"c{c}p{(i + 1) % 4}")
    return b.build()


def philosophers(n: int = 3) -> Net:
    """Dining philosophers taking both forks at once: philosopher i uses
    fork i and fork i+1, so fork i is shared by philosophers i and i-1."""
    b = NetBuilder(f"philosophers{n}")
    for i in range(n):
        b.place(f"think{i}", 1)
        b.place(f"eat{i}")
        b.place(f"fork{i}", 1)
    for i in range(n):
        hands = (f"think{i}", f"fork{i}", f"fork{(i + 1) % n}")
        b.transition(f"take{i}")
        b.transition(f"release{i}")
        for p in hands:
            b.arc(p, f"take{i}")
            b.arc(f"release{i}", p)
        b.arc(f"take{i}", f"eat{i}")
        b.arc(f"eat{i}", f"release{i}")
    return b.build()


def philosophers_left_first(n: int) -> Net:
    """Dining philosophers taking the left fork, then the right, eating and
    putting both back; it deadlocks."""
    b = NetBuilder(f"philosophers-left-first{n}")
    for i in range(n):
        b.place(f"fork{i}", 1)
        b.place(f"think{i}", 1)
        b.place(f"left{i}")
        b.place(f"eat{i}")
    for i in range(n):
        left, right = f"fork{i}", f"fork{(i + 1) % n}"
        b.transition(f"take_left{i}")
        b.arc(f"think{i}", f"take_left{i}")
        b.arc(left, f"take_left{i}")
        b.arc(f"take_left{i}", f"left{i}")
        b.transition(f"take_right{i}")
        b.arc(f"left{i}", f"take_right{i}")
        b.arc(right, f"take_right{i}")
        b.arc(f"take_right{i}", f"eat{i}")
        b.transition(f"release{i}")
        b.arc(f"eat{i}", f"release{i}")
        b.arc(f"release{i}", left)
        b.arc(f"release{i}", right)
        b.arc(f"release{i}", f"think{i}")
    return b.build()


def token_ring(n: int) -> Net:
    """n stations passing one token around, each doing a local step (idle,
    ready) while it waits."""
    b = NetBuilder(f"token-ring{n}")
    for i in range(n):
        b.place(f"token{i}", 1 if i == 0 else 0)
        b.place(f"idle{i}", 1)
        b.place(f"ready{i}")
        b.place(f"busy{i}")
    for i in range(n):
        nxt = (i + 1) % n
        b.transition(f"prepare{i}")          # local work while it waits
        b.arc(f"idle{i}", f"prepare{i}")
        b.arc(f"prepare{i}", f"ready{i}")
        b.transition(f"use{i}")              # ready and holding the token: critical section
        b.arc(f"ready{i}", f"use{i}")
        b.arc(f"token{i}", f"use{i}")
        b.arc(f"use{i}", f"busy{i}")
        b.transition(f"done{i}")             # leave, pass the token on
        b.arc(f"busy{i}", f"done{i}")
        b.arc(f"done{i}", f"idle{i}")
        b.arc(f"done{i}", f"token{nxt}")
        b.transition(f"pass{i}")             # not ready: pass the token on
        b.arc(f"token{i}", f"pass{i}")
        b.read(f"idle{i}", f"pass{i}")
        b.arc(f"pass{i}", f"token{nxt}")
    return b.build()


def shared_memory(n: int) -> Net:
    """n processors with their own memories and one shared memory, on one bus."""
    b = NetBuilder(f"shared-memory{n}")
    b.place("bus_free", 1)
    b.place("ext_free", 1)
    for i in range(n):
        b.place(f"active{i}", 1)
        b.place(f"wait_own{i}")
        b.place(f"wait_ext{i}")
        b.place(f"own_free{i}", 1)
        b.place(f"access_own{i}")
        b.place(f"access_ext{i}")
    for i in range(n):
        b.transition(f"req_own{i}")
        b.arc(f"active{i}", f"req_own{i}")
        b.arc(f"req_own{i}", f"wait_own{i}")
        b.transition(f"req_ext{i}")
        b.arc(f"active{i}", f"req_ext{i}")
        b.arc(f"req_ext{i}", f"wait_ext{i}")
        b.transition(f"begin_own{i}")
        for p in (f"wait_own{i}", "bus_free", f"own_free{i}"):
            b.arc(p, f"begin_own{i}")
        b.arc(f"begin_own{i}", f"access_own{i}")
        b.transition(f"end_own{i}")
        b.arc(f"access_own{i}", f"end_own{i}")
        for p in (f"active{i}", "bus_free", f"own_free{i}"):
            b.arc(f"end_own{i}", p)
        b.transition(f"begin_ext{i}")
        for p in (f"wait_ext{i}", "bus_free", "ext_free"):
            b.arc(p, f"begin_ext{i}")
        b.arc(f"begin_ext{i}", f"access_ext{i}")
        b.transition(f"end_ext{i}")
        b.arc(f"access_ext{i}", f"end_ext{i}")
        for p in (f"active{i}", "bus_free", "ext_free"):
            b.arc(f"end_ext{i}", p)
    return b.build()


def kanban(n: int) -> Net:
    """Ciardo and Tilgner's Kanban system: four cells of ``n`` cards, cell 1 forks into 2
    and 3, which join into 4."""
    b = NetBuilder(f"kanban{n}")
    for i in range(1, 5):
        b.place(f"Pm{i}")
        b.place(f"Pback{i}")
        b.place(f"Pkan{i}", n)
        b.place(f"Pout{i}")
    for i in range(1, 5):
        for t, before, after in (("tredo", "Pm", "Pback"), ("tback", "Pback", "Pm"),
                                 ("tok", "Pm", "Pout")):
            b.transition(f"{t}{i}")
            b.arc(f"{before}{i}", f"{t}{i}")
            b.arc(f"{t}{i}", f"{after}{i}")
    for t, ins, outs in (("tin1", ["Pkan1"], ["Pm1"]),
                         ("tsynch1_23", ["Pout1", "Pkan2", "Pkan3"], ["Pkan1", "Pm2", "Pm3"]),
                         ("tsynch4_23", ["Pout2", "Pout3", "Pkan4"], ["Pkan2", "Pkan3", "Pm4"]),
                         ("tout4", ["Pout4"], ["Pkan4"])):
        b.transition(t)
        for p in ins:
            b.arc(p, t)
        for p in outs:
            b.arc(t, p)
    return b.build()
