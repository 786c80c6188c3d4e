"""The loops in plain Python: the reference backend of
:class:`~mcl2pnml.analysis.statespace.loops.interface.Loops`.

The same algorithms as the C loops (``_native.c``), written to be read: a
marking is a tuple of words (Python integers), the set of markings found a
dict from marking to position, each transition tested on every word. It
serves where the C extension was not built, and the shared tests run it on
their small nets beside C (tests/analysis/test_statespace.py, test_graph_kernels.py,
test_onthefly.py), so that the two are held to one behaviour. The order in
which a marking tries its transitions is C's (the key index's: the free
transitions, then those keyed on each marked place upwards), so that both
find the same markings in the same order and the same counterexamples.
Slower than C by the interpreter's factor: for the tests' nets, and for a
machine without a C compiler.
"""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from mcl2pnml.analysis.statespace.loops.interface import (Buchi, Code, CounterNet, CounterSearch,
                                                          Fields, Index, KeyIndex, LtlCode,
                                                          Observer, Op, ProductSearch, Rows,
                                                          STUBBORN_KEYS,
                                                          SafeNet, SafeSearch, StateProgram,
                                                          Stubborn)

name = "python"

#: The tables here are dicts, which grow by themselves: no size in bits to carry.
NO_BITS = 0

Row = tuple[int, ...]


def _row(queue: np.ndarray, i: int) -> Row:
    return tuple(int(w) for w in np.atleast_1d(queue[i]))


def _put(queue: np.ndarray, i: int, row: Row) -> np.ndarray:
    """``queue`` with ``row`` at ``i``, doubled first if it is too short."""
    if i >= len(queue):
        grown = np.empty((2 * len(queue) + 1, *queue.shape[1:]), dtype=queue.dtype)
        grown[:i] = queue[:i]
        queue = grown
    queue[i] = row if queue.ndim == 2 else row[0]
    return queue


def _lists(a: np.ndarray) -> list[Row]:
    """Rows of an array (one word each if it is flat) as tuples of Python integers."""
    return [tuple(r) if isinstance(r, list) else (r,) for r in a.tolist()]


def _rows_of(rows: Rows) -> list[list[int]]:
    """Compressed rows as one list a row."""
    ptr, items = rows.ptr.tolist(), rows.items.tolist()
    return [items[ptr[i]:ptr[i + 1]] for i in range(len(ptr) - 1)]


class _Keys:
    """A :class:`KeyIndex` as lists: which transitions a marking tries, in C's order."""

    def __init__(self, key: KeyIndex):
        self.free, self.by_place = key.free.tolist(), _rows_of(key.by_place)

    def candidates(self, row: Row) -> list[int]:
        """The free transitions, then those keyed on each marked place upwards."""
        out = list(self.free)
        for w, x in enumerate(row):
            while x:
                low = x & -x
                out += self.by_place[w * 64 + low.bit_length() - 1]
                x ^= low
        return out


class _Safe:
    """A safe net's masks as Python integers, one tuple of words a transition."""

    def __init__(self, net: SafeNet):
        self.need, self.keep, self.give = _lists(net.need), _lists(net.keep), _lists(net.give)
        self.take = _lists(net.take)
        self.key = _Keys(net.key)

    def enables(self, row: Row, t: int) -> bool:
        return all(x & n == n for x, n in zip(row, self.need[t]))

    def fire(self, row: Row, t: int) -> Row | None:
        """The marking after t, or None if it would put a second token in a place."""
        if any(x & k & g for x, k, g in zip(row, self.keep[t], self.give[t])):
            return None
        return tuple((x & k) | g for x, k, g in zip(row, self.keep[t], self.give[t]))

    def unfire(self, after: Row, t: int) -> Row | None:
        """The one marking t can fire from into ``after`` (the net is safe), or None."""
        if any(x & g != g for x, g in zip(after, self.give[t])):
            return None
        before = tuple((x & ~g) | k for x, g, k in zip(after, self.give[t], self.take[t]))
        if not self.enables(before, t) or self.fire(before, t) != after:
            return None
        return before


def _index(queue: np.ndarray, count: int) -> dict[Row, int]:
    return {row: i for i, row in enumerate(_lists(queue[:count]))}


# -- a safe net --------------------------------------------------------------------------------

