"""The contact colours' edge colouring (``contact.layout = "contacts"``, :mod:`.contact_colour`):
the listed pairs are given colours so that no two pairs of a colour share a ball (an edge
colouring of the contact graph, as Box2D v3's constraint graph does), on the device.

The colouring is made each time the neighbour lists are rebuilt, and only for the pairs new to
the lists: a pair that was listed before keeps its colour (:func:`colour_carry`, looked up in the
stash of the old lists as its resting impulse is, ``stash.stashed_row``), and stays valid, since
two such pairs that share a ball had different colours before. While a pour lands the lists are
rebuilt every step, but only the few pairs of the balls that landed are new. The new pairs are
coloured speculatively (:func:`colour_rounds`, Gebremedhin and Manne's parallel greedy colouring
with the conflicts settled by priority): in each round (:func:`colour_round`), every uncoloured
pair proposes the first colour free at both its balls (neither held by a coloured pair nor
proposed by another pair in the round before: :func:`colours_around`), and keeps the colour it
proposed in the round before unless a pair at one of its balls holds it, or proposed it and comes
first in priority. The priority: the lower the height of a pair's midpoint (in bands of ``band``
[m] along "up"), the earlier, ties broken by a hash of its index, then the index. A round reads
only what the round before wrote (two copies of the colours and the proposals, written in turn:
:func:`round_copies`), so the colours do not depend on the order the threads run in: the runs
stay bit-for-bit repeatable. A pair takes its colour *rising*: its search starts at the colour
after those of the pairs that hold its lower ball from below (cyclically), and it waits while one
of those is uncoloured, so that a column's pairs take rising colours and a sweep's support climbs
it in one sweep (a heavy ball on a column of light ones). A pair that finds all ``COLOURS``
colours taken at its balls, or is still uncoloured after ``ROUND_CAP`` rounds, goes to an
*overflow* set, swept after the colours one pair after another, in index order (and coloured
again at the next rebuild). :func:`colour_sort` then lays the pairs out colour by colour
(``pairs[start[c] : start[c + 1]]``, each colour in index order: the layout, and so a saved run,
does not depend on the order the threads ran in). Every listed pair is coloured, so
the pairs of balls set apart (:mod:`.apart`) need no pass of their own. :class:`PairColouring`
keeps the colours and drives the kernels.
"""

from dataclasses import dataclass, field
from typing import Any, TypeAlias

import numpy as np
import taichi as ti

from ti_golf.physics.types import NeighbourLists, int_array, kernel, pair_table
from ti_golf.runtime import plain_compile
from ti_golf.solvers.links import listed, owner_slot, slot_bits
from ti_golf.solvers.stash import stashed_row

COLOURS = 32
"""Colours of the pairs (the bits of a ball's mask): a pair that finds them all taken at its balls
goes to the overflow set. A ball has about a dozen pairs in a pile, and a greedy colouring needs
at most 2·pairs − 1 colours at a ball."""

OVERFLOW = COLOURS
"""The colour of the pairs swept one after another after the colours."""

UNCOLOURED = -1
"""The colour of a pair before a round gives it one (and its proposal when it has none)."""

ROUNDS_PER_LAUNCH = 4
"""Colouring rounds a launch of :func:`colour_rounds` makes before it says how many pairs are
left (an even number: the rounds write the two copies of the colours in turn)."""

ROUND_CAP = 256
"""Colouring rounds after which the pairs still uncoloured go to the overflow set."""

KEY_BITS = 20
"""Low bits of a pair's priority key that hold the hash of its index (the height band is above)."""

BAND_DIAMETERS = 0.25
"""Height of the priority's bands, in diameters of the balls the lists are built for: of two
pairs that share a ball and propose one colour, the pair of the lower band keeps it."""

SORT_CHUNK = 512
"""Pairs a thread of :func:`colour_sort` takes: the sort's parallel loops have a thread per
``SORT_CHUNK`` listed pairs (about 600 in the 100,000-ball pour's pile)."""

BAND_LIMIT = 1 << 10
"""Height bands of the priority key, either side of zero (a height beyond is taken as the last band)."""


