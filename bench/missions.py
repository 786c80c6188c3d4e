"""Generated MCL missions of any size, for the benchmarks and the scale tests.

A survey is what makes missions long in practice: a vehicle visiting
waypoint after waypoint, changing depth between legs. ``survey(n)`` is such a
mission with ``n`` task calls in one block, alternating a depth change and a
transit leg, every value different, so that no two call sites are alike.
"""
from __future__ import annotations


def survey(calls: int) -> str:
    lines = [
        f"// a generated survey of {calls:,} task calls",
        "primitive GoToWayPoint(wp);",
        "primitive KeepDepth(d);",
        "task Goto(wp) = AchieveGoal(GoToWayPoint(wp)) timeout 100;",
        "task Depth(d) = AchieveGoal(KeepDepth(d)) timeout 60;",
        "mission {",
    ]
    for i in range(calls):
        if i % 2:
            lines.append(f"    Goto(({i * 10.0}, {(i % 17) * 5.0}, 5.0));")
        else:
            lines.append(f"    Depth({2.0 + i % 7});")
    lines.append("}")
    return "\n".join(lines) + "\n"