def safe_search(net: SafeNet, m0: np.ndarray, max_states: int) -> SafeSearch:
    queue = np.empty((1024, net.words) if net.words > 1 else 1024, dtype=np.uint64)
    queue = _put(queue, 0, tuple(int(w) for w in m0))
    return SafeSearch(queue, 1, 0, _index(queue, 1), NO_BITS)


def safe_step(net: SafeNet, search: SafeSearch, max_states: int, budget: int) -> SafeSearch:
    tables, found = _Safe(net), search.table
    queue, count, head = search.queue, search.count, search.head
    stop = head + budget
    while head < count and head < stop:
        row = _row(queue, head)
        for t in tables.key.candidates(row):
            if not tables.enables(row, t):
                continue
            after = tables.fire(row, t)
            if after is None:
                return replace(search, queue=queue, count=count, head=head, code=Code.NOT_SAFE)
            if after in found:
                continue
            if count >= max_states:
                return replace(search, queue=queue, count=count, head=head, code=Code.LIMIT)
            queue = _put(queue, count, after)
            found[after] = count
            count += 1
        head += 1
    return replace(search, queue=queue, count=count, head=head, code=Code.GOING)


def permute_rows(rows: np.ndarray, order: np.ndarray) -> np.ndarray:
    return rows[order]


def out_degree(rows: np.ndarray, net: SafeNet) -> np.ndarray:
    tables = _Safe(net)
    return np.array([sum(tables.enables(row, t) for t in tables.key.candidates(row))
                     for row in _lists(rows)], dtype=np.int32)


def live(rows: np.ndarray, net: SafeNet) -> np.ndarray:
    return (out_degree(rows, net) > 0).astype(np.int32)