ColourTables: TypeAlias = ti.types.argpack(
    owner=int_array,  # the ball that owns each pair (its upper list holds it), (pairs,)
    colour=int_array,  # each pair's colour, 0 to COLOURS − 1, or OVERFLOW, or UNCOLOURED, (pairs,)
    colour_b=int_array,  # the second copy of the colours, which the colouring rounds write in turn, (pairs,)
    propose=int_array,  # each uncoloured pair's proposed colour, or UNCOLOURED, (pairs,)
    propose_b=int_array,  # its second copy, (pairs,)
    key=int_array,  # each pair's priority key, lower first (height band, hash), (pairs,)
    pairs=int_array,  # the pairs colour by colour, (pairs,)
    fresh=int_array,  # the pairs to colour (new to the lists) in fresh[:count[0]], (pairs,)
    count=int_array,  # the pairs in fresh, (1,)
    start=int_array,  # where each colour starts in pairs; the overflow set last, (COLOURS + 2,)
    fill=int_array,  # the pairs of each colour at the last sort, the overflow set last, (COLOURS + 1,)
    chunk_count=int_array,  # scratch of the sort: each chunk's pairs of each colour, (chunks × (COLOURS + 1),)
)
"""The pairs' colours and the colouring's tables on the device (see :class:`PairColouring`)."""


@ti.func
def index_hash(p):
    """A hash of the pair index p in ``KEY_BITS`` bits (Wellons' lowbias32): pairs of one height
    band are taken in an order with no runs along the storage order (which follows space)."""
    x = ti.cast(p, ti.u32)
    x ^= x >> 16
    x *= ti.u32(0x7FEB352D)
    x ^= x >> 15
    x *= ti.u32(0x846CA68B)
    x ^= x >> 16
    return ti.cast(x & ti.u32((1 << KEY_BITS) - 1), ti.i32)


@kernel
def colour_carry(
    up: ti.math.vec3,
    inv_band: float,
    lists: NeighbourLists,
    tables: ColourTables,
    old_colour: int_array,
    stashed: pair_table,
    stash_first: int_array,
    old_id: int_array,
    carry: ti.template(),
    moved: ti.template(),
):
    """Start a colouring of the listed pairs: each pair's owner noted and its priority key made
    from the height of its midpoint along ``up`` at the lists' build, in bands ``1/inv_band`` [m]
    high (one band with ``inv_band`` 0); with ``carry``, a pair listed before keeps its colour
    ``old_colour`` in the old lists (found through the stash ``stashed``, laid out by
    ``stash_first``, as ``links.carry_ball`` finds its resting impulse; with ``moved``, ball i
    was ball ``old_id[i]`` there), but for the overflow set. The pairs left uncoloured are
    listed in ``tables.fresh``."""
    n = lists.first.shape[0] - 1
    for i in range(n):
        for k in range(listed(lists.first, i)):
            p, j = lists.first[i] + k, lists.upper[i, k]
            height = 0.5 * (lists.x_at_build[i] + lists.x_at_build[j]).dot(up)
            band = ti.cast(ti.floor(height * inv_band), ti.i32)
            band = ti.max(-BAND_LIMIT, ti.min(BAND_LIMIT - 1, band))
            tables.owner[p] = i
            tables.key[p] = (band << KEY_BITS) | index_hash(p)
            c = UNCOLOURED
            if ti.static(carry):
                a, b = i, j
                if ti.static(moved):
                    a, b = old_id[a], old_id[b]
                row, _ = stashed_row(stashed, stash_first, width=0, a=a, b=b, with_friction=True)
                if row < 0:
                    row, _ = stashed_row(stashed, stash_first, width=0, a=b, b=a, with_friction=True)
                if row >= 0:
                    c = old_colour[row]
                if c == OVERFLOW:
                    c = UNCOLOURED
            tables.colour_b[p] = c
    list_fresh(lists.first[n], tables)


