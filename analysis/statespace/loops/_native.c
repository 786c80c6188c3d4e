/* The exploration loops in C: the C backend of analysis/statespace/loops/interface.py.
 *
 * The same loops as analysis/statespace/loops/python.py, their plain-Python
 * reference (read it for the algorithms: a breadth-first queue of markings
 * packed into 64-bit words, an open-addressing hash set with linear probing,
 * each transition keyed on one place it needs), built once when mcl2pnml is
 * installed: loading them costs a millisecond and a few hundred kilobytes.
 * analysis/statespace/loops/c.py is the one caller of these functions and
 * the one place that knows their positional signatures. The shared test
 * suite runs both backends on the same nets.
 *
 * The functions take numpy arrays through the buffer protocol and never
 * allocate them: when the queue or the table is full, a step returns
 * QUEUE_FULL or TABLE_FULL before expanding the marking at the head, and the
 * Python side grows the array and calls again, so every byte is a numpy array
 * that the memory budget sees.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <string.h>
#include <time.h>

enum { GOING = 0, NOT_SAFE = 1, LIMIT = 2, QUEUE_FULL = 3, TABLE_FULL = 4 };

static const uint64_t GOLDEN = 0x9E3779B97F4A7C15ULL;

static inline int64_t slot_one(uint64_t m, int bits) {
    return (int64_t)((m * GOLDEN) >> (64 - bits));
}

/* A row's 64-bit hash: its top bits (times GOLDEN) choose the slot, its low 32 bits are
 * the fingerprint kept in the slot. */
static inline uint64_t hash_row(const uint64_t *row, int64_t words) {
    uint64_t h = 0;
    for (int64_t w = 0; w < words; w++) {
        h = (h ^ row[w]) * GOLDEN;
        h ^= h >> 29;
    }
    return h;
}

static inline int64_t slot_of_hash(uint64_t h, int bits) {
    return (int64_t)((h * GOLDEN) >> (64 - bits));
}

static inline int64_t slot_row(const uint64_t *row, int64_t words, int bits) {
    return slot_of_hash(hash_row(row, words), bits);
}

/* A slot of a table of rows: the fingerprint in the high half, the position + 1 in the
 * low half (0: free). A probe reads the row itself only when the fingerprints agree, so
 * an unsuccessful search (six probes at 70% full) costs one cache miss, not six. */
static inline uint64_t entry(uint64_t h, int64_t position) {
    return ((h & 0xFFFFFFFFULL) << 32) | (uint64_t)(position + 1);
}

/* The transitions keyed on the marked places of row (and the free ones), into out. */
static inline int64_t candidates(const uint64_t *row, int64_t words, const int64_t *key_ptr,
                                 const int64_t *key_t, const int64_t *free_t, int64_t nfree,
                                 int64_t *out) {
    int64_t n = 0;
    for (int64_t i = 0; i < nfree; i++)
        out[n++] = free_t[i];
    for (int64_t w = 0; w < words; w++) {
        uint64_t x = row[w];
        while (x) {
            int64_t p = w * 64 + __builtin_ctzll(x);
            x &= x - 1;
            for (int64_t k = key_ptr[p]; k < key_ptr[p + 1]; k++)
                out[n++] = key_t[k];
        }
    }
    return n;
}

/* -- arguments ------------------------------------------------------------------------- */

/* The buffers of one call, released together whatever happens. */
#define MAX_BUFFERS 48

typedef struct {
    Py_buffer views[MAX_BUFFERS];
    int count;
} Buffers;

static void release(Buffers *b) {
    for (int i = 0; i < b->count; i++)
        PyBuffer_Release(&b->views[i]);
    b->count = 0;
}

/* The data of a C-contiguous buffer of `itemsize`-byte items; NULL and an exception if not. */
static void *data_of(Buffers *b, PyObject *obj, Py_ssize_t itemsize, int writable) {
    if (b->count == MAX_BUFFERS) {
        PyErr_SetString(PyExc_ValueError, "too many arrays for one call");
        return NULL;
    }
    Py_buffer *v = &b->views[b->count];
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, v, flags) < 0)
        return NULL;
    b->count++;
    if (v->itemsize != itemsize) {
        PyErr_Format(PyExc_TypeError, "expected items of %zd bytes, got %zd", itemsize,
                     v->itemsize);
        return NULL;
    }
    return v->buf;
}

static Py_ssize_t items_of(Buffers *b) { return b->views[b->count - 1].len / b->views[b->count - 1].itemsize; }

/* The masks every loop reads, in the order of the Python signatures. */
typedef struct {
    const uint64_t *need, *keep, *give;
    const int64_t *need_ptr, *need_word, *touch_ptr, *touch_word, *key_ptr, *key_t, *free_t;
    int64_t transitions, words, nfree;
} Masks;

/* -- exploring ------------------------------------------------------------------------- */

static inline int enables(const uint64_t *row, const Masks *m, int64_t t) {
    for (int64_t k = m->need_ptr[t]; k < m->need_ptr[t + 1]; k++) {
        int64_t w = m->need_word[k];
        uint64_t need = m->need[t * m->words + w];
        if ((row[w] & need) != need)
            return 0;
    }
    return 1;
}

/* Markings are looked up in batches: the successors (or predecessors) of one marking are
 * built and hashed first and their slots fetched ahead (__builtin_prefetch), then probed,
 * so that the cache misses of a batch overlap instead of following one another. */
#define BATCH 32

static inline int64_t probe(const uint64_t *queue, int64_t words, const uint64_t *table,
                            int64_t mask, const uint64_t *row, uint64_t fp, int64_t i,
                            int64_t *slot) {
    while (table[i] != 0) {
        if ((table[i] >> 32) == fp) {
            int64_t j = (int64_t)(table[i] & 0xFFFFFFFFULL) - 1;
            if (memcmp(queue + j * words, row, (size_t)words * 8) == 0)
                return j;
        }
        i = (i + 1) & mask;
    }
    *slot = i;
    return -1;
}

/* The second stage of a batch: where the home slot's fingerprint agrees, fetch the
 * marking that the probe will compare (the slots were fetched in the first stage). */
static inline void prefetch_rows(const uint64_t *queue, int64_t words, const uint64_t *table,
                                 int bits, const uint64_t *hashes, int nb) {
    for (int i = 0; i < nb; i++) {
        uint64_t e = table[slot_of_hash(hashes[i], bits)];
        if (e != 0 && (e >> 32) == (hashes[i] & 0xFFFFFFFFULL))
            __builtin_prefetch(queue + ((int64_t)(e & 0xFFFFFFFFULL) - 1) * words);
    }
}

/* Position of row among queue's rows that table (entries, 0 free) holds, or -1 with the
 * free *slot and the row's hash *h. */
static inline int64_t find(const uint64_t *queue, int64_t words, const uint64_t *table, int bits,
                           const uint64_t *row, int64_t *slot, uint64_t *h) {
    int64_t mask = ((int64_t)1 << bits) - 1;
    *h = hash_row(row, words);
    uint64_t fp = *h & 0xFFFFFFFFULL;
    int64_t i = slot_of_hash(*h, bits);
    return probe(queue, words, table, mask, row, fp, i, slot);
}

static PyObject *py_step_words(PyObject *self, PyObject *args) {
    PyObject *o[14];
    long long count, head, max_states, budget;
    int bits;
    if (!PyArg_ParseTuple(args, "OOOOOOOOOOOLLOiLL", &o[0], &o[1], &o[2], &o[3], &o[4], &o[5],
                          &o[6], &o[7], &o[8], &o[9], &o[10], &count, &head, &o[11], &bits,
                          &max_states, &budget))
        return NULL;
    Buffers b = {.count = 0};
    Masks m;
    uint64_t *queue, *table;
    if (!(m.need = data_of(&b, o[0], 8, 0))) goto fail;
    m.transitions = items_of(&b);
    if (!(m.keep = data_of(&b, o[1], 8, 0)) || !(m.give = data_of(&b, o[2], 8, 0))
        || !(m.need_ptr = data_of(&b, o[3], 8, 0)) || !(m.need_word = data_of(&b, o[4], 8, 0))
        || !(m.touch_ptr = data_of(&b, o[5], 8, 0)) || !(m.touch_word = data_of(&b, o[6], 8, 0))
        || !(m.key_ptr = data_of(&b, o[7], 8, 0)) || !(m.key_t = data_of(&b, o[8], 8, 0))
        || !(m.free_t = data_of(&b, o[9], 8, 0)))
        goto fail;
    m.nfree = items_of(&b);
    if (!(queue = data_of(&b, o[10], 8, 1))) goto fail;
    m.words = b.views[b.count - 1].ndim == 2 ? b.views[b.count - 1].shape[1] : 1;
    int64_t capacity = items_of(&b) / m.words;
    m.transitions /= m.words;
    if (!(table = data_of(&b, o[11], 8, 1))) goto fail;
    int64_t table_size = items_of(&b);

    int code = GOING;
    int64_t *cand = PyMem_Malloc(sizeof(int64_t) * (size_t)(m.transitions + 1));
    uint64_t *next = PyMem_Malloc(8 * BATCH * (size_t)m.words), hashes[BATCH];
    if (!cand || !next) { PyMem_Free(cand); PyMem_Free(next); PyErr_NoMemory(); goto fail; }
    Py_BEGIN_ALLOW_THREADS
    int64_t stop = head + budget, words = m.words;
    while (head < count && head < stop) {
        /* room for every successor of the head first, so that no marking is half expanded */
        if (count + m.transitions > capacity) { code = QUEUE_FULL; break; }
        if (10 * (count + m.transitions) > 7 * table_size) { code = TABLE_FULL; break; }
        const uint64_t *row = queue + head * words;
        int64_t n = candidates(row, words, m.key_ptr, m.key_t, m.free_t, m.nfree, cand);
        int64_t c = 0, tmask = ((int64_t)1 << bits) - 1;
        while (c < n && code == GOING) {
            int nb = 0;
            for (; c < n && nb < BATCH; c++) {
                int64_t t = cand[c];
                if (!enables(row, &m, t))
                    continue;
                uint64_t *nx = next + nb * words;
                memcpy(nx, row, 8 * (size_t)words);
                for (int64_t k = m.touch_ptr[t]; k < m.touch_ptr[t + 1]; k++) {
                    int64_t w = m.touch_word[k];
                    uint64_t rest = nx[w] & m.keep[t * words + w];
                    if (rest & m.give[t * words + w]) { code = NOT_SAFE; break; }
                    nx[w] = rest | m.give[t * words + w];
                }
                if (code != GOING)
                    break;
                hashes[nb] = hash_row(nx, words);
                __builtin_prefetch(&table[slot_of_hash(hashes[nb], bits)]);
                nb++;
            }
            prefetch_rows(queue, words, table, bits, hashes, nb);
            for (int i = 0; i < nb && code == GOING; i++) {
                const uint64_t *nx = next + i * words;
                int64_t slot = -1;
                if (probe(queue, words, table, tmask, nx, hashes[i] & 0xFFFFFFFFULL,
                          slot_of_hash(hashes[i], bits), &slot) >= 0)
                    continue;
                if (count >= max_states) { code = LIMIT; break; }
                memcpy(queue + count * words, nx, 8 * (size_t)words);
                table[slot] = entry(hashes[i], count++);
            }
        }
        if (code != GOING)
            break;
        head++;
    }
    Py_END_ALLOW_THREADS
    PyMem_Free(cand);
    PyMem_Free(next);
    release(&b);
    return Py_BuildValue("LLi", (long long)count, (long long)head, code);
fail:
    release(&b);
    return NULL;
}

