"""Scalable nets for the state-space benchmarks, each a classic of the field.

* ``cycles(k)``: k independent 4-place cycles, one token each: 4^k markings;
* ``philosophers(n)``: the dining philosophers (Dijkstra), each taking the
  left fork, then the right, eating and putting both back; it deadlocks;
* ``token_ring(n)``: n stations passing one token around, each doing a
  local step (idle, ready) while it waits; n * 2^n markings or so;
* ``shared_memory(n)``: n processors, each with its own memory, sharing one
  extra memory through one bus (the model of Ajmone Marsan et al., used in
  the Model Checking Contest): a processor is active, then asks for the bus
  to reach its own or the shared memory, and gives it back;
* ``mission(width)``: a compiled MCL mission, ``width`` tasks in parallel,
  each on its own primitive (``examples``-style, from the compiler).
"""
from __future__ import annotations

from mcl2pnml.core.net import Net, NetBuilder


def cycles(k: int) -> Net:
    b = NetBuilder(f"cycles-{k}")
    for c in range(k):
        for i in range(4):
            b.place(f"c{c}_p{i}", 1 if i == 0 else 0)
            b.transition(f"c{c}_t{i}")
        for i in range(4):
            b.arc(f"c{c}_p{i}", f"c{c}_t{i}")
            b.arc(f"c{c}_t{i}", f"c{c}_p{(i + 1) % 4}")
    return b.build()


def philosophers(n: int) -> Net:
    b = NetBuilder(f"philosophers-{n}")
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
    b = NetBuilder(f"token-ring-{n}")
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
    b = NetBuilder(f"shared-memory-{n}")
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


def mission(width: int) -> Net:
    from mcl2pnml.language.compiler import compile_checked
    from mcl2pnml.language.checker import check
    from mcl2pnml.language.parser import parse

    lines = [f"primitive P{i}(x);" for i in range(width)]
    lines += [f"task T{i}(x) = AchieveGoal(P{i}(x)) timeout 10;" for i in range(width)]
    calls = ", ".join(f"T{i}({i})" for i in range(width))
    body = f"parallel({calls});" if width > 1 else "T0(0);"
    lines.append(f"mission {{ {body} }}")
    return compile_checked(check(parse("\n".join(lines), f"parallel-{width}.mcl")))
