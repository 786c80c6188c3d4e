"""Step 1 of the compiler: imperative MCL to functional code (the paper's Algorithm 2).

Every control structure becomes a function whose arguments are other
functions (structures or calls), as section 3.2 describes:

* a block of statements is a right-nested ``sequence(first, rest)``, with
  one statement it is that statement, empty it is ``NULL``;
* ``parallel(a, b, c)`` is ``parallel(a, parallel(b, c))``: the parallel
  net joins two structures, as the sequence does;
* ``if (c) then {t} else {e}`` is ``if-then-else(c, t, e)``, with ``NULL``
  for a missing else;
* ``while (c) {b}`` is ``while(c, b)``; ``monitor(a, b)`` stays as it is;
* calls of tasks and functions stay calls, with their arguments as written.

The paper's Algorithm 1 gives, character for character, the string that
``docs/mcl.md`` shows for Algorithm 2.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Union

from mcl2pnml.core.payloads import MISSION
from mcl2pnml.language import ast


@dataclass(frozen=True)
class FCall:
    """A call of a task or a function, with its arguments."""

    name: str
    args: tuple[ast.Value, ...]
    pos: ast.Pos


@dataclass(frozen=True)
class FStructure:
    """A control structure applied to its sub-structures (``NULL`` has none)."""

    kind: str          # sequence, parallel, if-then-else, while, monitor, NULL
    children: tuple["FNode", ...]
    pos: ast.Pos


FNode = Union[FCall, FStructure]

NULL_KIND = "NULL"


def to_functional(stmt: ast.Statement) -> FNode:
    if isinstance(stmt, ast.Call):
        return FCall(stmt.name, stmt.args, stmt.pos)
    if isinstance(stmt, ast.Block):
        return _sequence(list(stmt.body), stmt.pos)
    if isinstance(stmt, ast.Parallel):
        items = [to_functional(s) for s in stmt.items]
        node = items[-1]
        for item in reversed(items[:-1]):
            node = FStructure("parallel", (item, node), item.pos)
        return node
    if isinstance(stmt, ast.Monitor):
        return FStructure("monitor", (to_functional(stmt.watched), to_functional(stmt.watcher)),
                          stmt.pos)
    if isinstance(stmt, ast.If):
        otherwise = (to_functional(stmt.otherwise) if stmt.otherwise is not None
                     else FStructure(NULL_KIND, (), stmt.pos))
        return FStructure("if-then-else", (to_functional(stmt.condition),
                                           to_functional(stmt.then), otherwise), stmt.pos)
    if isinstance(stmt, ast.While):
        return FStructure("while", (to_functional(stmt.condition), to_functional(stmt.body)),
                          stmt.pos)
    raise TypeError(f"not a statement: {stmt!r}")


def _sequence(body: list[ast.Statement], pos: ast.Pos) -> FNode:
    if not body:
        return FStructure(NULL_KIND, (), pos)
    # built from the end, in a loop: a block of 10,000 statements nests
    # 10,000 sequences, far deeper than Python's recursion limit
    items = [to_functional(s) for s in body]
    node = items[-1]
    for item in reversed(items[:-1]):
        node = FStructure("sequence", (item, node), item.pos)
    return node


def format_value(v: ast.Value) -> str:
    if isinstance(v, ast.Number):
        return v.text
    if isinstance(v, ast.String):
        return '"' + v.value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, ast.Tuple):
        return "(" + ", ".join(format_value(i) for i in v.items) + ")"
    return v.name


def format_node(node: FNode) -> str:
    """The functional code as the paper prints it (iterative: sequences nest deep)."""
    out: list[str] = []
    stack: list[FNode | str] = [node]
    while stack:
        item = stack.pop()
        if isinstance(item, str):
            out.append(item)
        elif isinstance(item, FCall):
            out.append(f"{item.name}({', '.join(format_value(a) for a in item.args)})")
        elif item.kind == NULL_KIND:
            out.append(NULL_KIND)
        else:
            pieces: list[FNode | str] = [f"{item.kind}("]
            for i, child in enumerate(item.children):
                pieces += [", "] if i else []
                pieces.append(child)
            pieces.append(")")
            stack.extend(reversed(pieces))
    return "".join(out)


def mission_expression(mission: ast.Mission) -> FNode:
    return to_functional(mission.body)


def function_expression(function: ast.Function) -> FNode:
    return to_functional(function.body)


@dataclass(frozen=True)
class Instance:
    """A node of the functional form with the name of its instance in the compiled net.

    The compiler (:mod:`mcl2pnml.language.compiler`) makes one template
    instance per structure and one call site per call (section 2.5), each
    prefixing its nodes' ids (``mission.sequence-1.t2``, ``Goto-1.IN``);
    ``name`` is that prefix. ``parent`` is the index of the parent in the
    list :func:`instances` returns (-1 for the root), ``size`` the number of
    nodes in this one's subtree, itself included: in pre-order they are the
    ``size`` entries from this one on.
    """

    name: str
    kind: str          # "call", or a structure: sequence, parallel, ..., NULL
    line: int
    parent: int
    depth: int
    size: int
    node: "FNode" = field(compare=False, repr=False, default=None)

    @property
    def label(self) -> str:
        """The call as written (``Goto((10.0, 5.0, 5.0))``), or the kind: written when it
        is asked for (a survey's 10,000 calls are named, and seldom shown)."""
        return format_node(self.node) if self.kind == "call" else self.kind


def instances(root: FNode, root_name: str, scope: str) -> list[Instance]:
    """The nodes of ``root`` in pre-order, each named as the compiler names its instance.

    The root is ``root_name``; a child is ``scope.STEM-k`` (``STEM-k`` in the
    mission, whose scope is empty), STEM its kind or its callee, ``k``
    counting that stem's instances of the scope in pre-order. This is the one
    naming rule: the compiler takes its names from here. Iterative (a block
    of 10,000 statements nests 10,000 sequences).
    """
    counters: dict[str, int] = {}
    out: list[tuple] = []
    sizes: list[int] = []
    # a frame: (node, parent index, depth); a node is named when it is reached,
    # as the compiler names a child when it descends into it: the counts follow
    # the order in which the compiler meets the nodes
    stack: list[tuple[FNode, int, int]] = [(root, -1, 0)]
    while stack:
        node, parent, depth = stack.pop()
        if isinstance(node, FCall):
            kind, stem, children = "call", node.name, ()
        else:
            kind, stem, children = node.kind, node.kind, node.children
        if parent < 0:
            name = root_name
        else:
            counters[stem] = counters.get(stem, 0) + 1
            name = f"{scope}.{stem}-{counters[stem]}" if scope else f"{stem}-{counters[stem]}"
        index = len(out)
        out.append((name, kind, node.pos.line, parent, depth, node))
        sizes.append(1)
        stack.extend((child, index, depth + 1) for child in reversed(children))
    for k in range(len(out) - 1, 0, -1):   # children after parents: sizes bottom-up
        sizes[out[k][3]] += sizes[k]
    # each instance made once, its size known (a frozen dataclass's replace() is slow,
    # and a survey of 10,000 calls has 20,000 instances)
    return [Instance(name, kind, line, parent, depth, size, node)
            for (name, kind, line, parent, depth, node), size in zip(out, sizes)]


def box_label(node: FNode) -> str:
    """A node as a drawing's box names it: a call as written (``AchieveDepth(CrossDepth)``),
    a structure with its children one level deep (``monitor(Survey(), FindCross())``,
    ``if-then-else(monitor(…), sequence(…), NULL)``)."""
    if isinstance(node, FCall) or node.kind == NULL_KIND:
        return format_node(node)
    inner = (format_node(c) if isinstance(c, FCall) or c.kind == NULL_KIND else f"{c.kind}(\u2026)"
             for c in node.children)
    return f"{node.kind}({', '.join(inner)})"


def instance_trees(checked) -> list[tuple[str, list[Instance]]]:
    """The mission's functional form, then each function's, as the compiled net names
    their instances (:func:`instances`): where each instance of the net comes from."""
    trees = [(MISSION, instances(mission_expression(checked.mission), MISSION, ""))]
    trees += [(name, instances(function_expression(checked.functions[name]), name, name))
              for name in checked.function_order]
    return trees


def call_labels(checked) -> dict[str, str]:
    """Each instance of the compiled mission named as MCL writes it (section 2.5: one
    instance per structure and call site, one shared net per task, function and
    primitive): a call site by its call (``Dive(Depth)``), a structure by
    :func:`box_label`, the mission's root ``mission``, a function's body, a task and a
    primitive by their declarations with their parameters (``task Dive(d)``)."""
    labels = {}
    for root, tree in instance_trees(checked):
        for k, instance in enumerate(tree):
            labels[instance.name] = box_label(instance.node) if k else root
    for kind, declared in (("function", checked.functions), ("task", checked.tasks),
                           ("primitive", checked.primitives)):
        for name, d in declared.items():
            labels[name] = f"{kind} {name}({', '.join(d.params)})"
    return labels