@ti.func
def list_fresh(listed_pairs, tables: ti.template()):
    """Copy the carried colours (``colour_b``) to ``colour``, clear the proposals, and list the
    pairs left uncoloured in ``tables.fresh[:count[0]]``, in index order (a stable compaction in
    chunks of ``SORT_CHUNK``, as :func:`colour_sort` sorts: the list does not depend on the order
    the threads ran in)."""
    width = COLOURS + 1
    chunks = (listed_pairs + SORT_CHUNK - 1) // SORT_CHUNK
    for k in range(chunks):
        here = 0
        for p in range(k * SORT_CHUNK, ti.min(listed_pairs, (k + 1) * SORT_CHUNK)):
            c = tables.colour_b[p]
            tables.colour[p] = c
            tables.propose[p], tables.propose_b[p] = UNCOLOURED, UNCOLOURED
            if c == UNCOLOURED:
                here += 1
        tables.chunk_count[k * width] = here
    ti.loop_config(serialize=True)
    for _ in range(1):
        total = 0
        for k in range(chunks):
            here = tables.chunk_count[k * width]
            tables.chunk_count[k * width] = total
            total += here
        tables.count[0] = total
    for k in range(chunks):
        at = tables.chunk_count[k * width]
        for p in range(k * SORT_CHUNK, ti.min(listed_pairs, (k + 1) * SORT_CHUNK)):
            if tables.colour[p] == UNCOLOURED:
                tables.fresh[at] = p
                at += 1


@ti.func
def colour_round(p, odd: ti.template(), climb, up, lists: ti.template(), tables: ti.template()):
    """A colouring round of pair p (see the module's docstring), from the colours and proposals
    of the round before into the other copies (``odd``: the rounds write ``colour_b`` and
    ``propose_b`` in even rounds, ``colour`` and ``propose`` in odd ones; :func:`round_copies`)."""
    c_in, c_out, p_in, p_out = ti.static(round_copies(tables, odd))
    c_now = c_in[p]
    if c_now != UNCOLOURED:
        c_out[p], p_out[p] = c_now, UNCOLOURED
    else:
        mine = p_in[p]
        taken, proposed, level, waiting, lost = colours_around(p, up, lists, tables, c_in, p_in)
        if mine != UNCOLOURED and lost == 0 and (taken >> mine) & 1 == 0:
            c_out[p], p_out[p] = mine, UNCOLOURED  # kept: no pair at its balls holds it or comes first with it
        elif climb != 0 and waiting != 0:
            c_out[p], p_out[p] = UNCOLOURED, UNCOLOURED  # (its lower ball's pairs from below first)
        else:
            c0 = 0
            if climb != 0:
                c0 = level % COLOURS
            c = free_colour(taken | proposed, c0)
            if c == UNCOLOURED:
                c = free_colour(taken, c0)
            if c == UNCOLOURED:
                c_out[p], p_out[p] = OVERFLOW, UNCOLOURED
            else:
                c_out[p], p_out[p] = UNCOLOURED, c


def round_copies(tables: Any, odd: bool) -> tuple:
    """The (colours in, colours out, proposals in, proposals out) of a colouring round: the even
    rounds read ``colour`` and ``propose`` and write their second copies, the odd rounds the other
    way round."""
    copies = (tables.colour, tables.colour_b, tables.propose, tables.propose_b)
    return (copies[1], copies[0], copies[3], copies[2]) if odd else copies


@ti.func
def colours_around(p, up, lists: ti.template(), tables: ti.template(), c_in: ti.template(), p_in: ti.template()):
    """What the pairs at the two balls of uncoloured pair p hold (``c_in``) and proposed (``p_in``)
    in the round before (:func:`colours_at`, at each ball): (the colours taken, as bits; the
    colours proposed, as bits; the colour after the highest of those that hold its lower ball from
    below; whether one of those is still uncoloured; whether a pair that proposed p's own proposal
    comes first in priority)."""
    i = tables.owner[p]
    j = lists.upper[i, p - lists.first[i]]
    below = i
    if lists.x_at_build[j].dot(up) < lists.x_at_build[i].dot(up):
        below = j
    taken, proposed, level, waiting, lost = 0, 0, 0, 0, 0
    for side in ti.static(range(2)):
        b = i if ti.static(side == 0) else j
        t_b, p_b, level_b, waiting_b, lost_b = colours_at(b, p, b == below, up, lists, tables, c_in, p_in)
        taken, proposed = taken | t_b, proposed | p_b
        level, waiting, lost = ti.max(level, level_b), ti.max(waiting, waiting_b), ti.max(lost, lost_b)
    return taken, proposed, level, waiting, lost