static PyObject *py_step_one_word(PyObject *self, PyObject *args) {
    PyObject *o[8];
    long long count, head, max_states, budget;
    int bits, zero_seen;
    if (!PyArg_ParseTuple(args, "OOOOOOOLLOipLL", &o[0], &o[1], &o[2], &o[3], &o[4], &o[5],
                          &o[6], &count, &head, &o[7], &bits, &zero_seen, &max_states, &budget))
        return NULL;
    Buffers b = {.count = 0};
    const uint64_t *need, *keep, *give;
    const int64_t *key_ptr, *key_t, *free_t;
    uint64_t *queue, *table;
    if (!(need = data_of(&b, o[0], 8, 0))) goto fail;
    int64_t transitions = items_of(&b);
    if (!(keep = data_of(&b, o[1], 8, 0)) || !(give = data_of(&b, o[2], 8, 0))
        || !(key_ptr = data_of(&b, o[3], 8, 0)) || !(key_t = data_of(&b, o[4], 8, 0))
        || !(free_t = data_of(&b, o[5], 8, 0)))
        goto fail;
    int64_t nfree = items_of(&b);
    if (!(queue = data_of(&b, o[6], 8, 1))) goto fail;
    int64_t capacity = items_of(&b);
    if (!(table = data_of(&b, o[7], 8, 1))) goto fail;
    int64_t table_size = items_of(&b);

    int code = GOING;
    int64_t *cand = PyMem_Malloc(sizeof(int64_t) * (size_t)(transitions + 1));
    if (!cand) { PyErr_NoMemory(); goto fail; }
    Py_BEGIN_ALLOW_THREADS
    int64_t stop = head + budget, mask = ((int64_t)1 << bits) - 1;
    while (head < count && head < stop) {
        if (count + transitions > capacity) { code = QUEUE_FULL; break; }
        if (10 * (count + transitions) > 7 * table_size) { code = TABLE_FULL; break; }
        uint64_t m = queue[head], batch[BATCH];
        int64_t n = candidates(&m, 1, key_ptr, key_t, free_t, nfree, cand);
        int64_t c = 0;
        while (c < n && code == GOING) {
            int nb = 0;
            for (; c < n && nb < BATCH; c++) {
                int64_t t = cand[c];
                if ((m & need[t]) != need[t])
                    continue;
                uint64_t rest = m & keep[t];
                if (rest & give[t]) { code = NOT_SAFE; break; }
                batch[nb] = rest | give[t];
                __builtin_prefetch(&table[slot_one(batch[nb], bits)]);
                nb++;
            }
            for (int j = 0; j < nb && code == GOING; j++) {
                uint64_t next = batch[j];
                int64_t i = 0;
                if (next == 0) {
                    /* the empty marking cannot be told from a free slot: remembered apart */
                    if (zero_seen)
                        continue;
                } else {
                    i = slot_one(next, bits);
                    while (table[i] != 0 && table[i] != next)
                        i = (i + 1) & mask;
                    if (table[i] == next)
                        continue;
                }
                if (count >= max_states) { code = LIMIT; break; }
                if (next == 0)
                    zero_seen = 1;
                else
                    table[i] = next;
                queue[count++] = next;
            }
        }
        if (code != GOING)
            break;
        head++;
    }
    Py_END_ALLOW_THREADS
    PyMem_Free(cand);
    release(&b);
    return Py_BuildValue("LLNi", (long long)count, (long long)head, PyBool_FromLong(zero_seen),
                         code);
fail:
    release(&b);
    return NULL;
}

/* rehash(queue, count, table, bits, values): the first count rows of queue into table (all
 * 0, free): the markings themselves (values: one word), or their entries. */
static PyObject *py_rehash(PyObject *self, PyObject *args) {
    PyObject *oq, *ot;
    long long count;
    int bits, by_value;
    if (!PyArg_ParseTuple(args, "OLOip", &oq, &count, &ot, &bits, &by_value))
        return NULL;
    Buffers b = {.count = 0};
    uint64_t *queue, *table;
    if (!(queue = data_of(&b, oq, 8, 0))) goto fail;
    int64_t words = b.views[0].ndim == 2 ? b.views[0].shape[1] : 1;
    if (!(table = data_of(&b, ot, 8, 1))) goto fail;
    int64_t mask = ((int64_t)1 << bits) - 1;
    for (int64_t q = 0; q < count; q++) {
        int64_t i;
        uint64_t value;
        if (by_value) {
            if ((value = queue[q]) == 0) continue;
            i = slot_one(value, bits);
        } else {
            uint64_t h = hash_row(queue + q * words, words);
            i = slot_of_hash(h, bits);
            value = entry(h, q);
        }
        while (table[i] != 0) i = (i + 1) & mask;
        table[i] = value;
    }
    release(&b);
    Py_RETURN_NONE;
fail:
    release(&b);
    return NULL;
}

/* -- a property's product, explored on the fly ----------------------------------------- */

/* The product of the net with a property's observer (analysis/checking/on_the_fly.py): a row is the
 * marking's words and one more word, the observer's state. The observer reads each new
 * marking through its atoms (a set of places and a least number of tokens among them:
 * popcount, the net being safe): code_of[atom bits] is the marking's letter (P S Q R as
 * four bits), move[state * 16 + letter] the observer's next state. The search stops at
 * the first violation found breadth first: a successor in the state `bad` (its position,
 * FOUND_BAD) or a dead marking with an obligation open (the head's position, FOUND_DEAD).
 * A successor in `bad` one firing deeper than the head is only the shortest violation
 * once the head's level is done (a dead marking there is shorter): the level is finished
 * first. parent, via (the transition) and depth of each row make the way back. */
enum { FOUND_BAD = 7, FOUND_DEAD = 8 };

typedef struct {
    const uint64_t *atoms;
    const int64_t *least, *code_of, *move;
    const uint8_t *pend;
    int64_t natoms, bad;
} Observer;

static inline int64_t observe(const uint64_t *row, int64_t words, const Observer *o,
                              int64_t state) {
    int64_t bits = 0;
    for (int64_t a = 0; a < o->natoms; a++) {
        int64_t n = 0;
        const uint64_t *mask = o->atoms + a * words;
        for (int64_t w = 0; w < words; w++)
            n += __builtin_popcountll(row[w] & mask[w]);
        if (n >= o->least[a])
            bits |= (int64_t)1 << a;
    }
    return o->move[state * 16 + o->code_of[bits]];
}

static int observer_of(Buffers *b, PyObject **objs, Observer *o) {
    if (!(o->atoms = data_of(b, objs[0], 8, 0))) return 0;
    if (!(o->least = data_of(b, objs[1], 8, 0))) return 0;
    o->natoms = items_of(b);
    if (!(o->code_of = data_of(b, objs[2], 8, 0)) || !(o->move = data_of(b, objs[3], 8, 0))
        || !(o->pend = data_of(b, objs[4], 1, 0)))
        return 0;
    return 1;
}

static int masks_of(Buffers *b, PyObject **objs, Masks *m) {
    if (!(m->need = data_of(b, objs[0], 8, 0))) return 0;
    m->words = b->views[b->count - 1].ndim == 2 ? b->views[b->count - 1].shape[1] : 1;
    m->transitions = items_of(b) / m->words;
    if (!(m->keep = data_of(b, objs[1], 8, 0)) || !(m->give = data_of(b, objs[2], 8, 0))
        || !(m->need_ptr = data_of(b, objs[3], 8, 0)) || !(m->need_word = data_of(b, objs[4], 8, 0))
        || !(m->touch_ptr = data_of(b, objs[5], 8, 0)) || !(m->touch_word = data_of(b, objs[6], 8, 0))
        || !(m->key_ptr = data_of(b, objs[7], 8, 0)) || !(m->key_t = data_of(b, objs[8], 8, 0))
        || !(m->free_t = data_of(b, objs[9], 8, 0)))
        return 0;
    m->nfree = items_of(b);
    return 1;
}

/* The successor of row by t into nx (the marking's words): 0, or NOT_SAFE. */
static inline int fire_into(const uint64_t *row, uint64_t *nx, const Masks *m, int64_t t) {
    memcpy(nx, row, 8 * (size_t)m->words);
    for (int64_t k = m->touch_ptr[t]; k < m->touch_ptr[t + 1]; k++) {
        int64_t w = m->touch_word[k];
        uint64_t rest = nx[w] & m->keep[t * m->words + w];
        if (rest & m->give[t * m->words + w])
            return NOT_SAFE;
        nx[w] = rest | m->give[t * m->words + w];
    }
    return 0;
}

/* The net's structure for stubborn sets (analysis/checking/on_the_fly.py, Valmari's method on a safe
 * net): the places each transition consumes and needs (consumes or reads), the
 * transitions that consume, need and mark each place, and which transitions are visible
 * (change a place the observer reads). */
typedef struct {
    const int64_t *t_pre_ptr, *t_pre, *t_need_ptr, *t_need, *p_take_ptr, *p_take,
        *p_need_ptr, *p_need, *p_make_ptr, *p_make;
    const uint8_t *visible;
    int on;
} Stubborn;

static int stubborn_of(Buffers *b, PyObject **objs, Stubborn *st) {
    const int64_t **f[10] = {&st->t_pre_ptr, &st->t_pre, &st->t_need_ptr, &st->t_need,
                             &st->p_take_ptr, &st->p_take, &st->p_need_ptr, &st->p_need,
                             &st->p_make_ptr, &st->p_make};
    for (int i = 0; i < 10; i++)
        if (!(*f[i] = data_of(b, objs[i], 8, 0)))
            return 0;
    if (!(st->visible = data_of(b, objs[10], 1, 0)))
        return 0;
    return 1;
}

static inline int marked(const uint64_t *row, int64_t p) {
    return (int)((row[p >> 6] >> (p & 63)) & 1);
}

/* An enabled member t of a stubborn set brings every transition that consumes a place t
 * needs (it may disable t) and every one that needs a place t consumes (t may disable
 * it): pushed on work (in[u] == stamp marks a member). */
static inline void bring_conflicts(const Stubborn *st, int64_t t, int64_t *in, int64_t stamp,
                                   int64_t *work, int64_t *top) {
    for (int64_t k = st->t_need_ptr[t]; k < st->t_need_ptr[t + 1]; k++) {
        int64_t p = st->t_need[k];
        for (int64_t j = st->p_take_ptr[p]; j < st->p_take_ptr[p + 1]; j++) {
            int64_t u = st->p_take[j];
            if (in[u] != stamp) { in[u] = stamp; work[(*top)++] = u; }
        }
    }
    for (int64_t k = st->t_pre_ptr[t]; k < st->t_pre_ptr[t + 1]; k++) {
        int64_t p = st->t_pre[k];
        for (int64_t j = st->p_need_ptr[p]; j < st->p_need_ptr[p + 1]; j++) {
            int64_t u = st->p_need[j];
            if (in[u] != stamp) { in[u] = stamp; work[(*top)++] = u; }
        }
    }
}

/* The stubborn set grown from the enabled transition `key` (in[t] == stamp marks a member,
 * work is a stack): an enabled member brings every transition that consumes a place it
 * needs (which may disable it) and every one that needs a place it consumes (which it may
 * disable); a disabled one every transition that marks one of its empty needed places
 * (the first: a reason it waits). Its enabled members go to out; returns their number,
 * or -1 if one is visible (the set would hide a step the observer sees). */
static int64_t stubborn_set(const uint64_t *row, const Masks *m, const Stubborn *st,
                            const uint8_t *is_enabled, int64_t key, int64_t *in, int64_t stamp,
                            int64_t *work, int64_t *out) {
    int64_t top = 0, n = 0;
    in[key] = stamp;
    work[top++] = key;
    while (top > 0) {
        int64_t t = work[--top];
        if (is_enabled[t]) {
            if (st->visible[t])
                return -1;
            out[n++] = t;
            bring_conflicts(st, t, in, stamp, work, &top);
        } else {
            for (int64_t k = st->t_need_ptr[t]; k < st->t_need_ptr[t + 1]; k++) {
                int64_t p = st->t_need[k];
                if (marked(row, p))
                    continue;
                for (int64_t j = st->p_make_ptr[p]; j < st->p_make_ptr[p + 1]; j++) {
                    int64_t u = st->p_make[j];
                    if (in[u] != stamp) { in[u] = stamp; work[top++] = u; }
                }
                break;
            }
        }
    }
    (void)m;
    return n;
}

/* product_step(10 masks, 5 observer arrays, bad, queue, count, head, table, bits, parent,
 * via, depth, found, max_states, budget, 11 stubborn arrays, reduce) -> (count, head, code,
 * found); found: the bad row met so far (-1: none), whose level is being finished. With
 * reduce, a row fires only the enabled members of a stubborn set with no visible member
 * (the smallest found from each enabled key), unless one of their successors is a row
 * met before at this depth or less, which then fires everything (the cycle proviso in
 * breadth-first form: a cycle has an arc that does not go deeper, so a row of each cycle
 * fires everything); C0-C3 of partial-order reduction, which keep the verdict of a
 * stutter-invariant observer (analysis/checking/on_the_fly.py checks it is one). */
