"""The loops in plain Python: the reference backend of
:class:`~mcl2pnml.analysis.statespace.loops.interface.Loops`.

The same algorithms as the C loops (``_native.c``), written to be read: a
marking is a tuple of words (Python integers), the set of markings found a
dict from marking to position, each transition tested on every word. It
serves where the C extension was not built, and the shared tests run it on
their small nets beside C (tests/test_statespace.py, test_graph_kernels.py,
test_onthefly.py), so that the two are held to one behaviour. The order in
which a marking tries its transitions is C's (the key index's: the free
transitions, then those keyed on each marked place upwards), so that both
find the same markings in the same order and the same counterexamples.
Slower than C by the interpreter's factor: for the tests' nets, and for a
machine without a C compiler.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from mcl2pnml.analysis.statespace.loops.interface import (Code, CounterNet, CounterSearch, Fields,
                                                          Index, KeyIndex, Observer,
                                                          ProductSearch, SafeNet, SafeSearch,
                                                          Stubborn)

name = "python"

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


def _lists(a: np.ndarray) -> list:
    return [tuple(int(x) for x in r) for r in a]


class _Safe:
    """A safe net's masks as Python integers, one tuple of words a transition."""

    def __init__(self, net: SafeNet):
        self.need, self.keep, self.give = _lists(net.need), _lists(net.keep), _lists(net.give)
        self.take = _lists(net.take)

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


def _candidates(row: Row, key: KeyIndex) -> list[int]:
    """The transitions a marking tries, in the C loops' order (see the module)."""
    out = [int(t) for t in key.free]
    for w, x in enumerate(row):
        while x:
            low = x & -x
            out.extend(int(t) for t in key.by_place.of(w * 64 + low.bit_length() - 1))
            x ^= low
    return out


def _index(queue: np.ndarray, count: int) -> dict[Row, int]:
    return {_row(queue, i): i for i in range(count)}


# -- a safe net --------------------------------------------------------------------------------

def safe_search(net: SafeNet, m0: np.ndarray, max_states: int) -> SafeSearch:
    queue = np.empty((1024, net.words) if net.words > 1 else 1024, dtype=np.uint64)
    queue = _put(queue, 0, tuple(int(w) for w in m0))
    return SafeSearch(queue, 1, 0, _index(queue, 1), 0)


def safe_step(net: SafeNet, search: SafeSearch, max_states: int, budget: int) -> SafeSearch:
    tables, found = _Safe(net), search.table
    queue, count, head = search.queue, search.count, search.head
    stop = head + budget
    while head < count and head < stop:
        row = _row(queue, head)
        for t in _candidates(row, net.key):
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
    return np.array([sum(tables.enables(row, t) for t in _candidates(row, net.key))
                     for row in map(tuple, _lists(rows))], dtype=np.int32)


def live(rows: np.ndarray, net: SafeNet) -> np.ndarray:
    return (out_degree(rows, net) > 0).astype(np.int32)


