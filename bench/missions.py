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


def relay(functions: int) -> str:
    """A chain of ``functions`` functions, each running the next in parallel with a depth
    change: the shape that makes the warnings' check of what runs at once (W002) look
    through every function below a call, the whole chain at each level if it were not
    found once per function."""
    lines = [
        f"// a generated relay of {functions:,} functions",
        "primitive GoToWayPoint(wp);",
        "primitive KeepDepth(d);",
        "task Goto(wp) = AchieveGoal(GoToWayPoint(wp)) timeout 100;",
        "task Depth(d) = AchieveGoal(KeepDepth(d)) timeout 60;",
    ]
    for i in range(functions):
        lines.append(f"function Leg{i}() {{ parallel(Leg{i + 1}(), Depth({2.0 + i % 7})); }}")
    lines.append(f"function Leg{functions}() {{ Goto((0.0, 0.0, 5.0)); }}")
    lines.append("mission { Leg0(); }")
    return "\n".join(lines) + "\n"