static PyObject *py_product_step(PyObject *self, PyObject *args) {
    PyObject *o[31];
    long long bad, count, head, max_states, budget, found_in;
    int bits, reduce;
    if (!PyArg_ParseTuple(args, "OOOOOOOOOOOOOOOLOLLOiOOOLLLOOOOOOOOOOOp", &o[0], &o[1], &o[2],
                          &o[3], &o[4], &o[5], &o[6], &o[7], &o[8], &o[9], &o[10], &o[11],
                          &o[12], &o[13], &o[14], &bad, &o[15], &count, &head, &o[16], &bits,
                          &o[17], &o[18], &o[19], &found_in, &max_states, &budget, &o[20],
                          &o[21], &o[22], &o[23], &o[24], &o[25], &o[26], &o[27], &o[28],
                          &o[29], &o[30], &reduce))
        return NULL;
    Buffers b = {.count = 0};
    Masks m;
    Observer ob;
    Stubborn st;
    uint64_t *queue, *table;
    int64_t *parent, *via, *depth;
    if (!masks_of(&b, o, &m) || !observer_of(&b, o + 10, &ob)) goto fail;
    ob.bad = bad;
    if (!(queue = data_of(&b, o[15], 8, 1))) goto fail;
    int64_t width = m.words + 1;
    int64_t capacity = items_of(&b) / width;
    if (!(table = data_of(&b, o[16], 8, 1))) goto fail;
    int64_t table_size = items_of(&b);
    if (!(parent = data_of(&b, o[17], 8, 1)) || !(via = data_of(&b, o[18], 8, 1))
        || !(depth = data_of(&b, o[19], 8, 1)))
        goto fail;
    if (items_of(&b) < capacity) { PyErr_SetString(PyExc_ValueError, "depth too short"); goto fail; }
    if (!stubborn_of(&b, o + 20, &st)) goto fail;
    st.on = reduce;

    int code = GOING;
    int64_t found = found_in, T = m.transitions;
    int64_t *cand = PyMem_Malloc(sizeof(int64_t) * (size_t)(T + 1));
    int64_t *fire = PyMem_Malloc(sizeof(int64_t) * (size_t)(T + 1));
    int64_t *best = PyMem_Malloc(sizeof(int64_t) * (size_t)(T + 1));
    int64_t *set = PyMem_Malloc(sizeof(int64_t) * (size_t)(T + 1));
    int64_t *in = PyMem_Calloc((size_t)(T + 1), sizeof(int64_t));
    int64_t *work = PyMem_Malloc(sizeof(int64_t) * (size_t)(T + 1));
    uint8_t *is_enabled = PyMem_Calloc((size_t)(T + 1), 1);
    uint64_t *nx = PyMem_Malloc(8 * (size_t)width);
    if (!cand || !fire || !best || !set || !in || !work || !is_enabled || !nx) {
        PyMem_Free(cand); PyMem_Free(fire); PyMem_Free(best); PyMem_Free(set); PyMem_Free(in);
        PyMem_Free(work); PyMem_Free(is_enabled); PyMem_Free(nx);
        PyErr_NoMemory();
        goto fail;
    }
    Py_BEGIN_ALLOW_THREADS
    int64_t stop = head + budget, tmask = ((int64_t)1 << bits) - 1, stamp = 0;
    while (head < count && head < stop) {
        /* a bad row found, and its level above done: the shortest violation */
        if (found >= 0 && depth[head] >= depth[found]) { code = FOUND_BAD; break; }
        if (count + T > capacity) { code = QUEUE_FULL; break; }
        if (10 * (count + T) > 7 * table_size) { code = TABLE_FULL; break; }
        const uint64_t *row = queue + head * width;
        int64_t state = (int64_t)row[m.words];
        int64_t n = candidates(row, m.words, m.key_ptr, m.key_t, m.free_t, m.nfree, cand);
        int64_t ne = 0;
        for (int64_t c = 0; c < n; c++)
            if (!is_enabled[cand[c]] && enables(row, &m, cand[c])) {
                is_enabled[cand[c]] = 1;
                fire[ne++] = cand[c];
            }
        int enabled = ne > 0;
        /* the transitions to fire: a stubborn set's enabled members where one is smaller */
        int64_t nf = ne, nb = ne;
        if (st.on && ne > 1) {
            for (int64_t k = 0; k < ne && nb > 1; k++) {
                int64_t got = stubborn_set(row, &m, &st, is_enabled, fire[k], in, ++stamp, work,
                                           set);
                if (got > 0 && got < nb) {
                    nb = got;
                    memcpy(best, set, sizeof(int64_t) * (size_t)got);
                }
            }
            if (nb < ne) {
                /* the reduced set first, the others after it only if the proviso asks */
                stamp++;
                for (int64_t k = 0; k < nb; k++) in[best[k]] = stamp;
                int64_t r = nb;
                for (int64_t k = 0; k < ne; k++)
                    if (in[fire[k]] != stamp) best[r++] = fire[k];
                memcpy(fire, best, sizeof(int64_t) * (size_t)ne);
                nf = nb;
            }
        }
        for (int64_t k = 0; k < ne; k++)
            is_enabled[fire[k]] = 0;
        int old = 0;
        for (int64_t c = 0; c < nf && code == GOING; c++) {
            int64_t t = fire[c];
            if (fire_into(row, nx, &m, t) == NOT_SAFE) { code = NOT_SAFE; break; }
            nx[m.words] = (uint64_t)observe(nx, m.words, &ob, state);
            uint64_t h = hash_row(nx, width);
            int64_t slot = -1;
            int64_t seen = probe(queue, width, table, tmask, nx, h & 0xFFFFFFFFULL,
                                 slot_of_hash(h, bits), &slot);
            if (seen >= 0) {
                /* an arc back to this level or above: the one a cycle must have */
                if (depth[seen] <= depth[head])
                    old = 1;
            } else {
                if (count >= max_states) {
                    /* a violation already found is one, if not proven the shortest */
                    code = found >= 0 ? FOUND_BAD : LIMIT;
                    break;
                }
                memcpy(queue + count * width, nx, 8 * (size_t)width);
                table[slot] = entry(h, count);
                parent[count] = head;
                via[count] = t;
                depth[count] = depth[head] + 1;
                if ((int64_t)nx[m.words] == ob.bad && found < 0)
                    found = count;
                count++;
            }
            /* the proviso: a reduced row that meets a row seen before fires everything */
            if (c == nf - 1 && nf < ne && old)
                nf = ne;
        }
        if (code != GOING)
            break;
        if (!enabled && ob.pend[state]) { code = FOUND_DEAD; found = head; break; }
        head++;
    }
    if (code == GOING && found >= 0 && head == count)
        code = FOUND_BAD;
    Py_END_ALLOW_THREADS
    PyMem_Free(cand); PyMem_Free(fire); PyMem_Free(best); PyMem_Free(set); PyMem_Free(in);
    PyMem_Free(work); PyMem_Free(is_enabled);
    PyMem_Free(nx);
    release(&b);
    return Py_BuildValue("LLiL", (long long)count, (long long)head, code, (long long)found);
fail:
    release(&b);
    return NULL;
}

/* product_edges(10 masks, 5 observer arrays, queue, count, table, bits, first, src, dst,
 * trans) -> (next, edges): the arcs between rows whose observer state is pending (an
 * obligation open), from row `first` on, until the output arrays are full; a pending
 * row's edges are written whole or not at all. */
static PyObject *py_product_edges(PyObject *self, PyObject *args) {
    PyObject *o[20];
    long long count, first;
    int bits;
    if (!PyArg_ParseTuple(args, "OOOOOOOOOOOOOOOOLOiLOOO", &o[0], &o[1], &o[2], &o[3], &o[4],
                          &o[5], &o[6], &o[7], &o[8], &o[9], &o[10], &o[11], &o[12], &o[13],
                          &o[14], &o[15], &count, &o[16], &bits, &first, &o[17], &o[18], &o[19]))
        return NULL;
    Buffers b = {.count = 0};
    Masks m;
    Observer ob;
    const uint64_t *queue, *table;
    int64_t *src, *dst, *trans;
    if (!masks_of(&b, o, &m) || !observer_of(&b, o + 10, &ob)) goto fail;
    if (!(queue = data_of(&b, o[15], 8, 0)) || !(table = data_of(&b, o[16], 8, 0))) goto fail;
    if (!(src = data_of(&b, o[17], 8, 1)) || !(dst = data_of(&b, o[18], 8, 1))
        || !(trans = data_of(&b, o[19], 8, 1)))
        goto fail;
    int64_t room = items_of(&b), width = m.words + 1, edges = 0, i = first;
    int64_t *cand = PyMem_Malloc(sizeof(int64_t) * (size_t)(m.transitions + 1));
    uint64_t *nx = PyMem_Malloc(8 * (size_t)width);
    if (!cand || !nx) { PyMem_Free(cand); PyMem_Free(nx); PyErr_NoMemory(); goto fail; }
    Py_BEGIN_ALLOW_THREADS
    int64_t tmask = ((int64_t)1 << bits) - 1;
    for (; i < count; i++) {
        const uint64_t *row = queue + i * width;
        int64_t state = (int64_t)row[m.words];
        if (!ob.pend[state])
            continue;
        if (edges + m.transitions > room)
            break;
        int64_t n = candidates(row, m.words, m.key_ptr, m.key_t, m.free_t, m.nfree, cand);
        for (int64_t c = 0; c < n; c++) {
            int64_t t = cand[c], slot = -1;
            if (!enables(row, &m, t) || fire_into(row, nx, &m, t) == NOT_SAFE)
                continue;
            nx[m.words] = (uint64_t)observe(nx, m.words, &ob, state);
            if (!ob.pend[nx[m.words]])
                continue;
            uint64_t h = hash_row(nx, width);
            int64_t j = probe(queue, width, table, tmask, nx, h & 0xFFFFFFFFULL,
                              slot_of_hash(h, bits), &slot);
            if (j < 0)
                continue;   /* not explored: cannot be, the search was complete */
            src[edges] = i;
            dst[edges] = j;
            trans[edges++] = t;
        }
    }
    Py_END_ALLOW_THREADS
    PyMem_Free(cand);
    PyMem_Free(nx);
    release(&b);
    return Py_BuildValue("LL", (long long)i, (long long)edges);
fail:
    release(&b);
    return NULL;
}

/* -- the explored state space, asked again --------------------------------------------- */

/* out_degree(packed, need, need_ptr, need_word, key_ptr, key_t, free_t, degree, first):
 * how many transitions each marking enables; with first, 1 at the first one found (what
 * telling the dead markings needs, at a fraction of the cost). */
static PyObject *py_out_degree(PyObject *self, PyObject *args) {
    PyObject *o[8];
    int first;
    if (!PyArg_ParseTuple(args, "OOOOOOOOp", &o[0], &o[1], &o[2], &o[3], &o[4], &o[5], &o[6],
                          &o[7], &first))
        return NULL;
    Buffers b = {.count = 0};
    Masks m;
    const uint64_t *packed;
    int32_t *degree;
    if (!(packed = data_of(&b, o[0], 8, 0))) goto fail;
    int64_t states = b.views[0].ndim >= 1 ? b.views[0].shape[0] : 0;
    m.words = b.views[0].ndim == 2 ? b.views[0].shape[1] : 1;
    if (!(m.need = data_of(&b, o[1], 8, 0))) goto fail;
    m.transitions = items_of(&b) / m.words;
    if (!(m.need_ptr = data_of(&b, o[2], 8, 0)) || !(m.need_word = data_of(&b, o[3], 8, 0))
        || !(m.key_ptr = data_of(&b, o[4], 8, 0)) || !(m.key_t = data_of(&b, o[5], 8, 0))
        || !(m.free_t = data_of(&b, o[6], 8, 0)))
        goto fail;
    m.nfree = items_of(&b);
    if (!(degree = data_of(&b, o[7], 4, 1))) goto fail;
    int64_t *cand = PyMem_Malloc(sizeof(int64_t) * (size_t)(m.transitions + 1));
    if (!cand) { PyErr_NoMemory(); goto fail; }
    Py_BEGIN_ALLOW_THREADS
    for (int64_t q = 0; q < states; q++) {
        const uint64_t *row = packed + q * m.words;
        int64_t n = candidates(row, m.words, m.key_ptr, m.key_t, m.free_t, m.nfree, cand);
        int32_t d = 0;
        for (int64_t c = 0; c < n && !(first && d); c++)
            d += enables(row, &m, cand[c]);
        degree[q] = d;
    }
    Py_END_ALLOW_THREADS
    PyMem_Free(cand);
    release(&b);
    Py_RETURN_NONE;
fail:
    release(&b);
    return NULL;
}

