"""Hypothesis strategies for whole MCL missions and vehicle scripts, to run both engines on
(with :func:`helpers.both`), and properties generated for a mission's net."""
from __future__ import annotations

import random
from functools import lru_cache

from hypothesis import strategies as st

PRIMITIVES = ["Pa", "Pb", "Pc"]

#: The strategies a mission's draw uses, built once: built afresh inside each draw, each
#: had its whole tree validated again, most of a draw's time (the draws are the same).
TASK_KINDS = st.sampled_from(["AchieveGoal", "AchieveGoal", "KeepGoal", "KeepTwoGoals"])
TIMEOUTS = st.sampled_from(["", " timeout 3", " timeout 10", " timeout 20"])
PRIMITIVE_ORDERS = st.permutations(PRIMITIVES)
SOME_PRIMITIVE = st.sampled_from(PRIMITIVES)
TASK_COUNTS = st.integers(1, 3)
FUNCTION_COUNTS = st.integers(0, 2)
ARGUMENTS = st.sampled_from(["1", "2.5", "(1, 2)", "K"])


@st.composite
def task_decl(draw, name: str) -> str:
    kind = draw(TASK_KINDS)
    timeout = draw(TIMEOUTS)
    if kind == "KeepTwoGoals":
        a, b = draw(PRIMITIVE_ORDERS)[:2]
        body = f"KeepTwoGoals({a}(x), {b}(1))"
        timeout = timeout or " timeout 10"
    else:
        body = f"{kind}({draw(SOME_PRIMITIVE)}(x))"
        if kind == "KeepGoal":
            timeout = timeout or " timeout 10"
    return f"task {name}(x) = {body}{timeout};"


def statement(depth: int, callees: list[str], width: int = 3, tasks: list[str] | None = None,
              any_condition: bool = False):
    """Statements nested ``depth`` structures deep, blocks and branches at most ``width`` long.

    A loop's condition calls one of ``tasks`` (default: any callee). A task
    can always fail, which ends the loop; a function's body may end OK at
    once, every time (``function F() { }``), and a loop on it would never
    end: a livelock that the analysis rightly reports (not reusable) and
    that both engines stop as a zero-time loop, but not a mission to prove.
    ``any_condition``: a loop's condition may be any structure, such missions too.
    """
    return _statement(depth, tuple(callees), width, tuple(tasks or callees), any_condition)


@lru_cache(maxsize=None)
def _statement(depth: int, callees: tuple[str, ...], width: int, tasks: tuple[str, ...],
               any_condition: bool):
    """:func:`statement`'s strategy, built once for each shape and names: a mission draws
    its bodies from it, and a new one would be validated again at each draw."""
    arg = ARGUMENTS
    call = st.builds(lambda n, a: f"{n}({a});", st.sampled_from(callees), arg)
    condition = st.builds(lambda n, a: f"{n}({a})", st.sampled_from(tasks), arg)
    if depth == 0:
        return call
    inner = _statement(depth - 1, callees, width, tasks, any_condition)
    block = st.lists(inner, min_size=0, max_size=width).map(lambda b: "{ " + " ".join(b) + " }")
    nonempty = st.lists(inner, min_size=1, max_size=width).map(lambda b: "{ " + " ".join(b) + " }")
    structure = st.one_of(call.map(lambda c: c[:-1]), nonempty)
    return st.one_of(
        call, call,
        block,
        st.lists(structure, min_size=2, max_size=max(2, width)).map(lambda s: f"parallel({', '.join(s)});"),
        st.tuples(structure, structure).map(lambda s: f"monitor({s[0]}, {s[1]});"),
        st.tuples(structure, nonempty, st.none() | block).map(
            lambda s: f"if ({s[0]}) then {s[1]}" + (f" else {s[2]}" if s[2] else "")),
        # a loop's condition is a task's call, so that every loop may end (unless any)
        st.tuples(structure if any_condition else condition, nonempty).map(
            lambda s: f"while ({s[0]}) {s[1]}"),
    )