def edges(rows: np.ndarray, net: SafeNet, ids: np.ndarray, order: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node i is row ``order[i]`` (``order`` its own inverse); its edges by transition."""
    tables, position = _Safe(net), _index(rows, len(rows))
    every, node, ids = _lists(rows), order.tolist(), ids.tolist()
    out = []
    for i, r in enumerate(node):
        row = every[r]
        out += sorted((i, ids[t], node[position[tables.fire(row, t)]])
                      for t in tables.key.candidates(row) if tables.enables(row, t))
    src, trans, dst = (np.array(x, dtype=np.int32) for x in zip(*out)) if out else \
        (np.zeros(0, dtype=np.int32),) * 3
    return src, trans, dst


def backward(rows: np.ndarray, net: SafeNet, unfire: KeyIndex, seen: np.ndarray,
             frontier: np.ndarray) -> np.ndarray:
    """Mark in ``seen`` every row that reaches one of ``frontier`` (seen already), breadth
    first by unfiring: only the transitions keyed on the places marked after are tried."""
    tables, position, keys = _Safe(net), _index(rows, len(rows)), _Keys(unfire)
    every, todo = _lists(rows), frontier.tolist()
    for a in todo:           # the list grows as it is walked: first in, first out
        after = every[a]
        for t in keys.candidates(after):
            j = position.get(tables.unfire(after, t))
            if j is not None and not seen[j]:
                seen[j] = True
                todo.append(j)
    return seen


# -- a bounded net -----------------------------------------------------------------------------

class _Counters:
    """A bounded net's fields as Python integers: per transition, (word, shift, mask,
    tokens) of what it needs and (word, shift, mask, change) of what it changes."""

    def __init__(self, net: CounterNet):
        self.needs, self.changes = _fields_of(net.need), _fields_of(net.change)
        self.places = net.change.place.tolist()
        self.first = net.change.ptr.tolist()       # a change's index: first[t] + its rank
        self.growing = net.growing.tolist()

    def enabled(self, row: Row, t: int) -> bool:
        return all((row[w] >> shift) & mask >= tokens for w, shift, mask, tokens in self.needs[t])

    def fire(self, row: Row, t: int, sign: int) -> tuple[Row | None, int]:
        """``row`` changed by ``sign`` times t's change, or None and the first field that
        would leave its range (below 0 or past its mask)."""
        out = list(row)
        for k, (w, shift, mask, change) in enumerate(self.changes[t]):
            value = ((out[w] >> shift) & mask) + sign * change
            if not 0 <= value <= mask:
                return None, self.first[t] + k
            out[w] = (out[w] & ~(mask << shift)) | (value << shift)
        return tuple(out), -1


def _fields_of(f: Fields) -> list[list[tuple[int, int, int, int]]]:
    fields = list(zip(f.word.tolist(), f.shift.tolist(), f.mask.tolist(), f.value.tolist()))
    ptr = f.ptr.tolist()
    return [fields[ptr[t]:ptr[t + 1]] for t in range(len(ptr) - 1)]


def counter_search(queue: np.ndarray, parent: np.ndarray, count: int, head: int,
                   dead: int = 0) -> CounterSearch:
    return CounterSearch(queue, parent, count, head, Index(_index(queue, count), NO_BITS),
                         dead)


def counter_step(net: CounterNet, search: CounterSearch, max_states: int,
                 budget: int) -> CounterSearch:
    found, tables = search.index.table, _Counters(net)
    queue, parent, count, head, dead = (search.queue, search.parent, search.count, search.head,
                                        search.dead)

    def stopped(code: Code, info: int = 0) -> CounterSearch:
        return CounterSearch(queue, parent, count, head, search.index, dead, code, info)

    stop = head + budget
    while head < count and head < stop:
        row, fired = _row(queue, head), False
        for t in range(net.transitions):
            if not tables.enabled(row, t):
                continue
            fired = True
            if tables.growing[t]:
                return stopped(Code.GROWING, t)
            after, k = tables.fire(row, t, 1)
            if after is None:
                return stopped(Code.OVERFLOW, tables.places[k])
            if after in found:
                continue
            if count >= max_states:
                return stopped(Code.LIMIT)
            queue = _put(queue, count, after)
            if len(parent) < len(queue):
                parent = np.concatenate([parent, np.empty(len(queue) - len(parent), np.int64)])
            parent[count] = head
            found[after] = count
            count += 1
        dead += not fired
        head += 1
    return stopped(Code.GOING)


def counter_out_degree(rows: np.ndarray, net: CounterNet) -> np.ndarray:
    tables = _Counters(net)
    return np.array([sum(tables.enabled(row, t) for t in range(net.transitions))
                     for row in _lists(rows)], dtype=np.int32)


def counter_edges(rows: np.ndarray, index: Index, net: CounterNet, total: int
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    tables = _Counters(net)
    out: list[tuple[int, int, int]] = []
    # the first ``total`` firings in node order, as C gives them: the rows past them
    # (an exploration's open frontier) may have successors the index does not hold
    for q, row in enumerate(_lists(rows)):
        if len(out) == total:
            break
        for t in range(net.transitions):
            if tables.enabled(row, t):
                out.append((q, t, index.table[tables.fire(row, t, 1)[0]]))
    src, trans, dst = (np.array(x, dtype=np.int32) for x in zip(*out)) if out else \
        (np.zeros(0, dtype=np.int32),) * 3
    return src, trans, dst


def counter_backward(rows: np.ndarray, net: CounterNet, seen: np.ndarray,
                     frontier: np.ndarray) -> np.ndarray:
    """Unfiring: the only marking t comes from is the one after minus t's change; it is a
    predecessor when it is a found marking and enables t."""
    tables, position = _Counters(net), _index(rows, len(rows))
    every, todo = _lists(rows), frontier.tolist()
    for a in todo:
        after = every[a]
        for t in range(net.transitions):
            before, _ = tables.fire(after, t, -1)
            if before is None or not tables.enabled(before, t):
                continue
            j = position.get(before)
            if j is not None and not seen[j]:
                seen[j] = True
                todo.append(j)
    return seen


# -- a property's product ----------------------------------------------------------------------

class _Observing:
    """An :class:`Observer` as lists: it reads a marking through its atoms."""

    def __init__(self, o: Observer):
        self.atoms = list(zip(o.atoms.tolist(), o.least.tolist()))
        self.letters, self.move = o.letters.tolist(), o.move.tolist()
        self.pending, self.bad = o.pending.tolist(), o.bad

    def after(self, marking: Row, state: int) -> int:
        """The observer's state after reading ``marking`` (the net is safe: an atom's
        tokens are the marked places of its mask)."""
        letter = 0
        for a, (mask, least) in enumerate(self.atoms):
            if sum(bin(x & m).count("1") for x, m in zip(marking, mask)) >= least:
                letter |= 1 << a
        return self.move[state * 16 + self.letters[letter]]


class _Reducing:
    """A :class:`Stubborn` as lists, one a transition or place."""

    def __init__(self, st: Stubborn):
        self.on, self.visible = st.on, st.visible.tolist()
        self.pre, self.needs = _rows_of(st.pre), _rows_of(st.needs)
        self.takers, self.needers, self.makers = (_rows_of(st.takers), _rows_of(st.needers),
                                                  _rows_of(st.makers))


def _stubborn_set(row: Row, st: _Reducing, enabled: set[int], key: int,
                  lacking=None) -> list[int] | None:
    """The enabled members of the stubborn set grown from the enabled ``key`` (C's
    ``stubborn_set``: an enabled member brings the transitions that consume a place it
    needs and those that need a place it consumes; a disabled one those that mark its
    first empty needed place, or ``lacking(t)``'s), or None if one is visible."""
    members, work, out = {key}, [key], []
    while work:
        t = work.pop()
        if t in enabled:
            if st.visible[t]:
                return None
            out.append(t)
            brought = [u for p in st.needs[t] for u in st.takers[p]]
            brought += [u for p in st.pre[t] for u in st.needers[p]]
        elif lacking is not None:
            brought = st.makers[lacking(t)]
        else:
            empty = [p for p in st.needs[t] if not row[p // 64] >> (p % 64) & 1]
            brought = st.makers[empty[0]] if empty else []
        for u in brought:
            if u not in members:
                members.add(u)
                work.append(u)
    return out


def _to_fire(row: Row, tables: _Safe, st: _Reducing) -> tuple[list[int], int]:
    """The row's enabled transitions, a smallest stubborn set's first, and how many of them
    to fire unless the proviso asks for all (all of them without reduction)."""
    fire = list(dict.fromkeys(t for t in tables.key.candidates(row) if tables.enables(row, t)))
    if not st.on or len(fire) < 2:
        return fire, len(fire)
    best = fire
    for key in fire:
        if len(best) <= 1:
            break
        got = _stubborn_set(row, st, set(fire), key)
        if got and len(got) < len(best):
            best = got
    return best + [t for t in fire if t not in best], len(best)


def product_search(start: np.ndarray, capacity: int) -> ProductSearch:
    queue = np.empty((capacity, len(start)), dtype=np.uint64)
    queue[0] = start
    parent, via, depth = (np.zeros(capacity, dtype=np.int64) for _ in range(3))
    parent[0], via[0] = -1, -1
    return ProductSearch(queue, 1, 0, Index(_index(queue, 1), NO_BITS), parent, via,
                         depth)


def product_step(net: SafeNet, observer: Observer, stubborn: Stubborn, search: ProductSearch,
                 max_states: int, budget: int) -> ProductSearch:
    """Breadth first to the first violation, as C's ``product_step`` (read its comment):
    a successor in the bad state is only the shortest violation once its level is done;
    a dead row with an obligation open is one at once."""
    tables, found_rows, reducing = _Safe(net), search.index.table, _Reducing(stubborn)
    observing = _Observing(observer)
    queue, count, head, found = search.queue, search.count, search.head, search.found
    parent, via, depth = search.parent, search.via, search.depth

    def stopped(code: Code) -> ProductSearch:
        return ProductSearch(queue, count, head, search.index, parent, via, depth, found, code)

    stop = head + budget
    while head < count and head < stop:
        if found >= 0 and depth[head] >= depth[found]:
            return stopped(Code.FOUND_BAD)
        row = _row(queue, head)
        marking, state = row[:-1], row[-1]
        fire, reduced = _to_fire(marking, tables, reducing)
        n, old, c = reduced, False, 0
        while c < n:
            t = fire[c]
            after = tables.fire(marking, t)
            if after is None:
                return stopped(Code.NOT_SAFE)
            after += (observing.after(after, state),)
            seen = found_rows.get(after)
            if seen is not None:
                old |= bool(depth[seen] <= depth[head])   # an arc back: a cycle may close
            else:
                if count >= max_states:
                    return stopped(Code.FOUND_BAD if found >= 0 else Code.LIMIT)
                queue = _put(queue, count, after)
                parent = _put(parent, count, (head,))
                via = _put(via, count, (t,))
                depth = _put(depth, count, (int(depth[head]) + 1,))
                found_rows[after] = count
                if after[-1] == observing.bad and found < 0:
                    found = count
                count += 1
            if c == n - 1 and n < len(fire) and old:
                n = len(fire)   # the proviso: a reduced row meeting an old one fires all
            c += 1
        if not fire and observing.pending[state]:
            found = head
            return stopped(Code.FOUND_DEAD)
        head += 1
    return stopped(Code.FOUND_BAD if found >= 0 and head == count else Code.GOING)


def product_edges(net: SafeNet, observer: Observer, search: ProductSearch, first: int,
                  room: int) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """The arcs between pending rows from row ``first`` on (every one: ``room`` is only
    C's bound on a call)."""
    tables, position, observing = _Safe(net), search.index.table, _Observing(observer)
    out = []
    for i in range(first, search.count):
        row = _row(search.queue, i)
        if not observing.pending[row[-1]]:
            continue
        for t in tables.key.candidates(row[:-1]):
            after = tables.fire(row[:-1], t) if tables.enables(row[:-1], t) else None
            if after is None:
                continue
            after += (observing.after(after, row[-1]),)
            if observing.pending[after[-1]] and after in position:
                out.append((i, position[after], t))
    src, dst, trans = (np.array(x, dtype=np.int64) for x in zip(*out)) if out else \
        (np.zeros(0, dtype=np.int64),) * 3
    return search.count, src, dst, trans


# -- graph searches ----------------------------------------------------------------------------

def scc(indptr: np.ndarray, indices: np.ndarray, keep: np.ndarray, label: np.ndarray) -> int:
    """The strongly connected components of the graph restricted to the kept nodes, by
    Tarjan's algorithm without recursion: ``label[v]`` v's component (-1 where not kept),
    numbered in the order they complete; returns their number."""
    n = len(indptr) - 1
    ptr, idx, kept = indptr.tolist(), indices.tolist(), keep.astype(bool).tolist()
    num, low = [0] * n, [0] * n                 # num 0: not met; -1: its component is done
    out = [-1] * n
    count, nxt = 0, 1
    for root in range(n):
        if not kept[root] or num[root]:
            continue
        num[root] = low[root] = nxt
        nxt += 1
        open_, call = [root], [[root, ptr[root]]]
        while call:
            frame = call[-1]
            v, e = frame
            if e < ptr[v + 1]:
                frame[1] = e + 1
                w = idx[e]
                if not kept[w]:
                    continue
                if not num[w]:
                    num[w] = low[w] = nxt
                    nxt += 1
                    open_.append(w)
                    call.append([w, ptr[w]])
                elif num[w] > 0 and num[w] < low[v]:
                    low[v] = num[w]
                continue
            call.pop()
            if low[v] == num[v]:
                while True:
                    w = open_.pop()
                    num[w] = -1
                    out[w] = count
                    if w == v:
                        break
                count += 1
            if call:
                u = call[-1][0]
                low[u] = min(low[u], low[v])
    label[:] = out
    return count


def scatter_by_source(src: np.ndarray, values: np.ndarray, cursor: np.ndarray,
                      out: np.ndarray) -> None:
    """The edges' ``values`` in a stable order by source (C's counting sort): ``cursor[v]``
    starts at row v's first slot and ends past its last."""
    n, edges = len(cursor), len(src)
    if len(out) != edges or len(values) != edges:
        raise ValueError("values and out must have a slot per edge")
    if edges and (src.min() < 0 or src.max() >= n):
        raise ValueError("an edge's source is not a row")
    ranked = np.argsort(src, kind="stable")
    start = cursor.copy()
    cursor += np.bincount(src, minlength=n)
    if edges and (start.min() < 0 or cursor.max() > edges):
        raise ValueError("a row is full")
    # each row's edges, in order, at its slots
    rows = src[ranked]
    out[start[rows] + (np.arange(edges) - np.searchsorted(rows, rows))] = values[ranked]


def back_reach(indptr: np.ndarray, indices: np.ndarray, through: np.ndarray,
               out: np.ndarray) -> None:
    """With the predecessors' compressed rows, add to ``out`` every node of ``through`` from
    which a path inside ``through`` reaches one of its nodes: E(through U out)."""
    mark, allowed = out.view(bool), through.astype(bool)
    todo = np.flatnonzero(mark).tolist()
    for v in todo:
        for u in indices[indptr[v]:indptr[v + 1]].tolist():
            if allowed[u] and not mark[u]:
                mark[u] = True
                todo.append(u)


def ltl_product(indptr, indices, a_ptr, a_succ, label, acc, all_sets: int, initial, num,
                max_states: int) -> tuple[int, int]:
    """Couvreur's on-the-fly emptiness check of the graph's product with a generalised
    Büchi automaton (C's ``ltl_product``, its arguments and result): ``(1, states)`` an
    accepting cycle, ``(0, states)`` none, ``(-1, states)`` past ``max_states``."""
    n, k = len(indptr) - 1, len(a_ptr) - 1
    ptr, idx = indptr.tolist(), indices.tolist()
    aptr, asucc = a_ptr.tolist(), a_succ.tolist()
    reads, sets = label.astype(bool).tolist(), [int(x) for x in acc]
    nxt = 1
    for first in initial.tolist():
        if num[first]:
            continue
        num[first] = nxt
        nxt += 1
        open_, roots, call = [first], [[num[first], sets[first % k]]], [[first, 0]]
        while call:
            frame = call[-1]
            p, cursor = frame
            s, a = divmod(p, k)
            degree, moves = ptr[s + 1] - ptr[s], aptr[a + 1] - aptr[a]
            if cursor < degree * moves:
                frame[1] = cursor + 1
                b = asucc[aptr[a] + cursor // degree]
                t = idx[ptr[s] + cursor % degree]
                if not reads[b * n + t]:
                    continue
                q = t * k + b
                if not num[q]:
                    if nxt > max_states:
                        return -1, nxt - 1
                    num[q] = nxt
                    nxt += 1
                    open_.append(q)
                    roots.append([num[q], sets[b]])
                    call.append([q, 0])
                elif num[q] > 0:
                    # a cycle closes: every root above q's joins the component below
                    met = 0
                    while roots[-1][0] > num[q]:
                        met |= roots.pop()[1]
                    roots[-1][1] |= met
                    if roots[-1][1] == all_sets:
                        return 1, nxt - 1
                continue
            call.pop()
            if roots[-1][0] == num[p]:
                roots.pop()
                while True:
                    w = open_.pop()
                    num[w] = -1
                    if w == p:
                        break
    return 0, nxt - 1


# -- an LTL formula's product with a bounded net, on the fly ------------------------------------

class _Program:
    """A :class:`StateProgram` read into Python lists: ``atoms(row)`` is a mask, a bit an
    atom that holds in the marking."""

    def __init__(self, program: StateProgram, tables: _Counters, transitions: int):
        ops = program.ops.reshape(-1, 2).tolist()
        ptr = program.atom_ptr.tolist()
        self.atoms = [ops[ptr[i]:ptr[i + 1]] for i in range(len(ptr) - 1)]
        lp = program.lin_ptr.tolist()
        fields = list(zip(program.lin_word.tolist(), program.lin_shift.tolist(),
                          program.lin_mask.tolist(), program.lin_coef.tolist()))
        self.linear = [(fields[lp[c]:lp[c + 1]], b) for c, b in enumerate(program.bound.tolist())]
        self.tables, self.transitions = tables, transitions

    def mask(self, row: Row) -> int:
        out, dead = 0, None
        for i, ops in enumerate(self.atoms):
            stack: list[bool] = []
            for op, arg in ops:
                if op == Op.LINEAR:
                    fields, bound = self.linear[arg]
                    stack.append(sum(c * ((row[w] >> sh) & m) for w, sh, m, c in fields)
                                 <= bound)
                elif op == Op.ENABLED:
                    stack.append(self.tables.enabled(row, arg))
                elif op == Op.DEAD:
                    if dead is None:
                        dead = not any(self.tables.enabled(row, t)
                                       for t in range(self.transitions))
                    stack.append(dead)
                elif op == Op.CONST:
                    stack.append(bool(arg))
                elif op == Op.NOT:
                    stack.append(not stack.pop())
                else:
                    parts = [stack.pop() for _ in range(arg)]
                    stack.append(all(parts) if op == Op.AND else any(parts))
            if stack.pop():
                out |= 1 << i
        return out


# long: the reference follows C's one loop (a search's state on its stacks) step by step
def ltl_search(net: CounterNet, program: StateProgram, buchi: Buchi, stubborn: Stubborn,
               m0: np.ndarray, max_states: int, seconds: float) -> tuple[LtlCode, int, int]:
    tables = _Counters(net)
    transitions = net.transitions
    reads = _Program(program, tables, transitions)
    need_places = [net.need.place[net.need.ptr[t]:net.need.ptr[t + 1]].tolist()
                   for t in range(transitions)]
    reducing = _Reducing(stubborn)
    aptr, asucc = buchi.ptr.tolist(), buchi.succ.tolist()
    required, accepting = [int(x) for x in buchi.required], [int(x) for x in buchi.accepting]
    deadline = time.monotonic() + seconds
    number: dict[tuple, int] = {}     # product state -> its number; done: negated
    on_stack: set[tuple] = set()      # the search's path
    masks: dict[Row, int] = {}

    def atoms(row: Row) -> int:
        m = masks.get(row)
        if m is None:
            m = masks[row] = reads.mask(row)
        return m

    def successors(row: Row, a: int, ts: list[int]) -> list[tuple]:
        out = []
        for t in ts:
            after = row if t < 0 else tables.fire(row, t, 1)[0]
            if after is None:
                raise _Overflow(tables.places[tables.fire(row, t, 1)[1]])
            m = atoms(after)
            out += [(after, b) for b in asucc[aptr[a]:aptr[a + 1]]
                    if required[b] & m == required[b]]
        return out

    def expand(row: Row, a: int) -> list[tuple]:
        enabled = [t for t in range(transitions) if tables.enabled(row, t)]
        if any(tables.growing[t] for t in enabled):
            raise _Growing
        if not enabled:
            return successors(row, a, [-1])     # a dead marking repeats
        if stubborn.on and len(enabled) > 1:
            best = None
            def lacking(t: int) -> int:    # the first place t needs more tokens in
                return next(p for (w, sh, m, tokens), p in zip(tables.needs[t], need_places[t])
                            if (row[w] >> sh) & m < tokens)

            for key in enabled[:STUBBORN_KEYS]:
                got = _stubborn_set(row, reducing, set(enabled), key, lacking)
                if got is not None and (best is None or len(got) < len(best)):
                    best = got
            if best is not None and len(best) < len(enabled):
                reduced = successors(row, a, sorted(best))
                if not any(x in on_stack for x in reduced):   # the proviso
                    return reduced
        return successors(row, a, enabled)

    start = tuple(int(x) for x in np.asarray(m0).ravel())
    try:
        for a in buchi.initial.tolist():
            if required[a] & atoms(start) != required[a] or (start, a) in number:
                continue
            first = (start, a)
            number[first] = len(number) + 1
            open_, roots = [first], [[number[first], accepting[a]]]
            on_stack.add(first)
            call = [(first, expand(*first), [0])]
            while call:
                p, todo, at = call[-1]
                if at[0] < len(todo):
                    q = todo[at[0]]
                    at[0] += 1
                    if q not in number:
                        if len(number) >= max_states:
                            return LtlCode.LIMIT, len(number), 0
                        if time.monotonic() > deadline:
                            return LtlCode.TIME, len(number), 0
                        number[q] = len(number) + 1
                        open_.append(q)
                        roots.append([number[q], accepting[q[1]]])
                        on_stack.add(q)
                        call.append((q, expand(*q), [0]))
                    elif number[q] > 0:
                        # a cycle closes: every root above q's joins the component below
                        met = 0
                        while roots[-1][0] > number[q]:
                            met |= roots.pop()[1]
                        roots[-1][1] |= met
                        if roots[-1][1] == buchi.all:
                            return LtlCode.ACCEPTING, len(number), 0
                    continue
                call.pop()
                on_stack.discard(p)
                if roots[-1][0] == number[p]:
                    roots.pop()
                    while True:
                        w = open_.pop()
                        number[w] = -abs(number[w])
                        if w == p:
                            break
    except _Overflow as e:
        return LtlCode.OVERFLOW, len(number), e.place
    except _Growing:
        return LtlCode.GROWING, len(number), 0
    return LtlCode.HOLDS, len(number), 0


class _Overflow(Exception):
    def __init__(self, place: int):
        self.place = place


class _Growing(Exception):
    pass