/* paired_index(packed, table, bits): the entries of packed's rows, for the backward search. */
static PyObject *py_paired_index(PyObject *self, PyObject *args) {
    PyObject *op, *ot;
    int bits;
    if (!PyArg_ParseTuple(args, "OOi", &op, &ot, &bits))
        return NULL;
    Buffers b = {.count = 0};
    const uint64_t *packed;
    uint64_t *table;
    if (!(packed = data_of(&b, op, 8, 0))) goto fail;
    int64_t states = b.views[0].shape[0], words = b.views[0].ndim == 2 ? b.views[0].shape[1] : 1;
    if (!(table = data_of(&b, ot, 8, 1))) goto fail;
    int64_t mask = ((int64_t)1 << bits) - 1;
    for (int64_t q = 0; q < states; q++) {
        uint64_t h = hash_row(packed + q * words, words);
        int64_t i = slot_of_hash(h, bits);
        while (table[i] != 0) i = (i + 1) & mask;
        table[i] = entry(h, q);
    }
    release(&b);
    Py_RETURN_NONE;
fail:
    release(&b);
    return NULL;
}

/* backward(packed, pairs, bits, need, take, give, touch_ptr, touch_word, key_ptr, key_t,
 *          free_t, seen, frontier): mark in seen every position that reaches the frontier. */
static PyObject *py_backward(PyObject *self, PyObject *args) {
    PyObject *o[13];
    int bits;
    if (!PyArg_ParseTuple(args, "OOiOOOOOOOOOO", &o[0], &o[1], &bits, &o[2], &o[3], &o[4],
                          &o[5], &o[6], &o[7], &o[8], &o[9], &o[10], &o[11]))
        return NULL;
    Buffers b = {.count = 0};
    const uint64_t *packed, *need, *take, *give, *pairs;
    const int64_t *touch_ptr, *touch_word, *key_ptr, *key_t, *free_t, *frontier;
    uint8_t *seen;
    if (!(packed = data_of(&b, o[0], 8, 0))) goto fail;
    int64_t states = b.views[0].shape[0], words = b.views[0].ndim == 2 ? b.views[0].shape[1] : 1;
    if (!(pairs = data_of(&b, o[1], 8, 0)) || !(need = data_of(&b, o[2], 8, 0))) goto fail;
    int64_t transitions = items_of(&b) / words;
    if (!(take = data_of(&b, o[3], 8, 0)) || !(give = data_of(&b, o[4], 8, 0))
        || !(touch_ptr = data_of(&b, o[5], 8, 0)) || !(touch_word = data_of(&b, o[6], 8, 0))
        || !(key_ptr = data_of(&b, o[7], 8, 0)) || !(key_t = data_of(&b, o[8], 8, 0))
        || !(free_t = data_of(&b, o[9], 8, 0)))
        goto fail;
    int64_t nfree = items_of(&b);
    if (!(seen = data_of(&b, o[10], 1, 1)) || !(frontier = data_of(&b, o[11], 8, 0))) goto fail;
    int64_t nfrontier = items_of(&b);
    int64_t *todo = PyMem_Malloc(sizeof(int64_t) * (size_t)(states + 1));
    int64_t *cand = PyMem_Malloc(sizeof(int64_t) * (size_t)(transitions + 1));
    uint64_t *before = PyMem_Malloc(8 * BATCH * (size_t)words), hashes[BATCH];
    if (!todo || !cand || !before) {
        PyMem_Free(todo); PyMem_Free(cand); PyMem_Free(before);
        PyErr_NoMemory();
        goto fail;
    }
    Py_BEGIN_ALLOW_THREADS
    int64_t top = 0, head = 0;
    for (int64_t i = 0; i < nfrontier; i++)
        todo[top++] = frontier[i];
    /* first in, first out: the lookups of consecutive markings overlap in the processor */
    int64_t mask = ((int64_t)1 << bits) - 1;
    while (head < top) {
        if (head + 8 < top)   /* the marking unfired eight turns from now */
            __builtin_prefetch(packed + todo[head + 8] * words);
        int64_t a = todo[head++];
        const uint64_t *after = packed + a * words;
        int64_t n = candidates(after, words, key_ptr, key_t, free_t, nfree, cand);
        int64_t c = 0;
        while (c < n) {
            int nb = 0;
            for (; c < n && nb < BATCH; c++) {
                int64_t t = cand[c];
                uint64_t *bf = before + nb * words;
                int ok = 1;
                memcpy(bf, after, 8 * (size_t)words);
                for (int64_t k = touch_ptr[t]; k < touch_ptr[t + 1]; k++) {
                    int64_t w = touch_word[k];
                    uint64_t g = give[t * words + w], tk = take[t * words + w],
                             nd = need[t * words + w], x = after[w];
                    if ((x & g) != g) { ok = 0; break; }
                    uint64_t y = (x & ~g) | tk;
                    if ((y & nd) != nd || ((y & ~tk) | g) != x) { ok = 0; break; }
                    bf[w] = y;
                }
                if (!ok)
                    continue;
                hashes[nb] = hash_row(bf, words);
                __builtin_prefetch(&pairs[slot_of_hash(hashes[nb], bits)]);
                nb++;
            }
            prefetch_rows(packed, words, pairs, bits, hashes, nb);
            for (int i = 0; i < nb; i++) {
                int64_t slot;
                int64_t j = probe(packed, words, pairs, mask, before + i * words,
                                  hashes[i] & 0xFFFFFFFFULL, slot_of_hash(hashes[i], bits), &slot);
                if (j >= 0 && !seen[j]) {
                    seen[j] = 1;
                    todo[top++] = j;
                }
            }
        }
    }
    Py_END_ALLOW_THREADS
    PyMem_Free(todo);
    PyMem_Free(cand);
    PyMem_Free(before);
    release(&b);
    Py_RETURN_NONE;
fail:
    release(&b);
    return NULL;
}

/* packed_edges(packed, pairs, bits, need, keep, give, need_ptr, need_word, key_ptr, key_t,
 *              free_t, ids, order, node, src, dst, trans) -> count: every edge of the
 * explored markings (sorted rows; pairs: paired_index's table of them), in node order:
 * the node i's marking is row order[i], row j is node[j]; an edge's transition is
 * ids[firing row], and a node's edges are sorted by transition, as the numpy path sorts
 * them. The arrays (int32) hold the out-degrees' sum. The successors of a marking are
 * built and looked up in batches, as backward's predecessors are. */
static PyObject *py_packed_edges(PyObject *self, PyObject *args) {
    PyObject *o[16];
    int bits;
    if (!PyArg_ParseTuple(args, "OOiOOOOOOOOOOOOOO", &o[0], &o[1], &bits, &o[2], &o[3], &o[4],
                          &o[5], &o[6], &o[7], &o[8], &o[9], &o[10], &o[11], &o[12], &o[13],
                          &o[14], &o[15]))
        return NULL;
    Buffers b = {.count = 0};
    Masks m;
    const uint64_t *packed, *pairs;
    const int64_t *ids, *order, *node;
    int32_t *src, *dst, *trans;
    if (!(packed = data_of(&b, o[0], 8, 0))) goto fail;
    int64_t states = b.views[0].shape[0];
    m.words = b.views[0].ndim == 2 ? b.views[0].shape[1] : 1;
    if (!(pairs = data_of(&b, o[1], 8, 0)) || !(m.need = data_of(&b, o[2], 8, 0))) goto fail;
    m.transitions = items_of(&b) / m.words;
    if (!(m.keep = data_of(&b, o[3], 8, 0)) || !(m.give = data_of(&b, o[4], 8, 0))
        || !(m.need_ptr = data_of(&b, o[5], 8, 0)) || !(m.need_word = data_of(&b, o[6], 8, 0))
        || !(m.key_ptr = data_of(&b, o[7], 8, 0)) || !(m.key_t = data_of(&b, o[8], 8, 0))
        || !(m.free_t = data_of(&b, o[9], 8, 0)))
        goto fail;
    m.nfree = items_of(&b);
    if (!(ids = data_of(&b, o[10], 8, 0)) || !(order = data_of(&b, o[11], 8, 0))
        || !(node = data_of(&b, o[12], 8, 0)) || !(src = data_of(&b, o[13], 4, 1)))
        goto fail;
    int64_t room = items_of(&b);
    if (!(dst = data_of(&b, o[14], 4, 1)) || !(trans = data_of(&b, o[15], 4, 1))) goto fail;
    int64_t words = m.words, mask = ((int64_t)1 << bits) - 1;
    int64_t *cand = PyMem_Malloc(sizeof(int64_t) * (size_t)(m.transitions + 1));
    uint64_t *after = PyMem_Malloc(8 * BATCH * (size_t)words), hashes[BATCH];
    int64_t fired[BATCH];
    if (!cand || !after) {
        PyMem_Free(cand); PyMem_Free(after);
        PyErr_NoMemory();
        goto fail;
    }
    int64_t count = 0, lost = 0;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t i = 0; i < states && !lost; i++) {
        const uint64_t *row = packed + order[i] * words;
        int64_t n = candidates(row, words, m.key_ptr, m.key_t, m.free_t, m.nfree, cand);
        int64_t c = 0, first = count;
        while (c < n && !lost) {
            int nb = 0;
            for (; c < n && nb < BATCH; c++) {
                int64_t t = cand[c];
                if (!enables(row, &m, t))
                    continue;
                uint64_t *af = after + nb * words;
                for (int64_t w = 0; w < words; w++)
                    af[w] = (row[w] & m.keep[t * words + w]) | m.give[t * words + w];
                hashes[nb] = hash_row(af, words);
                __builtin_prefetch(&pairs[slot_of_hash(hashes[nb], bits)]);
                fired[nb++] = t;
            }
            prefetch_rows(packed, words, pairs, bits, hashes, nb);
            for (int k = 0; k < nb; k++) {
                int64_t slot;
                int64_t j = probe(packed, words, pairs, mask, after + k * words,
                                  hashes[k] & 0xFFFFFFFFULL, slot_of_hash(hashes[k], bits), &slot);
                if (j < 0 || count == room) { lost = 1; break; }
                /* in place among the node's edges, by transition (a node has few) */
                int32_t t = (int32_t)ids[fired[k]], d = (int32_t)node[j];
                src[count] = (int32_t)i;      /* every edge of the node starts there */
                int64_t at = count++;
                while (at > first && trans[at - 1] > t) {
                    trans[at] = trans[at - 1];
                    dst[at] = dst[at - 1];
                    at--;
                }
                trans[at] = t;
                dst[at] = d;
            }
        }
    }
    Py_END_ALLOW_THREADS
    PyMem_Free(cand);
    PyMem_Free(after);
    release(&b);
    if (lost) {
        PyErr_SetString(PyExc_RuntimeError, "a successor is not among the explored markings, "
                        "or the arrays are too short");
        return NULL;
    }
    return PyLong_FromLongLong(count);
fail:
    release(&b);
    return NULL;
}

/* backward_one_word(packed, table, bits, need, take, give, key_ptr, key_t, free_t, seen,
 *                   frontier): backward for markings of one word, in the slots of a table of
 * the markings themselves (rehash by value). A predecessor is found by its value alone, one
 * cache miss, and the marking to unfire next is read in its slot: the search never goes to
 * the sorted markings until the end, when each position reads its slot's verdict. The empty
 * marking, which cannot sit in a slot, is the extra slot at the end. */