@ti.func
def colours_at(b, p, lower, up, lists: ti.template(), tables: ti.template(), c_in: ti.template(), p_in: ti.template()):
    """:func:`colours_around` at ball b of pair p, its pairs but p (``lower``: whether b is p's
    lower ball, whose pairs from below set the level and the wait)."""
    mine, key_p = p_in[p], tables.key[p]
    taken, proposed, level, waiting, lost = 0, 0, 0, 0, 0
    bits = slot_bits(lists.upper.shape[1])
    yb = lists.x_at_build[b].dot(up)
    owned = listed(lists.first, b)
    for m in range(owned + lists.lower_first[b + 1] - lists.lower_first[b]):
        q, other = pair_at(b, m, owned, bits, lists)
        if q != p:
            from_below = lower and lists.x_at_build[other].dot(up) < yb
            c = c_in[q]
            if c == UNCOLOURED:
                bit, first = proposal_of(q, p, mine, key_p, tables, p_in)
                proposed |= bit
                lost |= first
                if from_below:
                    waiting = 1
            elif c < COLOURS:
                taken |= 1 << c
                if from_below:
                    level = ti.max(level, c + 1)
    return taken, proposed, level, waiting, lost


@ti.func
def pair_at(b, m, owned, bits, lists: ti.template()):
    """The m-th pair at ball b, of the ``owned`` in its upper list and then those of its lower
    list: (its index, the other ball)."""
    q, other = lists.first[b] + m, 0
    if m >= owned:
        o, k = owner_slot(lists.lower[lists.lower_first[b] + m - owned], bits)
        q, other = lists.first[o] + k, o
    else:
        other = lists.upper[b, m]
    return q, other


@ti.func
def proposal_of(q, p, mine, key_p, tables: ti.template(), p_in: ti.template()):
    """Of uncoloured pair q at a ball of pair p (whose proposal is ``mine``, its key ``key_p``):
    (the bit of its proposal, 0 without one; 1 when it proposed ``mine`` too and comes first in
    priority: the lower key, then the lower index)."""
    t, bit, first = p_in[q], 0, 0
    if t != UNCOLOURED:
        bit = 1 << t
        if t == mine and (tables.key[q] < key_p or (tables.key[q] == key_p and q < p)):
            first = 1
    return bit, first


@ti.func
def free_colour(mask, c0):
    """The first colour from c0 on (cyclically) whose bit in ``mask`` is clear, or ``UNCOLOURED``."""
    c, tried = c0, 0
    while tried < COLOURS and (mask >> c) & 1 != 0:
        c = (c + 1) % COLOURS
        tried += 1
    if tried == COLOURS:
        c = UNCOLOURED
    return c


@kernel
def colour_rounds(
    rounds: ti.template(), climb: ti.i32, last: ti.i32, up: ti.math.vec3, lists: NeighbourLists, tables: ColourTables
) -> ti.i32:
    """``rounds`` rounds (an even number) of the colouring of the pairs in ``tables.fresh`` (see
    the module's docstring), a parallel loop each, then the pairs laid out colour by colour
    (:func:`colour_sort`); with ``last``, the pairs still uncoloured go to the overflow set first.
    Returns how many pairs are still uncoloured. With ``climb``, colours rise up a pile."""
    for r in ti.static(range(rounds)):
        for m in range(tables.count[0]):
            colour_round(tables.fresh[m], r % 2 == 1, climb, up, lists, tables)
    left = 0
    for m in range(tables.count[0]):
        p = tables.fresh[m]
        if tables.colour[p] == UNCOLOURED:
            if last != 0:
                tables.colour[p] = OVERFLOW
            else:
                left += 1  # (an integer sum: the same on every thread order)
    colour_sort(lists.first[lists.first.shape[0] - 1], tables)
    return left


