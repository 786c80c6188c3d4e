"""Hypothesis strategies for random P/T nets with every feature of the core."""
from __future__ import annotations

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


@st.composite
def nets(draw, max_places: int = 8, max_transitions: int = 6):
    names = draw(st.lists(ids, min_size=2, max_size=max_places + max_transitions, unique=True))
    split = draw(st.integers(1, len(names) - 1))
    places, transitions = names[:split], names[split:]
    b = NetBuilder(draw(st.sampled_from(["net", "mission", "task"])))
    for p in places:
        b.place(p, draw(st.integers(0, 3)),
                name=draw(st.none() | st.text(st.characters(blacklist_categories=("Cs", "Cc")),
                                              min_size=1, max_size=5)),
                interface=draw(st.none() | st.sampled_from(["B", "A", "MTX", "OK", "E", "S1"])),
                payload=draw(st.none() | payloads))
    for t in transitions:
        timing = draw(st.none() | st.builds(lambda a, d: Timing(a, None if d is None else a + d),
                                            st.integers(0, 500).map(float),
                                            st.none() | st.integers(0, 100).map(float)))
        b.transition(t, timing=timing, payload=draw(st.none() | payloads))
    used: set = set()
    for _ in range(draw(st.integers(0, 3 * len(names)))):
        p, t = draw(st.sampled_from(places)), draw(st.sampled_from(transitions))
        kind = draw(st.sampled_from(["in", "out", "read"]))
        w = draw(st.integers(1, 3))
        if kind == "out":
            b.arc(t, p, w)
        elif (p, t) not in used:  # a transition may not both read and consume a place
            used.add((p, t))
            b.arc(p, t, w, ArcKind.READ if kind == "read" else ArcKind.NORMAL)
    return b.build()