static PyObject *py_backward_one_word(PyObject *self, PyObject *args) {
    PyObject *o[11];
    int bits;
    if (!PyArg_ParseTuple(args, "OOiOOOOOOOO", &o[0], &o[1], &bits, &o[2], &o[3], &o[4], &o[5],
                          &o[6], &o[7], &o[8], &o[9]))
        return NULL;
    Buffers b = {.count = 0};
    const uint64_t *packed, *table, *need, *take, *give;
    const int64_t *key_ptr, *key_t, *free_t, *frontier;
    uint8_t *seen;
    if (!(packed = data_of(&b, o[0], 8, 0))) goto fail;
    int64_t states = items_of(&b);
    if (!(table = data_of(&b, o[1], 8, 0))) goto fail;
    int64_t size = items_of(&b), mask = size - 1;
    if (!(need = data_of(&b, o[2], 8, 0))) goto fail;
    int64_t transitions = items_of(&b);
    if (!(take = data_of(&b, o[3], 8, 0)) || !(give = data_of(&b, o[4], 8, 0))
        || !(key_ptr = data_of(&b, o[5], 8, 0)) || !(key_t = data_of(&b, o[6], 8, 0))
        || !(free_t = data_of(&b, o[7], 8, 0)))
        goto fail;
    int64_t nfree = items_of(&b);
    if (!(seen = data_of(&b, o[8], 1, 1)) || !(frontier = data_of(&b, o[9], 8, 0))) goto fail;
    int64_t nfrontier = items_of(&b);
    uint8_t *in = PyMem_Calloc((size_t)size + 1, 1);
    int64_t *todo = PyMem_Malloc(sizeof(int64_t) * (size_t)(states + 1));
    int64_t *cand = PyMem_Malloc(sizeof(int64_t) * (size_t)(transitions + 1));
    if (!in || !todo || !cand) {
        PyMem_Free(in); PyMem_Free(todo); PyMem_Free(cand);
        PyErr_NoMemory();
        goto fail;
    }
    Py_BEGIN_ALLOW_THREADS
    /* the slot of a reachable marking (size: the empty one) */
#define SLOT_OF(value, out) do {                                                 \
        uint64_t v_ = (value);                                                   \
        if (v_ == 0) { out = size; break; }                                      \
        int64_t i_ = slot_one(v_, bits);                                         \
        while (table[i_] != 0 && table[i_] != v_) i_ = (i_ + 1) & mask;          \
        out = table[i_] == v_ ? i_ : -1;                                         \
    } while (0)
    int64_t top = 0, head = 0;
    for (int64_t f = 0; f < nfrontier; f++) {
        int64_t i;
        SLOT_OF(packed[frontier[f]], i);
        if (i >= 0 && !in[i]) { in[i] = 1; todo[top++] = i; }
    }
    while (head < top) {
        if (head + 8 < top)   /* the slot unfired eight turns from now */
            __builtin_prefetch(&table[todo[head + 8]]);
        int64_t a = todo[head++];
        uint64_t after = a == size ? 0 : table[a], batch[BATCH];
        int64_t n = candidates(&after, 1, key_ptr, key_t, free_t, nfree, cand), c = 0;
        while (c < n) {
            int nb = 0;
            for (; c < n && nb < BATCH; c++) {
                int64_t t = cand[c];
                uint64_t g = give[t], tk = take[t], nd = need[t];
                if ((after & g) != g) continue;
                uint64_t y = (after & ~g) | tk;
                if ((y & nd) != nd || ((y & ~tk) | g) != after) continue;
                batch[nb++] = y;
                __builtin_prefetch(&table[slot_one(y, bits)]);
            }
            for (int k = 0; k < nb; k++) {
                int64_t i;
                SLOT_OF(batch[k], i);
                if (i >= 0 && !in[i]) { in[i] = 1; todo[top++] = i; }
            }
        }
    }
    for (int64_t q = 0; q < states; q++) {
        if (q + 16 < states)
            __builtin_prefetch(&table[slot_one(packed[q + 16], bits)]);
        int64_t i;
        SLOT_OF(packed[q], i);
        seen[q] = i >= 0 && in[i];
    }
#undef SLOT_OF
    Py_END_ALLOW_THREADS
    PyMem_Free(in);
    PyMem_Free(todo);
    PyMem_Free(cand);
    release(&b);
    Py_RETURN_NONE;
fail:
    release(&b);
    return NULL;
}

/* permute_rows(rows, order): rows[i] = the old rows[order[i]] for every i, in place,
 * following the permutation's cycles: sorting the markings found costs no second copy of
 * them (a hundred megabytes on a state space of three million markings). */
static PyObject *py_permute_rows(PyObject *self, PyObject *args) {
    PyObject *orows, *oorder;
    if (!PyArg_ParseTuple(args, "OO", &orows, &oorder))
        return NULL;
    Buffers b = {.count = 0};
    uint64_t *rows;
    const int64_t *order;
    if (!(rows = data_of(&b, orows, 8, 1))) goto fail;
    int64_t n = b.views[0].shape[0], words = b.views[0].ndim == 2 ? b.views[0].shape[1] : 1;
    if (!(order = data_of(&b, oorder, 8, 0))) goto fail;
    if (items_of(&b) != n) {
        PyErr_SetString(PyExc_ValueError, "one position a row");
        goto fail;
    }
    uint8_t *done = PyMem_Calloc((size_t)n + 1, 1);
    uint64_t *held = PyMem_Malloc(8 * (size_t)words);
    if (!done || !held) { PyMem_Free(done); PyMem_Free(held); PyErr_NoMemory(); goto fail; }
    Py_BEGIN_ALLOW_THREADS
    for (int64_t i = 0; i < n; i++) {
        if (done[i])
            continue;
        memcpy(held, rows + i * words, 8 * (size_t)words);
        int64_t j = i;
        for (;;) {
            int64_t k = order[j];
            done[j] = 1;
            if (k == i) {
                memcpy(rows + j * words, held, 8 * (size_t)words);
                break;
            }
            memcpy(rows + j * words, rows + k * words, 8 * (size_t)words);
            j = k;
        }
    }
    Py_END_ALLOW_THREADS
    PyMem_Free(done);
    PyMem_Free(held);
    release(&b);
    Py_RETURN_NONE;
fail:
    release(&b);
    return NULL;
}

/* -- bounded nets: counters packed into words (analysis/statespace/counters.py) ----------- */

/* A transition's fields as compressed rows: its needs (value: tokens, unsigned) or its
 * changes (value: signed). */
typedef struct {
    const int64_t *ptr, *word;
    const uint64_t *shift, *mask;
    const uint64_t *need;    /* the needs' tokens */
    const int64_t *change;   /* the changes' signed counts */
    int64_t transitions;
} Fields;

/* The five arrays (ptr, word, shift, mask, value) of objs into f; 0 and an exception if not. */
static int fields_of(Buffers *b, PyObject **objs, Fields *f, int is_change) {
    if (!(f->ptr = data_of(b, objs[0], 8, 0))) return 0;
    f->transitions = items_of(b) - 1;
    if (!(f->word = data_of(b, objs[1], 8, 0)) || !(f->shift = data_of(b, objs[2], 8, 0))
        || !(f->mask = data_of(b, objs[3], 8, 0)))
        return 0;
    const void *v = data_of(b, objs[4], 8, 0);
    if (!v) return 0;
    f->need = is_change ? NULL : v;
    f->change = is_change ? v : NULL;
    return 1;
}

static inline int counter_enabled(const uint64_t *row, const Fields *n, int64_t t) {
    for (int64_t k = n->ptr[t]; k < n->ptr[t + 1]; k++)
        if (((row[n->word[k]] >> n->shift[k]) & n->mask[k]) < n->need[k])
            return 0;
    return 1;
}

/* out = row changed by sign times t's change; -1 if every counter fits its field, else the
 * index of the first field that would not (below 0 or past its mask). */
static inline int64_t counter_fire(const uint64_t *row, uint64_t *out, int64_t words,
                                   const Fields *d, int64_t t, int sign) {
    memcpy(out, row, 8 * (size_t)words);
    for (int64_t k = d->ptr[t]; k < d->ptr[t + 1]; k++) {
        int64_t w = d->word[k];
        uint64_t m = d->mask[k], sh = d->shift[k];
        int64_t f = (int64_t)((out[w] >> sh) & m) + sign * d->change[k];
        if (f < 0 || f > (int64_t)m)
            return k;
        out[w] = (out[w] & ~(m << sh)) | ((uint64_t)f << sh);
    }
    return -1;
}

enum { OVERFLOW = 5, GROWING = 6 };

/* counter_step(n x5, d x5, d_place, growing, queue, parent, count, head, table, bits, dead,
 *              max_states, budget) -> (count, head, dead, code, info) */
static PyObject *py_counter_step(PyObject *self, PyObject *args) {
    PyObject *o[17];
    long long count, head, dead, max_states, budget;
    int bits;
    if (!PyArg_ParseTuple(args, "OOOOOOOOOOOOOOLLOiLLL", &o[0], &o[1], &o[2], &o[3], &o[4],
                          &o[5], &o[6], &o[7], &o[8], &o[9], &o[10], &o[11], &o[12], &o[13],
                          &count, &head, &o[14], &bits, &dead, &max_states, &budget))
        return NULL;
    Buffers b = {.count = 0};
    Fields n, d;
    const int64_t *place;
    const uint8_t *growing;
    uint64_t *queue, *table;
    int64_t *parent;
    if (!fields_of(&b, o, &n, 0) || !fields_of(&b, o + 5, &d, 1)
        || !(place = data_of(&b, o[10], 8, 0)) || !(growing = data_of(&b, o[11], 1, 0))
        || !(queue = data_of(&b, o[12], 8, 1)))
        goto fail;
    int64_t words = b.views[b.count - 1].ndim == 2 ? b.views[b.count - 1].shape[1] : 1;
    int64_t capacity = b.views[b.count - 1].shape[0];
    if (!(parent = data_of(&b, o[13], 8, 1))) goto fail;
    if (items_of(&b) < capacity) capacity = items_of(&b);
    if (!(table = data_of(&b, o[14], 8, 1))) goto fail;
    int64_t table_size = items_of(&b), tmask = table_size - 1, info = 0;
    uint64_t *next = PyMem_Malloc(8 * (size_t)words);
    if (!next) { PyErr_NoMemory(); goto fail; }
    int code = GOING;
    Py_BEGIN_ALLOW_THREADS
    int64_t stop = head + budget, transitions = n.transitions;
    while (head < count && head < stop) {
        if (count + transitions > capacity) { code = QUEUE_FULL; break; }
        if (10 * (count + transitions) > 7 * table_size) { code = TABLE_FULL; break; }
        const uint64_t *row = queue + head * words;
        int fired = 0;
        for (int64_t t = 0; t < transitions && code == GOING; t++) {
            if (!counter_enabled(row, &n, t))
                continue;
            fired = 1;
            if (growing[t]) { code = GROWING; info = t; break; }
            int64_t k = counter_fire(row, next, words, &d, t, 1);
            if (k >= 0) { code = OVERFLOW; info = place[k]; break; }
            uint64_t h = hash_row(next, words);
            int64_t slot = -1;
            if (probe(queue, words, table, tmask, next, h & 0xFFFFFFFFULL, slot_of_hash(h, bits),
                      &slot) >= 0)
                continue;
            if (count >= max_states) { code = LIMIT; break; }
            memcpy(queue + count * words, next, 8 * (size_t)words);
            parent[count] = head;
            table[slot] = entry(h, count++);
        }
        if (code != GOING)
            break;
        if (!fired)
            dead++;
        head++;
    }
    Py_END_ALLOW_THREADS
    PyMem_Free(next);
    release(&b);
    return Py_BuildValue("LLLiL", count, head, dead, code, (long long)info);
fail:
    release(&b);
    return NULL;
}

/* counter_out_degree(rows, n x5, degree) */
static PyObject *py_counter_out_degree(PyObject *self, PyObject *args) {
    PyObject *o[7];
    if (!PyArg_ParseTuple(args, "OOOOOOO", &o[0], &o[1], &o[2], &o[3], &o[4], &o[5], &o[6]))
        return NULL;
    Buffers b = {.count = 0};
    Fields n;
    const uint64_t *rows;
    int32_t *degree;
    if (!(rows = data_of(&b, o[0], 8, 0))) goto fail;
    int64_t states = b.views[0].shape[0], words = b.views[0].ndim == 2 ? b.views[0].shape[1] : 1;
    if (!fields_of(&b, o + 1, &n, 0) || !(degree = data_of(&b, o[6], 4, 1))) goto fail;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t q = 0; q < states; q++) {
        int32_t deg = 0;
        for (int64_t t = 0; t < n.transitions; t++)
            deg += counter_enabled(rows + q * words, &n, t);
        degree[q] = deg;
    }
    Py_END_ALLOW_THREADS
    release(&b);
    Py_RETURN_NONE;
fail:
    release(&b);
    return NULL;
}

/* counter_walk(rows, table, bits, n x5, d x5, sign, seen, frontier, src, trans, dst):
 * sign 1: every firing (source, transition, target) into src, trans, dst, in node order;
 * sign -1: mark in seen every node that reaches the frontier, by unfiring. */