@ti.func
def colour_sort(listed_pairs, tables: ti.template()):
    """Lay the ``listed_pairs`` pairs out colour by colour: ``tables.pairs[start[c] : start[c + 1]]`` are
    the pairs of colour c in index order, the overflow set last (a stable counting sort, so the
    layout does not depend on the order the threads ran in). Uncoloured pairs (a colouring not yet
    finished) are left out. The pairs are taken in chunks of ``SORT_CHUNK``, a thread each: each
    chunk counts its pairs of each colour (``chunk_count``, a row a chunk), the counts are scanned
    over the chunks colour by colour (``fill``: each colour's pairs), then over the colours
    (``start``), and each chunk places its pairs from its own offsets.

    A chunk's row of counts is its thread's alone, so the counts are plain adds, not ``+=``, which
    Taichi makes an integer atomic: on its Vulkan backend (Taichi 1.7.4, mesa's lavapipe) a
    thread's loop of integer atomics on one entry added up to at most 2, and the layout then left
    most pairs out of every sweep."""
    width = COLOURS + 1
    chunks = (listed_pairs + SORT_CHUNK - 1) // SORT_CHUNK
    for k in range(chunks):
        for c in range(width):
            tables.chunk_count[k * width + c] = 0
        for p in range(k * SORT_CHUNK, ti.min(listed_pairs, (k + 1) * SORT_CHUNK)):
            c = tables.colour[p]
            if c != UNCOLOURED:
                tables.chunk_count[k * width + c] = tables.chunk_count[k * width + c] + 1
    for c in range(width):
        total = 0
        for k in range(chunks):
            here = tables.chunk_count[k * width + c]
            tables.chunk_count[k * width + c] = total
            total += here
        tables.fill[c] = total
    ti.loop_config(serialize=True)
    for c in range(width + 1):
        tables.start[c] = 0
        if c > 0:
            tables.start[c] = tables.start[c - 1] + tables.fill[c - 1]
    for k in range(chunks):
        for p in range(k * SORT_CHUNK, ti.min(listed_pairs, (k + 1) * SORT_CHUNK)):
            c = tables.colour[p]
            if c != UNCOLOURED:
                at = tables.chunk_count[k * width + c]
                tables.pairs[tables.start[c] + at] = p
                tables.chunk_count[k * width + c] = at + 1