@st.composite
def missions(draw, depth: int = 2, width: int = 3, function_depth: int | None = None,
             any_condition: bool = False) -> str:
    """A whole mission: up to three tasks, up to two functions (a later one may
    call an earlier one), and a mission body ``depth`` structures deep.

    Functions nest ``function_depth`` structures deep (by default one level
    less than the mission, so that a call of a function inside a structure
    reaches as deep as the mission's own structures). ``width`` bounds blocks and parallel branches: the state
    space grows with it far faster than with ``depth``. ``any_condition``: loops on any
    structure, some of which never end.
    """
    lines = ["const K = (0.5, -1);"]
    lines += [f"primitive {p}(v);" for p in PRIMITIVES]
    tasks = [f"T{i}" for i in range(draw(TASK_COUNTS))]
    lines += [draw(_task_decl(t)) for t in tasks]
    callees = list(tasks)
    fdepth = depth - 1 if function_depth is None else function_depth
    for k in range(draw(FUNCTION_COUNTS)):
        body = draw(_bodies(fdepth, tuple(callees), width, tuple(tasks), any_condition))
        lines.append(f"function F{k}(x) {{ {' '.join(body)} }}")
        callees.append(f"F{k}")
    body = draw(_bodies(depth, tuple(callees), width, tuple(tasks), any_condition))
    lines.append("mission { " + " ".join(body) + " }")
    return "\n".join(lines) + "\n"


@lru_cache(maxsize=None)
def _task_decl(name: str):
    return task_decl(name)


@lru_cache(maxsize=None)
def _bodies(depth: int, callees: tuple[str, ...], width: int, tasks: tuple[str, ...],
            any_condition: bool):
    """A body's statements, one to ``width`` of them: the strategy built once per shape."""
    return st.lists(_statement(depth, callees, width, tasks or callees, any_condition),
                    min_size=1, max_size=width)


replies = st.one_of(st.sampled_from(["never"]),
                    st.builds(lambda k, d: f"{k}@{d}", st.sampled_from(["ok", "fail"]),
                              st.sampled_from([0, 1, 2, 5, 10])))
scripts = st.fixed_dictionaries({p: st.lists(replies, max_size=6) for p in PRIMITIVES})


# -- generated properties ---------------------------------------------------------------------

PATTERNS = ("never {e}", "always {e}", "eventually {e}", "at most {k} times {e}",
            "{e} only after {f}", "{e} leads to {f}")
SCOPES = ("", " globally", " before {r}", " after {q}", " between ({q}) and {r}",
          " after {q} until {r}")


def _atoms(net) -> list[str]:
    """The atoms whose places the mission's net has (a declared task it never calls has none)."""
    atoms = [f"outcome({r})" for r in ("OK", "FAIL", "ABORTED")]
    for p in ("Pa", "Pb", "Pc"):
        if f"{p}.ON" in net.place_index:
            atoms += [f"enabled({p})", f"achieved({p})", f"failed({p})"]
    for t in ("T0", "T1", "T2", "F0", "F1"):
        if f"{t}.GATE" in net.place_index:
            atoms += [f"running({t})", f"ended({t}, OK)", f"ended({t}, FAIL)"]
    return atoms


def _expression(rng: random.Random, atoms: list[str], depth: int = 2) -> str:
    roll = rng.random()
    if depth == 0 or roll < 0.5:
        return rng.choice(atoms)
    if roll < 0.65:
        return f"not ({_expression(rng, atoms, depth - 1)})"
    word = rng.choice(("and", "or"))
    return f"({_expression(rng, atoms, depth - 1)} {word} {_expression(rng, atoms, depth - 1)})"


def generated_properties(net, seed: int, count: int = 3) -> str:
    rng = random.Random(seed)
    atoms = _atoms(net)
    lines = []
    for k in range(count):
        e = {x: _expression(rng, atoms) for x in "efqr"}
        text = rng.choice(PATTERNS).format(k=rng.randint(1, 3), **e) + \
            rng.choice(SCOPES).format(**e)
        lines.append(f"property G{k}: {text};")
    return "\n".join(lines) + "\n"


@st.composite
def shaped_missions(draw, depth: int = 3) -> str:
    """A small mission on callees of every shape a certificate tells apart: a task that
    ends OK or FAIL, one that can only fail (KeepGoal with no time-out), a function that
    can only end OK (an empty body), with loops on any structure: many never end, or may
    not, and each is a verdict for the certificate to get right."""
    lines = ["const K = (0.5, -1);", "primitive Pa(v);", "primitive Pb(v);",
             "task A(x) = AchieveGoal(Pa(x)) timeout 3;",
             "task F(x) = KeepGoal(Pb(x));",
             "function E(x) { { } }"]
    body = draw(_bodies(depth, ("A", "F", "E"), 2, ("A", "F", "E"), True))
    lines.append("mission { " + " ".join(body) + " }")
    return "\n".join(lines) + "\n"