static PyObject *py_counter_walk(PyObject *self, PyObject *args) {
    PyObject *o[17];
    int bits, sign;
    if (!PyArg_ParseTuple(args, "OOiOOOOOOOOOOiOOOOO", &o[0], &o[1], &bits, &o[2], &o[3], &o[4],
                          &o[5], &o[6], &o[7], &o[8], &o[9], &o[10], &o[11], &sign, &o[12],
                          &o[13], &o[14], &o[15], &o[16]))
        return NULL;
    Buffers b = {.count = 0};
    Fields n, d;
    const uint64_t *rows, *table;
    uint8_t *seen;
    const int64_t *frontier;
    int32_t *src, *trans, *dst;
    if (!(rows = data_of(&b, o[0], 8, 0))) goto fail;
    int64_t states = b.views[0].shape[0], words = b.views[0].ndim == 2 ? b.views[0].shape[1] : 1;
    if (!(table = data_of(&b, o[1], 8, 0))) goto fail;
    int64_t tmask = items_of(&b) - 1;
    if (!fields_of(&b, o + 2, &n, 0) || !fields_of(&b, o + 7, &d, 1)
        || !(seen = data_of(&b, o[12], 1, 1)) || !(frontier = data_of(&b, o[13], 8, 0)))
        goto fail;
    int64_t nfrontier = items_of(&b);
    if (!(src = data_of(&b, o[14], 4, 1))) goto fail;
    int64_t total = items_of(&b);
    if (!(trans = data_of(&b, o[15], 4, 1)) || !(dst = data_of(&b, o[16], 4, 1))) goto fail;
    uint64_t *other = PyMem_Malloc(8 * (size_t)words);
    int64_t *todo = sign < 0 ? PyMem_Malloc(sizeof(int64_t) * (size_t)(states + 1)) : NULL;
    if (!other || (sign < 0 && !todo)) {
        PyMem_Free(other); PyMem_Free(todo); PyErr_NoMemory(); goto fail;
    }
    Py_BEGIN_ALLOW_THREADS
    if (sign > 0) {
        int64_t e = 0;
        for (int64_t q = 0; q < states && e < total; q++)
            for (int64_t t = 0; t < n.transitions && e < total; t++) {
                if (!counter_enabled(rows + q * words, &n, t)) continue;
                counter_fire(rows + q * words, other, words, &d, t, 1);
                uint64_t h = hash_row(other, words);
                int64_t slot;
                src[e] = (int32_t)q;
                trans[e] = (int32_t)t;
                dst[e++] = (int32_t)probe(rows, words, table, tmask, other, h & 0xFFFFFFFFULL,
                                          slot_of_hash(h, bits), &slot);
            }
    } else {
        int64_t top = 0, head = 0;
        for (int64_t i = 0; i < nfrontier; i++)
            todo[top++] = frontier[i];
        /* first in, first out, as the safe nets' backward search */
        while (head < top) {
            const uint64_t *after = rows + todo[head++] * words;
            for (int64_t t = 0; t < n.transitions; t++) {
                if (counter_fire(after, other, words, &d, t, -1) >= 0) continue;
                if (!counter_enabled(other, &n, t)) continue;
                uint64_t h = hash_row(other, words);
                int64_t slot, j = probe(rows, words, table, tmask, other, h & 0xFFFFFFFFULL,
                                        slot_of_hash(h, bits), &slot);
                if (j >= 0 && !seen[j]) { seen[j] = 1; todo[top++] = j; }
            }
        }
    }
    Py_END_ALLOW_THREADS
    PyMem_Free(other);
    PyMem_Free(todo);
    release(&b);
    Py_RETURN_NONE;
fail:
    release(&b);
    return NULL;
}

static PyObject *py_slot_of_words(PyObject *self, PyObject *args) {
    PyObject *o;
    int bits;
    if (!PyArg_ParseTuple(args, "Oi", &o, &bits))
        return NULL;
    Buffers b = {.count = 0};
    const uint64_t *row = data_of(&b, o, 8, 0);
    if (!row) { release(&b); return NULL; }
    int64_t slot = slot_row(row, items_of(&b), bits);
    release(&b);
    return PyLong_FromLongLong(slot);
}

static PyObject *py_slot_of_word(PyObject *self, PyObject *args) {
    unsigned long long m;
    int bits;
    if (!PyArg_ParseTuple(args, "Ki", &m, &bits))
        return NULL;
    return PyLong_FromLongLong(slot_one((uint64_t)m, bits));
}

/* -- the reachability graph, asked by the contest's questions (analysis/contest/answers.py) -------- */

/* A growable int64 stack, scratch of one call (freed before it returns). */
typedef struct { int64_t *at; int64_t size, cap; } Stack;

static int push(Stack *s, int64_t v) {
    if (s->size == s->cap) {
        int64_t cap = s->cap ? 2 * s->cap : 1024;
        int64_t *at = PyMem_RawRealloc(s->at, sizeof(int64_t) * (size_t)cap);
        if (!at) return 0;
        s->at = at;
        s->cap = cap;
    }
    s->at[s->size++] = v;
    return 1;
}

/* scc(indptr, indices, keep, label) -> count: the strongly connected components of the
 * graph (CSR) restricted to the nodes with keep[v], by Tarjan's algorithm (1972) without
 * recursion; label[v] is v's component (-1 where not kept). Components are numbered in
 * the order they complete: a component's successors have smaller numbers. */
static PyObject *py_scc(PyObject *self, PyObject *args) {
    PyObject *o[4];
    if (!PyArg_ParseTuple(args, "OOOO", &o[0], &o[1], &o[2], &o[3]))
        return NULL;
    Buffers b = {.count = 0};
    const int64_t *ptr, *idx;
    const uint8_t *keep;
    int64_t *label;
    if (!(ptr = data_of(&b, o[0], 8, 0))) goto fail;
    int64_t n = items_of(&b) - 1;
    if (!(idx = data_of(&b, o[1], 8, 0)) || !(keep = data_of(&b, o[2], 1, 0))
        || !(label = data_of(&b, o[3], 8, 1)))
        goto fail;
    int64_t *low = PyMem_RawMalloc(sizeof(int64_t) * (size_t)(2 * n + 1));
    Stack call = {0}, open = {0};
    int64_t count = 0, ok = 1;
    if (!low) { PyErr_NoMemory(); goto fail; }
    int64_t *num = low + n;                     /* 0: not met; -1: its component is done */
    Py_BEGIN_ALLOW_THREADS
    int64_t next = 1;
    for (int64_t v = 0; v < n; v++) { num[v] = 0; label[v] = -1; }
    for (int64_t root = 0; root < n && ok; root++) {
        if (!keep[root] || num[root]) continue;
        num[root] = low[root] = next++;
        ok = push(&open, root) && push(&call, root) && push(&call, ptr[root]);
        while (call.size && ok) {
            int64_t v = call.at[call.size - 2], e = call.at[call.size - 1];
            if (e < ptr[v + 1]) {
                call.at[call.size - 1] = e + 1;
                int64_t w = idx[e];
                if (!keep[w]) continue;
                if (!num[w]) {
                    num[w] = low[w] = next++;
                    ok = push(&open, w) && push(&call, w) && push(&call, ptr[w]);
                } else if (num[w] > 0 && num[w] < low[v]) {
                    low[v] = num[w];
                }
                continue;
            }
            call.size -= 2;
            if (low[v] == num[v]) {
                int64_t w;
                do {
                    w = open.at[--open.size];
                    num[w] = -1;
                    label[w] = count;
                } while (w != v);
                count++;
            }
            if (call.size) {
                int64_t u = call.at[call.size - 2];
                if (low[v] > 0 && low[v] < low[u]) low[u] = low[v];
            }
        }
    }
    Py_END_ALLOW_THREADS
    PyMem_RawFree(low);
    PyMem_RawFree(call.at);
    PyMem_RawFree(open.at);
    release(&b);
    if (!ok) return PyErr_NoMemory();
    return PyLong_FromLongLong(count);
fail:
    release(&b);
    return NULL;
}

/* back_reach(indptr, indices, through, out): with the predecessors' CSR, add to out (its
 * nodes marked 1) every node of `through` from which a path inside `through` reaches
 * one of them: E(through U out), the backward search of CTL's labelling. */
static PyObject *py_back_reach(PyObject *self, PyObject *args) {
    PyObject *o[4];
    if (!PyArg_ParseTuple(args, "OOOO", &o[0], &o[1], &o[2], &o[3]))
        return NULL;
    Buffers b = {.count = 0};
    const int64_t *ptr, *idx;
    const uint8_t *through;
    uint8_t *out;
    if (!(ptr = data_of(&b, o[0], 8, 0))) goto fail;
    int64_t n = items_of(&b) - 1;
    if (!(idx = data_of(&b, o[1], 8, 0)) || !(through = data_of(&b, o[2], 1, 0))
        || !(out = data_of(&b, o[3], 1, 1)))
        goto fail;
    Stack todo = {0};
    int ok = 1;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t v = 0; v < n && ok; v++)
        if (out[v]) ok = push(&todo, v);
    while (todo.size && ok) {
        int64_t v = todo.at[--todo.size];
        for (int64_t e = ptr[v]; e < ptr[v + 1] && ok; e++) {
            int64_t u = idx[e];
            if (!out[u] && through[u]) { out[u] = 1; ok = push(&todo, u); }
        }
    }
    Py_END_ALLOW_THREADS
    PyMem_RawFree(todo.at);
    release(&b);
    if (!ok) return PyErr_NoMemory();
    Py_RETURN_NONE;
fail:
    release(&b);
    return NULL;
}

/* scatter_by_source(src, values, cursor, out): a counting sort of a graph's edges by
 * their source, stable: cursor[v] starts at the first slot of v's row (the row pointers),
 * and edge e's value goes to out[cursor[src[e]]++] (its target, or its position). One
 * pass, O(edges), where a comparison sort and a gather were most of the time a large
 * graph's labelling took. A source outside the rows, or a slot past the edges, is an
 * error, not a write out of bounds. */
static PyObject *py_scatter_by_source(PyObject *self, PyObject *args) {
    PyObject *o[4];
    if (!PyArg_ParseTuple(args, "OOOO", &o[0], &o[1], &o[2], &o[3]))
        return NULL;
    Buffers b = {.count = 0};
    const int64_t *src, *values;
    int64_t *cursor, *out;
    if (!(src = data_of(&b, o[0], 8, 0))) goto fail;
    int64_t edges = items_of(&b);
    if (!(values = data_of(&b, o[1], 8, 0))) goto fail;
    int64_t given = items_of(&b);
    if (!(cursor = data_of(&b, o[2], 8, 1))) goto fail;
    int64_t n = items_of(&b);
    if (!(out = data_of(&b, o[3], 8, 1))) goto fail;
    if (items_of(&b) != edges || given != edges) {
        PyErr_SetString(PyExc_ValueError, "values and out must have a slot per edge");
        goto fail;
    }
    int64_t bad = -1;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t e = 0; e < edges; e++) {
        int64_t v = src[e];
        if (v < 0 || v >= n || cursor[v] < 0 || cursor[v] >= edges) { bad = e; break; }
        out[cursor[v]++] = values[e];
    }
    Py_END_ALLOW_THREADS
    release(&b);
    if (bad >= 0)
        return PyErr_Format(PyExc_ValueError, "edge %lld: its source is not a row, or its "
                            "row is full", (long long)bad);
    Py_RETURN_NONE;
fail:
    release(&b);
    return NULL;
}

/* ltl_product(indptr, indices, a_ptr, a_succ, label, acc, all, initial, num, max_states)
 *   -> (found, states):
 * whether the product of the graph (CSR, node 0 the initial marking) and a generalised
 * Büchi automaton (its successors' CSR a_ptr/a_succ, label[b * n + t]: node b may read
 * marking t, acc[b] the acceptance sets node b is in, all every set, initial the
 * product's initial states) has a
 * reachable cycle meeting every set: Couvreur's on-the-fly emptiness check (1999), a
 * depth-first search that merges strongly connected components as their cycles close
 * and stops at the first that meets them all. num (int32, n * k zeros) numbers the
 * product's states (graph node * k + automaton node; -1 once its component is done).
 * found: 1 an accepting cycle, 0 none, -1 past max_states. */