def sort_chunks(room: int) -> int:
    """The entries of ``chunk_count`` for pair tables of ``room`` entries (:func:`colour_sort`)."""
    return max(1, -(-room // SORT_CHUNK)) * (COLOURS + 1)


@dataclass
class PairColouring:
    """The pairs' colours of a collision solver's lists, on the device (see the module's docstring).

    Attributes:
        band: height [m] of the priority's bands (of two pairs proposing one colour at a ball, the
            lower keeps it).
        climb: whether the colours rise up a pile (see the module's docstring).
        record: whether each build records in ``fresh`` the pairs it coloured (a read from the
            device, for the benchmarks).
        builds, rounds, rounds_max: the builds so far, their colouring rounds in all and at most.
        fresh: with ``record``, the pairs new to the lists at each build.
        tables: the :data:`ColourTables` on the device.
    """

    band: float
    climb: bool = True
    record: bool = False
    builds: int = 0
    rounds: int = 0
    rounds_max: int = 0
    fresh: list[int] = field(default_factory=list)
    tables: Any = None
    _room: int = 0
    _n: int = 0
    _up: Any = None

    TABLES = ("owner", "colour", "colour_b", "propose", "propose_b", "key", "pairs", "fresh", "count", "start", "fill")
    """The arrays of :data:`ColourTables` that a saved run keeps, in its order (``chunk_count``, the
    sort's scratch, is made again)."""

    def saved(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        """What the next steps and rebuilds read of the colours, for a saved run: the numbers by
        name and the tables' arrays (none before the first build)."""
        values = {
            "builds": self.builds,
            "rounds": self.rounds,
            "rounds_max": self.rounds_max,
            "room": self._room,
            "n": self._n,
        }
        arrays = {} if self.tables is None else {name: self.tables[name].to_numpy() for name in self.TABLES}
        return values, arrays

    def restore(self, values: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
        """Take back what :meth:`saved` returned."""
        self.builds, self.rounds, self.rounds_max = values["builds"], values["rounds"], values["rounds_max"]
        self._room, self._n = values["room"], values["n"]
        if arrays:
            tables = {}
            for name in self.TABLES:
                tables[name] = ti.ndarray(ti.i32, arrays[name].shape)
                tables[name].from_numpy(arrays[name])
            self.tables = ColourTables(**tables, chunk_count=ti.ndarray(ti.i32, sort_chunks(self._room)))

    def carry(self, lists: Any, n: int, pairs_room: int, gravity: Any, stash: tuple | None) -> None:
        """Start the colouring of the neighbour lists ``lists`` (a ``NeighbourLists`` pack of ``n``
        balls whose pair tables hold ``pairs_room`` entries, "up" against ``gravity``): with
        ``stash`` = (the stashed old lists, their ``first``, whether the balls moved, their old
        ids), the pairs listed before keep their colours (:func:`colour_carry`); call while the
        stash is kept (the sweep's table, scratch between steps)."""
        old = self.tables
        carried = stash is not None and old is not None and self._n == n
        if old is None or self._room < pairs_room or self._n != n:
            self._room, self._n = max(pairs_room, 1), n
            names = ("owner", "colour", "colour_b", "propose", "propose_b", "key", "pairs", "fresh")
            self.tables = ColourTables(
                **{name: ti.ndarray(ti.i32, self._room) for name in names},
                count=ti.ndarray(ti.i32, 1),
                start=ti.ndarray(ti.i32, COLOURS + 2),
                fill=ti.ndarray(ti.i32, COLOURS + 1),
                chunk_count=ti.ndarray(ti.i32, sort_chunks(self._room)),
            )
        t = self.tables
        g = np.asarray(gravity, dtype=float)
        self._up = ti.math.vec3(*(-g / np.linalg.norm(g) if np.linalg.norm(g) > 0.0 else np.zeros(3)))
        inv_band = 1.0 / self.band if self.band > 0.0 else 0.0
        with plain_compile(vulkan=True):
            if carried and stash is not None:  # (carried: a stash)
                stashed, stash_first, moved, old_id = stash
                old_colour, moved = old["colour"], bool(moved)
            else:  # (stand-ins, never read)
                (stashed, stash_first), old_colour, moved, old_id = _no_stash(), t["colour"], False, t["count"]
            colour_carry(
                self._up, inv_band, lists, t, old_colour, stashed, stash_first, old_id, carry=carried, moved=moved
            )

    def build(self, lists: Any) -> None:
        """Colour the pairs :meth:`carry` left uncoloured, and lay the pairs out colour by colour."""
        t, rounds, left = self.tables, 0, 1
        with plain_compile(vulkan=True):
            while left > 0:
                last = int(rounds + ROUNDS_PER_LAUNCH >= ROUND_CAP)
                left = colour_rounds(ROUNDS_PER_LAUNCH, int(self.climb), last, self._up, lists, t)
                rounds += ROUNDS_PER_LAUNCH
        self.builds += 1
        self.rounds += rounds
        self.rounds_max = max(self.rounds_max, rounds)
        if self.record:
            self.fresh.append(int(t["count"].to_numpy()[0]))

    def sizes(self) -> tuple[int, tuple[int, ...], int]:
        """(colours in use, the pairs of each, the pairs in the overflow set) of the last build."""
        start = self.tables["start"].to_numpy()
        sizes = np.diff(start)
        used = np.nonzero(sizes[:COLOURS])[0]
        colours = int(used[-1]) + 1 if used.size else 0
        return colours, tuple(int(s) for s in sizes[:colours]), int(sizes[OVERFLOW])


def _no_stash() -> tuple:
    """Stand-ins for :func:`colour_carry`'s stash arguments when nothing is carried (never read)."""
    global _STAND_INS
    if _STAND_INS is None:
        _STAND_INS = (ti.ndarray(ti.f32, (1, 3)), ti.ndarray(ti.i32, 1))  # (the Gauss–Seidel sweeps' table)
    return _STAND_INS


_STAND_INS: tuple | None = None
