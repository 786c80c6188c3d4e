"""Big P/T nets written straight to files, for the memory-budget tests.

Each shape stresses another stage of ``mcl2pnml analyze`` at a million places:

* ``ring``: one cycle p0 -> t0 -> p1 -> ... -> p0, one token. One P-invariant
  (every place), one T-invariant, n reachable markings: the invariant is a
  million entries long, the state space a million markings of a million places.
* ``components``: n separate loops p_i -> t_i -> p_i, each marked. The incidence
  matrix is zero: n P-invariants, n T-invariants, n minimal siphons and traps,
  one reachable marking. What grows is the number of answers.
* ``siphons``: a place z fed by transitions t_i that take a_i and b_i; z gives
  back to both. Every choice of a_i or b_i for each i, with z, is a minimal
  siphon: 2^((n-1)/2) of them.
* ``dense``: m transitions, each taking from ``degree`` places and putting into
  ``degree`` others, chosen by a seeded generator. The elimination that gives
  the P-invariant basis fills in: its rows become as long as the net is wide.

The nets are written as text, a line at a time, without building a
:class:`~mcl2pnml.core.net.Net`: the point is that the reader, not this module,
meets the size first.
"""
from __future__ import annotations

import random
from pathlib import Path
from typing import Callable, Iterator

#: A shape: (number of places) -> the net's places (id, tokens) and transitions
#: (id, inputs, outputs), as iterators, so that nothing is held.
Shape = Callable[[int], tuple[Iterator[tuple[str, int]],
                              Iterator[tuple[str, list[str], list[str]]]]]


def ring(n: int):
    places = ((f"p{i}", 1 if i == 0 else 0) for i in range(n))
    transitions = ((f"t{i}", [f"p{i}"], [f"p{(i + 1) % n}"]) for i in range(n))
    return places, transitions


def components(n: int):
    places = ((f"p{i}", 1) for i in range(n))
    transitions = ((f"t{i}", [f"p{i}"], [f"p{i}"]) for i in range(n))
    return places, transitions


def siphons(n: int):
    k = max(1, (n - 1) // 2)

    def places():
        yield "z", 1
        for i in range(k):
            yield f"a{i}", 0
            yield f"b{i}", 0

    def transitions():
        for i in range(k):
            yield f"t{i}", [f"a{i}", f"b{i}"], ["z"]
            yield f"s{i}", ["z"], [f"a{i}", f"b{i}"]

    return places(), transitions()


def dense(n: int, transitions_: int = 1_000, degree: int = 100, seed: int = 1):
    rng = random.Random(seed)
    places = ((f"p{i}", 1 if i == 0 else 0) for i in range(n))

    def transitions():
        for j in range(transitions_):
            chosen = rng.sample(range(n), 2 * min(degree, n // 2))
            half = len(chosen) // 2
            yield (f"t{j}", [f"p{i}" for i in chosen[:half]],
                   [f"p{i}" for i in chosen[half:]])

    return places, transitions()


SHAPES: dict[str, Shape] = {"ring": ring, "components": components, "siphons": siphons,
                            "dense": dense}


def write_pnml(path: Path, shape: str, n: int) -> Path:
    """The net ``shape`` with about ``n`` places as a PNML file at ``path``."""
    places, transitions = SHAPES[shape](n)
    arc = 0
    with open(path, "w") as f:
        f.write("<?xml version='1.0' encoding='UTF-8'?>\n"
                '<pnml xmlns="http://www.pnml.org/version-2009/grammar/pnml">\n'
                f'<net id="{shape}" type="http://www.pnml.org/version-2009/grammar/ptnet">\n'
                '<page id="page">\n')
        for p, tokens in places:
            mark = f"<initialMarking><text>{tokens}</text></initialMarking>" if tokens else ""
            f.write(f'<place id="{p}">{mark}</place>\n')
        for t, inputs, outputs in transitions:
            f.write(f'<transition id="{t}"/>\n')
            for p in inputs:
                arc += 1
                f.write(f'<arc id="x{arc}" source="{p}" target="{t}"/>\n')
            for p in outputs:
                arc += 1
                f.write(f'<arc id="x{arc}" source="{t}" target="{p}"/>\n')
        f.write("</page>\n</net>\n</pnml>\n")
    return path


def write_lola(path: Path, shape: str, n: int) -> Path:
    """The net ``shape`` with about ``n`` places as a LoLA file at ``path``."""
    places, transitions = SHAPES[shape](n)
    with open(path, "w") as f:
        f.write("PLACE\n")
        marked, first = [], True
        for p, tokens in places:
            f.write(("  " if first else ", ") + p)
            first = False
            if tokens:
                marked.append(f"{p}: {tokens}")
        f.write(";\n\nMARKING " + ", ".join(marked) + ";\n\n")
        for t, inputs, outputs in transitions:
            f.write(f"TRANSITION {t}\n  CONSUME {', '.join(p + ': 1' for p in inputs)};\n"
                    f"  PRODUCE {', '.join(p + ': 1' for p in outputs)};\n")
    return path


if __name__ == "__main__":   # python tests/support/bignets.py SHAPE N FILE
    import sys
    shape, size, out = sys.argv[1], int(sys.argv[2]), Path(sys.argv[3])
    (write_lola if out.suffix == ".lola" else write_pnml)(out, shape, size)