static PyObject *py_ltl_product(PyObject *self, PyObject *args) {
    PyObject *o[8];
    long long max_states;
    unsigned long long all;
    if (!PyArg_ParseTuple(args, "OOOOOOKOOL", &o[0], &o[1], &o[2], &o[3], &o[4], &o[5], &all,
                          &o[6], &o[7], &max_states))
        return NULL;
    Buffers b = {.count = 0};
    const int64_t *ptr, *idx, *aptr, *asucc, *initial;
    const uint8_t *label;
    const uint64_t *acc;
    int32_t *num;
    if (!(ptr = data_of(&b, o[0], 8, 0))) goto fail;
    int64_t n = items_of(&b) - 1;
    if (!(idx = data_of(&b, o[1], 8, 0)) || !(aptr = data_of(&b, o[2], 8, 0)))
        goto fail;
    int64_t k = items_of(&b) - 1;
    if (!(asucc = data_of(&b, o[3], 8, 0)) || !(label = data_of(&b, o[4], 1, 0))
        || !(acc = data_of(&b, o[5], 8, 0)) || !(initial = data_of(&b, o[6], 8, 0)))
        goto fail;
    int64_t starts = items_of(&b);
    if (!(num = data_of(&b, o[7], 4, 1))) goto fail;
    if (items_of(&b) < n * k) {
        PyErr_SetString(PyExc_ValueError, "num must hold n * k states");
        goto fail;
    }
    Stack call = {0}, open = {0}, roots = {0};   /* roots: (number, acceptance) pairs */
    int64_t found = 0, next = 1, ok = 1;
    Py_BEGIN_ALLOW_THREADS
    for (int64_t i = 0; i < starts && ok && !found; i++) {
        int64_t first = initial[i];
        if (num[first]) continue;
        num[first] = (int32_t)next++;
        ok = push(&open, first) && push(&roots, num[first]) && push(&roots, (int64_t)acc[first])
             && push(&call, first) && push(&call, 0);
        while (call.size && ok && !found) {
            int64_t p = call.at[call.size - 2], cursor = call.at[call.size - 1];
            int64_t s = p / k, a = p % k;
            int64_t degree = ptr[s + 1] - ptr[s], moves = aptr[a + 1] - aptr[a];
            if (cursor < degree * moves) {
                call.at[call.size - 1] = cursor + 1;
                int64_t bnode = asucc[aptr[a] + cursor / degree];
                int64_t t = idx[ptr[s] + cursor % degree];
                if (!label[bnode * n + t]) continue;
                int64_t q = t * k + bnode;
                if (!num[q]) {
                    if (next > max_states) { found = -1; break; }
                    num[q] = (int32_t)next++;
                    ok = push(&open, q) && push(&roots, num[q]) && push(&roots, (int64_t)acc[bnode])
                         && push(&call, q) && push(&call, 0);
                } else if (num[q] > 0) {
                    /* a cycle closes: every root above q's joins the component below */
                    uint64_t met = 0;
                    while (roots.at[roots.size - 2] > num[q]) {
                        met |= (uint64_t)roots.at[roots.size - 1];
                        roots.size -= 2;
                    }
                    roots.at[roots.size - 1] = (int64_t)((uint64_t)roots.at[roots.size - 1] | met);
                    if ((uint64_t)roots.at[roots.size - 1] == all) found = 1;
                }
                continue;
            }
            call.size -= 2;
            if (roots.at[roots.size - 2] == num[p]) {      /* p roots a finished component */
                roots.size -= 2;
                int64_t w;
                do {
                    w = open.at[--open.size];
                    num[w] = -1;
                } while (w != p);
            }
        }
    }
    Py_END_ALLOW_THREADS
    PyMem_RawFree(call.at);
    PyMem_RawFree(open.at);
    PyMem_RawFree(roots.at);
    release(&b);
    if (!ok) return PyErr_NoMemory();
    return Py_BuildValue("(LL)", (long long)found, (long long)(next - 1));
fail:
    release(&b);
    return NULL;
}


/* -- an LTL formula's product with a bounded net, on the fly (ltl_on_the_fly.py) ---------- */

enum { OP_LINEAR = 0, OP_ENABLED = 1, OP_DEAD = 2, OP_CONST = 3, OP_NOT = 4, OP_AND = 5,
       OP_OR = 6 };
enum { LTL_HOLDS = 0, LTL_ACCEPTING = 1, LTL_LIMIT = 2, LTL_TIME = 3, LTL_OVERFLOW = 4,
       LTL_GROWING = 5 };


/* State formulas as postfix programs (interface.StateProgram). */
typedef struct {
    const int64_t *ops, *atom_ptr, *lin_ptr, *lin_word, *lin_coef, *bound;
    const uint64_t *lin_shift, *lin_mask;
    int64_t atoms, length;
} Program;

/* The atoms that hold in row, a bit each; stack holds `length` truths. */
static uint64_t atoms_of(const uint64_t *row, const Program *pr, const Fields *n,
                         uint8_t *stack) {
    uint64_t out = 0;
    int dead = -1;
    for (int64_t i = 0; i < pr->atoms; i++) {
        int64_t top = 0;
        for (int64_t k = pr->atom_ptr[i]; k < pr->atom_ptr[i + 1]; k++) {
            int64_t op = pr->ops[2 * k], arg = pr->ops[2 * k + 1];
            switch (op) {
            case OP_LINEAR: {
                int64_t sum = 0;
                for (int64_t j = pr->lin_ptr[arg]; j < pr->lin_ptr[arg + 1]; j++)
                    sum += pr->lin_coef[j]
                           * (int64_t)((row[pr->lin_word[j]] >> pr->lin_shift[j]) & pr->lin_mask[j]);
                stack[top++] = sum <= pr->bound[arg];
                break;
            }
            case OP_ENABLED:
                stack[top++] = (uint8_t)counter_enabled(row, n, arg);
                break;
            case OP_DEAD:
                if (dead < 0) {
                    dead = 1;
                    for (int64_t t = 0; t < n->transitions && dead; t++)
                        if (counter_enabled(row, n, t)) dead = 0;
                }
                stack[top++] = (uint8_t)dead;
                break;
            case OP_CONST:
                stack[top++] = (uint8_t)(arg != 0);
                break;
            case OP_NOT:
                stack[top - 1] = !stack[top - 1];
                break;
            default: {   /* AND, OR of the top arg truths */
                uint8_t v = op == OP_AND;
                for (int64_t j = 0; j < arg; j++) {
                    uint8_t x = stack[--top];
                    v = op == OP_AND ? (v && x) : (v || x);
                }
                stack[top++] = v;
            }
            }
        }
        if (top > 0 && stack[top - 1]) out |= (uint64_t)1 << i;
    }
    return out;
}

/* The enabled members (into out) of the stubborn set grown from the enabled transition key
 * on a marking of counters, or -1 if one is visible: an enabled member brings every
 * transition that takes from a place it needs and every one that needs a place it takes
 * from; a disabled one every transition that adds to the first place it lacks. */
static int64_t counter_stubborn(const uint64_t *row, const Fields *n, const int64_t *need_place,
                                const Stubborn *st, const uint8_t *is_enabled, int64_t key,
                                int64_t *in, int64_t stamp, int64_t *work, int64_t *out) {
    int64_t top = 0, count = 0;
    in[key] = stamp;
    work[top++] = key;
    while (top > 0) {
        int64_t t = work[--top];
        if (is_enabled[t]) {
            if (st->visible[t]) return -1;
            out[count++] = t;
            bring_conflicts(st, t, in, stamp, work, &top);
        } else {
            for (int64_t k = n->ptr[t]; k < n->ptr[t + 1]; k++) {
                if (((row[n->word[k]] >> n->shift[k]) & n->mask[k]) >= n->need[k]) continue;
                int64_t p = need_place[k];
                for (int64_t j = st->p_make_ptr[p]; j < st->p_make_ptr[p + 1]; j++) {
                    int64_t u = st->p_make[j];
                    if (in[u] != stamp) { in[u] = stamp; work[top++] = u; }
                }
                break;
            }
        }
    }
    return count;
}

/* What one search shares: the net, the formula, the automaton, the table of product
 * states (rows of the marking's words and the automaton node). */
typedef struct {
    Fields n, d;
    const int64_t *need_place, *change_place;
    const uint8_t *growing;
    Program pr;
    const int64_t *aptr, *asucc;
    const uint64_t *required, *accepting;
    Stubborn st;
    uint64_t *rows, *table;
    int64_t words, width, capacity, tmask;
    int bits;
    /* scratch */
    uint64_t *next, *probe_row;
    uint8_t *stack, *is_enabled, *on_stack;
    int64_t *enabled, *best, *members, *in, *work, stamp, keys;
} Ltl;

static int64_t ltl_find(Ltl *L, const uint64_t *row, int64_t node, int64_t *slot, uint64_t *h) {
    memcpy(L->probe_row, row, 8 * (size_t)L->words);
    L->probe_row[L->words] = (uint64_t)node;
    *h = hash_row(L->probe_row, L->width);
    return probe(L->rows, L->width, L->table, L->tmask, L->probe_row, *h & 0xFFFFFFFFULL,
                 slot_of_hash(*h, L->bits), slot);
}

/* The transitions product state p fires, pushed on todo (-1: a dead marking stays);
 * returns LTL_HOLDS (0) or LTL_OVERFLOW / LTL_GROWING with *info. */
static int ltl_expand(Ltl *L, int64_t p, Stack *todo, int64_t *info, int *ok) {
    const uint64_t *row = L->rows + p * L->width;
    int64_t a = (int64_t)row[L->words], count = 0, T = L->n.transitions;
    for (int64_t t = 0; t < T; t++) {
        L->is_enabled[t] = (uint8_t)counter_enabled(row, &L->n, t);
        if (L->is_enabled[t]) {
            if (L->growing[t]) { *info = t; return LTL_GROWING; }
            L->enabled[count++] = t;
        }
    }
    if (count == 0) { *ok = push(todo, -1); return LTL_HOLDS; }
    int64_t *chosen = L->enabled, size = count;
    if (L->st.on && count > 1) {
        int64_t best = -1;
        /* the smallest set grown from the first `keys` enabled keys (interface.STUBBORN_KEYS) */
        for (int64_t i = 0; i < count && i < L->keys && best != 1; i++) {
            int64_t got = counter_stubborn(row, &L->n, L->need_place, &L->st, L->is_enabled,
                                           L->enabled[i], L->in, ++L->stamp, L->work, L->members);
            if (got > 0 && (best < 0 || got < best)) {
                best = got;
                memcpy(L->best, L->members, sizeof(int64_t) * (size_t)got);
            }
        }
        if (best > 0 && best < count) {
            /* the proviso: no product state the reduced set leads to is on the search's
             * stack (every cycle of a depth-first search closes on its stack, so each
             * cycle has a marking that fires everything) */
            int fresh = 1;
            for (int64_t i = 0; i < best && fresh; i++) {
                int64_t k = counter_fire(row, L->next, L->words, &L->d, L->best[i], 1);
                if (k >= 0) { *info = L->change_place[k]; return LTL_OVERFLOW; }
                uint64_t m = atoms_of(L->next, &L->pr, &L->n, L->stack), h;
                for (int64_t j = L->aptr[a]; j < L->aptr[a + 1] && fresh; j++) {
                    int64_t b = L->asucc[j], slot;
                    if ((L->required[b] & m) != L->required[b]) continue;
                    int64_t q = ltl_find(L, L->next, b, &slot, &h);
                    if (q >= 0 && L->on_stack[q]) fresh = 0;
                }
            }
            if (fresh) { chosen = L->best; size = best; }
        }
    }
    for (int64_t i = 0; i < size && *ok; i++)
        *ok = push(todo, chosen[i]);
    return LTL_HOLDS;
}

static double now_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ltl_search(n x5, need_place, d x5, change_place, growing, program x8, a_ptr, a_succ,
 * required, accepting, all, initial, stubborn x11, on, m0, rows, table, bits, max_states,
 * seconds, keys) -> (code, states, info): Couvreur's check (as ltl_product) on the product of
 * the net from m0 and the automaton, generated as it is searched, under stubborn sets
 * with the proviso where `on` (interface.Loops.ltl_search). */