def edges(rows: np.ndarray, net: SafeNet, ids: np.ndarray, order: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node i is row ``order[i]`` (``order`` its own inverse); its edges by transition."""
    tables, position = _Safe(net), _index(rows, len(rows))
    out = []
    for i, r in enumerate(order.tolist()):
        row = _row(rows, r)
        out += sorted((i, int(ids[t]), int(order[position[tables.fire(row, t)]]))
                      for t in _candidates(row, net.key) if tables.enables(row, t))
    src, trans, dst = (np.array(x, dtype=np.int32) for x in zip(*out)) if out else \
        (np.zeros(0, dtype=np.int32),) * 3
    return src, trans, dst


def backward(rows: np.ndarray, net: SafeNet, unfire: KeyIndex, seen: np.ndarray,
             frontier: np.ndarray) -> np.ndarray:
    """Mark in ``seen`` every row that reaches one of ``frontier`` (seen already), breadth
    first by unfiring: only the transitions keyed on the places marked after are tried."""
    tables, position = _Safe(net), _index(rows, len(rows))
    todo = [int(n) for n in frontier]
    for a in todo:           # the list grows as it is walked: first in, first out
        after = _row(rows, a)
        for t in _candidates(after, unfire):
            j = position.get(tables.unfire(after, t))
            if j is not None and not seen[j]:
                seen[j] = True
                todo.append(j)
    return seen


# -- a bounded net -----------------------------------------------------------------------------

def _field(row: Row, f: Fields, k: int) -> int:
    return (row[int(f.word[k])] >> int(f.shift[k])) & int(f.mask[k])


def _counter_enabled(row: Row, net: CounterNet, t: int) -> bool:
    n = net.need
    return all(_field(row, n, k) >= int(n.value[k]) for k in range(n.ptr[t], n.ptr[t + 1]))


def _counter_fire(row: Row, net: CounterNet, t: int, sign: int) -> tuple[Row | None, int]:
    """``row`` changed by ``sign`` times t's change, or None and the first field that would
    leave its range (below 0 or past its mask)."""
    d, out = net.change, list(row)
    for k in range(d.ptr[t], d.ptr[t + 1]):
        w, shift, mask = int(d.word[k]), int(d.shift[k]), int(d.mask[k])
        value = ((out[w] >> shift) & mask) + sign * int(d.value[k])
        if not 0 <= value <= mask:
            return None, k
        out[w] = (out[w] & ~(mask << shift)) | (value << shift)
    return tuple(out), -1


def counter_search(queue: np.ndarray, parent: np.ndarray, count: int, head: int,
                   dead: int = 0) -> CounterSearch:
    return CounterSearch(queue, parent, count, head, Index(_index(queue, count), 0), dead)


def counter_step(net: CounterNet, search: CounterSearch, max_states: int,
                 budget: int) -> CounterSearch:
    found = search.index.table
    queue, parent, count, head, dead = (search.queue, search.parent, search.count, search.head,
                                        search.dead)

    def stopped(code: Code, info: int = 0) -> CounterSearch:
        return CounterSearch(queue, parent, count, head, search.index, dead, code, info)

    stop = head + budget
    while head < count and head < stop:
        row, fired = _row(queue, head), False
        for t in range(net.transitions):
            if not _counter_enabled(row, net, t):
                continue
            fired = True
            if net.growing[t]:
                return stopped(Code.GROWING, t)
            after, k = _counter_fire(row, net, t, 1)
            if after is None:
                return stopped(Code.OVERFLOW, int(net.change.place[k]))
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
    return np.array([sum(_counter_enabled(_row(rows, q), net, t) for t in range(net.transitions))
                     for q in range(len(rows))], dtype=np.int32)


def counter_edges(rows: np.ndarray, index: Index, net: CounterNet, total: int
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    out = [(q, t, index.table[_counter_fire(_row(rows, q), net, t, 1)[0]])
           for q in range(len(rows)) for t in range(net.transitions)
           if _counter_enabled(_row(rows, q), net, t)]
    src, trans, dst = (np.array(x, dtype=np.int32) for x in zip(*out)) if out else \
        (np.zeros(0, dtype=np.int32),) * 3
    return src, trans, dst


def counter_backward(rows: np.ndarray, net: CounterNet, seen: np.ndarray,
                     frontier: np.ndarray) -> np.ndarray:
    """Unfiring: the only marking t comes from is the one after minus t's change; it is a
    predecessor when it is a found marking and enables t."""
    position = _index(rows, len(rows))
    todo = [int(n) for n in frontier]
    for a in todo:
        after = _row(rows, a)
        for t in range(net.transitions):
            before, _ = _counter_fire(after, net, t, -1)
            if before is None or not _counter_enabled(before, net, t):
                continue
            j = position.get(before)
            if j is not None and not seen[j]:
                seen[j] = True
                todo.append(j)
    return seen


# -- a property's product ----------------------------------------------------------------------

def _observe(row: Row, observer: Observer, state: int) -> int:
    """The observer's state after reading the marking (the row's words but the last)."""
    letter = 0
    for a, (mask, least) in enumerate(zip(observer.atoms.tolist(), observer.least.tolist())):
        if sum(bin(x & m).count("1") for x, m in zip(row, mask)) >= least:
            letter |= 1 << a
    return int(observer.move[state * 16 + int(observer.letters[letter])])


def _stubborn_set(row: Row, st: Stubborn, enabled: set[int], key: int) -> list[int] | None:
    """The enabled members of the stubborn set grown from the enabled ``key`` (C's
    ``stubborn_set``: an enabled member brings the transitions that consume a place it
    needs and those that need a place it consumes; a disabled one those that mark its
    first empty needed place), or None if one is visible."""
    members, work, out = {key}, [key], []
    while work:
        t = work.pop()
        if t in enabled:
            if st.visible[t]:
                return None
            out.append(t)
            brought = [int(u) for p in st.needs.of(t) for u in st.takers.of(int(p))]
            brought += [int(u) for p in st.pre.of(t) for u in st.needers.of(int(p))]
        else:
            empty = [int(p) for p in st.needs.of(t) if not row[int(p) // 64] >> (int(p) % 64) & 1]
            brought = [int(u) for u in st.makers.of(empty[0])] if empty else []
        for u in brought:
            if u not in members:
                members.add(u)
                work.append(u)
    return out


def _to_fire(row: Row, net: SafeNet, tables: _Safe, st: Stubborn) -> tuple[list[int], int]:
    """The row's enabled transitions, a smallest stubborn set's first, and how many of them
    to fire unless the proviso asks for all (all of them without reduction)."""
    fire = list(dict.fromkeys(t for t in _candidates(row, net.key) if tables.enables(row, t)))
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
    return ProductSearch(queue, 1, 0, Index(_index(queue, 1), 0), parent, via, depth)


def product_step(net: SafeNet, observer: Observer, stubborn: Stubborn, search: ProductSearch,
                 max_states: int, budget: int) -> ProductSearch:
    """Breadth first to the first violation, as C's ``product_step`` (read its comment):
    a successor in the bad state is only the shortest violation once its level is done;
    a dead row with an obligation open is one at once."""
    tables, found_rows = _Safe(net), search.index.table
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
        fire, reduced = _to_fire(marking, net, tables, stubborn)
        n, old, c = reduced, False, 0
        while c < n:
            t = fire[c]
            after = tables.fire(marking, t)
            if after is None:
                return stopped(Code.NOT_SAFE)
            after += (_observe(after, observer, state),)
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
                if after[-1] == observer.bad and found < 0:
                    found = count
                count += 1
            if c == n - 1 and n < len(fire) and old:
                n = len(fire)   # the proviso: a reduced row meeting an old one fires all
            c += 1
        if not fire and observer.pending[state]:
            found = head
            return stopped(Code.FOUND_DEAD)
        head += 1
    return stopped(Code.FOUND_BAD if found >= 0 and head == count else Code.GOING)


def product_edges(net: SafeNet, observer: Observer, search: ProductSearch, first: int,
                  room: int) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """The arcs between pending rows from row ``first`` on (every one: ``room`` is only
    C's bound on a call)."""
    tables, position = _Safe(net), search.index.table
    out = []
    for i in range(first, search.count):
        row = _row(search.queue, i)
        if not observer.pending[row[-1]]:
            continue
        for t in _candidates(row[:-1], net.key):
            after = tables.fire(row[:-1], t) if tables.enables(row[:-1], t) else None
            if after is None:
                continue
            after += (_observe(after, observer, row[-1]),)
            if observer.pending[after[-1]] and after in position:
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
