"""Hypothesis strategies for random P/T nets with every feature of the core."""
from __future__ import annotations

from functools import lru_cache

from hypothesis import strategies as st

from mcl2pnml.core.net import ArcKind, NetBuilder, Timing

ids = st.one_of(
    st.from_regex(r"[A-Za-z_][A-Za-z0-9_.]{0,6}", fullmatch=True),
    st.text(st.characters(blacklist_categories=("Cs", "Cc")), min_size=1, max_size=6)
      .map(str.strip).filter(bool),
)
payloads = st.recursive(
    st.none() | st.booleans() | st.integers(-10**6, 10**6) | st.text(max_size=5)
    | st.floats(allow_nan=False, allow_infinity=False, width=32),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=4), inner, max_size=3),
    max_leaves=6,
)


#: The strategies a net's draw uses, built once: built afresh inside each draw, each had
#: its whole tree validated again, nine tenths of a draw's time (the draws are the same).
NET_KINDS = st.sampled_from(["net", "mission", "task"])
TOKENS = st.integers(0, 3)
PLACE_NAMES = st.none() | st.text(st.characters(blacklist_categories=("Cs", "Cc")),
                                  min_size=1, max_size=5)
INTERFACES = st.none() | st.sampled_from(["B", "A", "MTX", "OK", "E", "S1"])
MAYBE_PAYLOADS = st.none() | payloads
TIMINGS = st.none() | st.builds(lambda a, d: Timing(a, None if d is None else a + d),
                                st.integers(0, 500).map(float),
                                st.none() | st.integers(0, 100).map(float))
ARC_KINDS = st.sampled_from(["in", "out", "read"])
WEIGHTS = st.integers(1, 3)


@lru_cache(maxsize=None)
def _names(most: int):
    return st.lists(ids, min_size=2, max_size=most, unique=True)


@lru_cache(maxsize=None)
def _between(low: int, high: int):
    return st.integers(low, high)


@st.composite
def nets(draw, max_places: int = 8, max_transitions: int = 6):
    names = draw(_names(max_places + max_transitions))
    split = draw(_between(1, len(names) - 1))
    places, transitions = names[:split], names[split:]
    b = NetBuilder(draw(NET_KINDS))
    for p in places:
        b.place(p, draw(TOKENS), name=draw(PLACE_NAMES), interface=draw(INTERFACES),
                payload=draw(MAYBE_PAYLOADS))
    for t in transitions:
        b.transition(t, timing=draw(TIMINGS), payload=draw(MAYBE_PAYLOADS))
    used: set = set()
    some_place, some_transition = st.sampled_from(places), st.sampled_from(transitions)
    for _ in range(draw(_between(0, 3 * len(names)))):
        p, t = draw(some_place), draw(some_transition)
        kind = draw(ARC_KINDS)
        w = draw(WEIGHTS)
        if kind == "out":
            b.arc(t, p, w)
        elif (p, t) not in used:  # a transition may not both read and consume a place
            used.add((p, t))
            b.arc(p, t, w, ArcKind.READ if kind == "read" else ArcKind.NORMAL)
    return b.build()