static PyObject *py_ltl_search(PyObject *self, PyObject *args) {
    PyObject *o[44];
    unsigned long long all;
    int on, bits, keys;
    long long max_states;
    double seconds;
    if (!PyArg_ParseTuple(args, "OOOOOOOOOOOOOOOOOOOOOOOOOKOOOOOOOOOOOOiOOOiLdi",
                          &o[0], &o[1], &o[2], &o[3], &o[4], &o[5], &o[6], &o[7], &o[8], &o[9],
                          &o[10], &o[11], &o[12], &o[13], &o[14], &o[15], &o[16], &o[17],
                          &o[18], &o[19], &o[20], &o[21], &o[22], &o[23], &o[24], &all,
                          &o[25], &o[26], &o[27], &o[28], &o[29], &o[30], &o[31], &o[32],
                          &o[33], &o[34], &o[35], &o[36], &on, &o[37], &o[38], &o[39], &bits,
                          &max_states, &seconds, &keys))
        return NULL;
    Buffers b = {.count = 0};
    Ltl L;
    memset(&L, 0, sizeof L);
    const int64_t *initial;
    const uint64_t *m0;
    int64_t starts;
    if (!fields_of(&b, o, &L.n, 0) || !(L.need_place = data_of(&b, o[5], 8, 0))
        || !fields_of(&b, o + 6, &L.d, 1) || !(L.change_place = data_of(&b, o[11], 8, 0))
        || !(L.growing = data_of(&b, o[12], 1, 0))
        || !(L.pr.ops = data_of(&b, o[13], 8, 0)))
        goto fail;
    L.pr.length = items_of(&b) / 2;
    if (!(L.pr.atom_ptr = data_of(&b, o[14], 8, 0))) goto fail;
    L.pr.atoms = items_of(&b) - 1;
    if (!(L.pr.lin_ptr = data_of(&b, o[15], 8, 0)) || !(L.pr.lin_word = data_of(&b, o[16], 8, 0))
        || !(L.pr.lin_shift = data_of(&b, o[17], 8, 0))
        || !(L.pr.lin_mask = data_of(&b, o[18], 8, 0))
        || !(L.pr.lin_coef = data_of(&b, o[19], 8, 0)) || !(L.pr.bound = data_of(&b, o[20], 8, 0))
        || !(L.aptr = data_of(&b, o[21], 8, 0)) || !(L.asucc = data_of(&b, o[22], 8, 0))
        || !(L.required = data_of(&b, o[23], 8, 0)) || !(L.accepting = data_of(&b, o[24], 8, 0))
        || !(initial = data_of(&b, o[25], 8, 0)))
        goto fail;
    starts = items_of(&b);
    if (!stubborn_of(&b, o + 26, &L.st) || !(m0 = data_of(&b, o[37], 8, 0))) goto fail;
    L.words = items_of(&b);
    L.width = L.words + 1;
    if (!(L.rows = data_of(&b, o[38], 8, 1))) goto fail;
    L.capacity = items_of(&b) / L.width;
    if (!(L.table = data_of(&b, o[39], 8, 1))) goto fail;
    L.tmask = items_of(&b) - 1;
    L.bits = bits;
    L.keys = keys;
    L.st.on = on;
    if (max_states > L.capacity) max_states = L.capacity;
    if (10 * max_states > 7 * (L.tmask + 1)) max_states = 7 * (L.tmask + 1) / 10;
    int64_t T = L.n.transitions;
    L.next = PyMem_RawMalloc(8 * (size_t)(2 * L.width));
    L.stack = PyMem_RawMalloc((size_t)L.pr.length + 1 + (size_t)T);
    L.enabled = PyMem_RawMalloc(sizeof(int64_t) * (size_t)(5 * T + 5));
    if (!L.next || !L.stack || !L.enabled) {
        PyMem_RawFree(L.next); PyMem_RawFree(L.stack); PyMem_RawFree(L.enabled);
        PyErr_NoMemory();
        goto fail;
    }
    L.probe_row = L.next + L.width;
    L.is_enabled = L.stack + L.pr.length + 1;
    L.best = L.enabled + T + 1;
    L.members = L.best + T + 1;
    L.in = L.members + T + 1;
    L.work = L.in + T + 1;
    for (int64_t t = 0; t < T; t++) L.in[t] = 0;
    Stack call = {0}, open = {0}, roots = {0}, todo = {0};
    uint8_t *done = NULL;
    int code = LTL_HOLDS, ok = 1;
    int64_t count = 0, info = 0;
    Py_BEGIN_ALLOW_THREADS
    double deadline = now_seconds() + seconds;
    done = PyMem_RawCalloc(2 * (size_t)(max_states > 0 ? max_states : 1), 1);
    if (!done) ok = 0;
    else L.on_stack = done + (max_states > 0 ? max_states : 1);
    uint64_t m_start = ok ? atoms_of(m0, &L.pr, &L.n, L.stack) : 0;
    for (int64_t i = 0; i < starts && ok && code == LTL_HOLDS; i++) {
        int64_t a = initial[i], slot;
        uint64_t h;
        if ((L.required[a] & m_start) != L.required[a]) continue;
        if (ltl_find(&L, m0, a, &slot, &h) >= 0) continue;
        if (count >= max_states) { code = LTL_LIMIT; break; }
        memcpy(L.rows + count * L.width, L.probe_row, 8 * (size_t)L.width);
        L.table[slot] = entry(h, count);
        int64_t p = count++;
        ok = push(&open, p) && push(&roots, p + 1) && push(&roots, (int64_t)L.accepting[a]);
        /* a frame: the product state, where its transitions start on todo, the one
         * being fired, and the automaton move being tried for it */
        int64_t begin = todo.size;
        L.on_stack[p] = 1;
        if (ok) code = ltl_expand(&L, p, &todo, &info, &ok);
        ok = ok && push(&call, p) && push(&call, begin) && push(&call, begin) && push(&call, 0);
        while (call.size && ok && code == LTL_HOLDS) {
            int64_t f = call.size - 4;
            int64_t pp = call.at[f], at = call.at[f + 2], bi = call.at[f + 3];
            int pushed = 0;
            /* the top frame's transitions run to the end of todo */
            while (at < todo.size && !pushed && code == LTL_HOLDS && ok) {
                int64_t t = todo.at[at];
                const uint64_t *row = L.rows + pp * L.width;
                int64_t aa = (int64_t)row[L.words];
                if (t < 0) memcpy(L.next, row, 8 * (size_t)L.words);
                else {
                    int64_t k = counter_fire(row, L.next, L.words, &L.d, t, 1);
                    if (k >= 0) { code = LTL_OVERFLOW; info = L.change_place[k]; break; }
                }
                uint64_t m = atoms_of(L.next, &L.pr, &L.n, L.stack);
                int64_t moves = L.aptr[aa + 1] - L.aptr[aa];
                while (bi < moves) {
                    int64_t bnode = L.asucc[L.aptr[aa] + bi++];
                    if ((L.required[bnode] & m) != L.required[bnode]) continue;
                    int64_t q = ltl_find(&L, L.next, bnode, &slot, &h);
                    if (q < 0) {
                        if (count >= max_states) { code = LTL_LIMIT; break; }
                        /* the clock every 256 markings: an expansion of a wide net
                         * can take a millisecond */
                        if ((count & 255) == 0 && now_seconds() > deadline) {
                            code = LTL_TIME; break;
                        }
                        memcpy(L.rows + count * L.width, L.probe_row, 8 * (size_t)L.width);
                        L.table[slot] = entry(h, count);
                        q = count++;
                        call.at[f + 2] = at;
                        call.at[f + 3] = bi;
                        ok = push(&open, q) && push(&roots, q + 1)
                             && push(&roots, (int64_t)L.accepting[bnode]);
                        int64_t qbegin = todo.size;
                        L.on_stack[q] = 1;
                        if (ok) code = ltl_expand(&L, q, &todo, &info, &ok);
                        ok = ok && push(&call, q) && push(&call, qbegin) && push(&call, qbegin)
                             && push(&call, 0);
                        pushed = 1;
                        break;
                    }
                    if (!done[q]) {
                        /* a cycle closes: every root above q's joins the component below */
                        uint64_t met = 0;
                        while (roots.at[roots.size - 2] > q + 1) {
                            met |= (uint64_t)roots.at[roots.size - 1];
                            roots.size -= 2;
                        }
                        roots.at[roots.size - 1] =
                            (int64_t)((uint64_t)roots.at[roots.size - 1] | met);
                        if ((uint64_t)roots.at[roots.size - 1] == all) {
                            code = LTL_ACCEPTING;
                            break;
                        }
                    }
                }
                if (pushed || code != LTL_HOLDS) break;
                at++;
                bi = 0;
            }
            if (pushed || code != LTL_HOLDS || !ok) continue;
            /* every successor of pp is done with: its frame and its transitions go */
            todo.size = call.at[f + 1];
            call.size -= 4;
            L.on_stack[pp] = 0;
            if (roots.at[roots.size - 2] == pp + 1) {      /* pp roots a finished component */
                roots.size -= 2;
                int64_t w;
                do {
                    w = open.at[--open.size];
                    done[w] = 1;
                } while (w != pp);
            }
        }
    }
    Py_END_ALLOW_THREADS
    PyMem_RawFree(done);
    PyMem_RawFree(call.at);
    PyMem_RawFree(open.at);
    PyMem_RawFree(roots.at);
    PyMem_RawFree(todo.at);
    PyMem_RawFree(L.next);
    PyMem_RawFree(L.stack);
    PyMem_RawFree(L.enabled);
    release(&b);
    if (!ok) return PyErr_NoMemory();
    return Py_BuildValue("(iLL)", code, (long long)count, (long long)info);
fail:
    release(&b);
    return NULL;
}

static PyMethodDef methods[] = {
    {"step_words", py_step_words, METH_VARARGS, "Expand markings of several words."},
    {"step_one_word", py_step_one_word, METH_VARARGS, "Expand markings of one word."},
    {"rehash", py_rehash, METH_VARARGS, "Fill a free table with the queue's first rows."},
    {"out_degree", py_out_degree, METH_VARARGS, "Enabled transitions per marking."},
    {"paired_index", py_paired_index, METH_VARARGS, "The backward search's table."},
    {"backward", py_backward, METH_VARARGS, "Markings that reach the frontier."},
    {"packed_edges", py_packed_edges, METH_VARARGS, "Every edge of the explored markings."},
    {"backward_one_word", py_backward_one_word, METH_VARARGS,
     "Markings of one word that reach the frontier."},
    {"permute_rows", py_permute_rows, METH_VARARGS, "Reorder rows in place."},
    {"counter_step", py_counter_step, METH_VARARGS, "Expand markings of counters."},
    {"counter_out_degree", py_counter_out_degree, METH_VARARGS,
     "Enabled transitions per marking of counters."},
    {"counter_walk", py_counter_walk, METH_VARARGS,
     "The edges of markings of counters, or those that reach the frontier."},
    {"product_step", py_product_step, METH_VARARGS,
     "Expand rows of a property's product until a violation."},
    {"product_edges", py_product_edges, METH_VARARGS,
     "The arcs between a product's pending rows."},
    {"scc", py_scc, METH_VARARGS, "Strongly connected components of a CSR graph."},
    {"back_reach", py_back_reach, METH_VARARGS, "What reaches a set, backwards."},
    {"scatter_by_source", py_scatter_by_source, METH_VARARGS,
     "A stable counting sort of a graph's edges by their source."},
    {"ltl_product", py_ltl_product, METH_VARARGS,
     "An accepting cycle of a graph's product with a Buchi automaton, on the fly."},
    {"ltl_search", py_ltl_search, METH_VARARGS,
     "An accepting cycle of a net's product with a Buchi automaton, on the fly."},
    {"slot_of_words", py_slot_of_words, METH_VARARGS, "A row's slot in a table of 2^bits."},
    {"slot_of_word", py_slot_of_word, METH_VARARGS, "A word's slot in a table of 2^bits."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "mcl2pnml.analysis.statespace.loops._native",
    "The exploration loops in C (see analysis/statespace/loops/c.py).", -1, methods,
};

PyMODINIT_FUNC PyInit__native(void) {
    PyObject *m = PyModule_Create(&module);
    if (m && (PyModule_AddIntConstant(m, "GOING", GOING) < 0
              || PyModule_AddIntConstant(m, "NOT_SAFE", NOT_SAFE) < 0
              || PyModule_AddIntConstant(m, "LIMIT", LIMIT) < 0
              || PyModule_AddIntConstant(m, "QUEUE_FULL", QUEUE_FULL) < 0
              || PyModule_AddIntConstant(m, "TABLE_FULL", TABLE_FULL) < 0
              || PyModule_AddIntConstant(m, "OVERFLOW", OVERFLOW) < 0
              || PyModule_AddIntConstant(m, "GROWING", GROWING) < 0
              || PyModule_AddIntConstant(m, "FOUND_BAD", FOUND_BAD) < 0
              || PyModule_AddIntConstant(m, "FOUND_DEAD", FOUND_DEAD) < 0)) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
