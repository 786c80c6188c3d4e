"""The paper's vehicle primitive (section 2.2, Fig. 1), built by hand with the net core.

Run:  python examples/handbuilt_primitive.py out/primitive.pnml

A primitive is enabled (ON) or disabled (OFF). While enabled it seeks its
goal (C), has achieved it (S2) or has not / has lost it (S1), and may switch
between the two. The supervisor asks for enabling and disabling by marking E
and D; disabling returns the goal state to C. E, D, OFF, S1 and S2 are the
fusion places through which a task controls the primitive.

The goal transitions *read* ON (a test arc): the primitive must be on to
report, and reporting does not switch it off.
"""
import sys

from mcl2pnml import NetBuilder, save_pnml


def primitive():
    b = NetBuilder("primitive")
    for place, tokens in [("ON", 0), ("OFF", 1), ("E", 0), ("D", 0),
                          ("C", 1), ("S1", 0), ("S2", 0)]:
        interface = place if place in ("E", "D", "OFF", "S1", "S2") else None
        b.place(place, tokens, interface=interface)
    b.transition("t_enable")
    b.arc("E", "t_enable"); b.arc("OFF", "t_enable"); b.arc("t_enable", "ON")
    for state in ("S1", "S2"):  # goal not achieved / achieved, reported by the vehicle
        t = b.transition(f"t_report_{state}")
        b.read("ON", t); b.arc("C", t); b.arc(t, state)
    for src, dst in (("S2", "S1"), ("S1", "S2")):  # goal lost / regained
        t = b.transition(f"t_{src}_to_{dst}")
        b.read("ON", t); b.arc(src, t); b.arc(t, dst)
    for state in ("C", "S1", "S2"):  # disabling resets the goal state to C
        t = b.transition(f"t_disable_{state}")
        b.arc("D", t); b.arc("ON", t); b.arc(state, t); b.arc(t, "OFF"); b.arc(t, "C")
    return b.build()


if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "primitive.pnml"
    net = primitive()
    save_pnml(net, out)
    print(net.summary())
    print(f"wrote {out}")
