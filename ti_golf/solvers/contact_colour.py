"""Gauss–Seidel sweeps laid out by contact colours (``contact.layout = "contacts"``).

The column layout (:mod:`.colour`) hands each thread a block of 2 × 2 grid columns and walks its
balls bottom-up: a pour of 100,000 balls gives about a hundred blocks of a colour, so a GPU runs
about a hundred threads. This layout hands each thread one *pair*: the listed pairs are given
colours so that no two pairs of a colour share a ball (an edge colouring of the contact graph, as
Box2D v3's constraint graph does), and a sweep takes the colours in turn, every pair of a colour
at once, one thread each. The update of a pair is the column layout's (:func:`.colour.sweep_pair`:
the same equations, :func:`.contact.pair_step`); only the order in which the pairs meet differs.

**The colouring** is made on the device each time the neighbour lists are rebuilt, and only for
the pairs new to the lists: a pair that was listed before keeps its colour (:func:`colour_carry`,
looked up in the stash of the old lists as its resting impulse is, ``links.stashed_row``), and
stays valid, since two such pairs that share a ball had different colours before. While a pour
lands the lists are rebuilt every step, but only the few pairs of the balls that landed are new.
The new pairs are coloured speculatively (:func:`colour_rounds`, Gebremedhin and Manne's
parallel greedy colouring with the conflicts settled by priority): in each round, every
uncoloured pair proposes the first colour free at both its balls (neither held by a coloured pair
nor proposed by another pair in the round before), and keeps the colour it proposed in the round
before unless a pair at one of its balls holds it, or proposed it and comes first in priority.
The priority: the lower the height of a pair's midpoint (in bands of ``band`` [m] along "up"),
the earlier, ties broken by a hash of its index, then the index. A round reads only what the
round before wrote (two copies of the colours and the proposals, written in turn), so the colours
do not depend on the order the threads run in: the runs stay bit-for-bit repeatable. A pair
takes its colour *rising*: its search starts at the colour after those of the pairs that hold
its lower ball from below (cyclically), and it waits while one of those is uncoloured, so that a
column's pairs take rising colours and a sweep's support climbs it in one sweep (a heavy ball on
a column of light ones). A pair that finds all ``COLOURS`` colours taken at its balls, or is
still uncoloured after ``ROUND_CAP`` rounds, goes to an *overflow* set, swept after the colours
one pair after another, in index order (and coloured again at the next rebuild).
:func:`colour_sort` then lays the pairs out colour by colour (``pairs[start[c] : start[c +
1]]``). Every listed pair is coloured, so the pairs of balls set apart (:mod:`.apart`) need no
pass of their own.

**A sweep** (:func:`colour_pass`): each ball meets its planes and the terrain (a thread per ball),
then the colours follow one another (a parallel loop per colour, a thread per pair, its bounds
read from ``start`` on the device), then the overflow set: ``SPAN`` colours a launch (the first
with the surfaces), the overflow set a launch of its own, or all in one launch when the span is
``COLOURS`` (:meth:`ContactColours.spans`). A sweep's parallel
loops therefore each hold a ball per thread, or a pair per thread: work in proportion to the
balls. The position projection (B.18) is laid out the same way, its planes last.
"""

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import taichi as ti

from ti_golf.errors import ConfigError
from ti_golf.physics.types import (
    BallState,
    ModelArrays,
    NeighbourLists,
    StepScratch,
    float_array,
    int_array,
    kernel,
    of_ball,
    pair_table,
    scalars_of,
)
from ti_golf.runtime import on_cpu, plain_compile
from ti_golf.scene.schema import AT_REST, OUT_OF_BOUNDS
from ti_golf.solvers.colour import (
    PROJECTIONS,
    inelastic_speed,
    project_pair,
    project_planes,
    stands_firm,
    step_phases,
    sweep_pair,
    upward,
)
from ti_golf.solvers.links import listed, owner_slot, slot_bits, stashed_row
from ti_golf.solvers.pairs import QUIET
from ti_golf.solvers.phases import Phase
from ti_golf.solvers.surfaces import surface_impulses

COLOURS = 32
"""Colours of the pairs (the bits of a ball's mask): a pair that finds them all taken at its balls
goes to the overflow set. A ball has about a dozen pairs in a pile, and a greedy colouring needs
at most 2·pairs − 1 colours at a ball."""

OVERFLOW = COLOURS
"""The colour of the pairs swept one after another after the colours."""

UNCOLOURED = -1
"""The colour of a pair before a round gives it one (and its proposal when it has none)."""

SPAN = 4
"""Colours a launch of :func:`colour_pass` takes, one parallel loop each: the pair update is
compiled once per colour of a launch, so a launch of all ``COLOURS`` costs a host call a pass
instead of nine, but took 2.6 times as long to compile on the CPU (a fresh cache's first step,
with every other kernel: 251 s against 97 s on a loaded 2-core machine), and LLVM's full
optimisation of it did not end within 15 minutes. ``TI_GOLF_COLOURS_PER_LAUNCH`` (a divisor of
``COLOURS``) sets another span, to measure it on a GPU (``make gpu-check``)."""

SPAN_ENV = "TI_GOLF_COLOURS_PER_LAUNCH"
"""The environment variable that sets the colours a launch takes (see ``SPAN``)."""

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

BAND_LIMIT = 1 << 10
"""Height bands of the priority key, either side of zero (a height beyond is taken as the last band)."""


def resolve_layout(layout: str) -> str:
    """The layout the sweeps take for ``contact.layout``: ``auto`` is the column layout on CPU
    backends (a few threads, each walking its columns bottom-up, is the fastest there) and the
    contact colours elsewhere (a GPU needs thousands of threads)."""
    if layout == "auto":
        return "columns" if on_cpu() else "contacts"
    return layout


def colours_per_launch() -> int:
    """Colours a launch of :func:`colour_pass` takes (``SPAN``, or ``TI_GOLF_COLOURS_PER_LAUNCH``)."""
    text = os.environ.get(SPAN_ENV, "")
    if not text:
        return SPAN
    allowed = [k for k in range(1, COLOURS + 1) if COLOURS % k == 0]
    if not text.isdigit() or int(text) not in allowed:
        raise ConfigError(SPAN_ENV, None, f"must be one of {', '.join(map(str, allowed))}, not {text!r}")
    return int(text)


ColourTables = ti.types.argpack(
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
    fill=int_array,  # scratch: the pairs placed of each colour, (COLOURS + 1,)
)
"""The pairs' colours (:mod:`.contact_colour`)."""


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
    carry: ti.template(),
    moved: ti.template(),
    up: ti.math.vec3,
    inv_band: float,
    lists: NeighbourLists,
    tables: ColourTables,
    old_colour: int_array,
    stashed: pair_table,
    stash_first: int_array,
    old_id: int_array,
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
                row, _ = stashed_row(stashed, stash_first, 0, a, b, True)
                if row < 0:
                    row, _ = stashed_row(stashed, stash_first, 0, b, a, True)
                if row >= 0:
                    c = old_colour[row]
                if c == OVERFLOW:
                    c = UNCOLOURED
            tables.colour_b[p] = c
    tables.count[0] = 0
    for p in range(lists.first[n]):
        c = tables.colour_b[p]
        tables.colour[p] = c
        tables.propose[p], tables.propose_b[p] = UNCOLOURED, UNCOLOURED
        if c == UNCOLOURED:
            tables.fresh[ti.atomic_add(tables.count[0], 1)] = p


@ti.func
def colour_round(  # noqa: C901 (a ti.func of the colouring kernel, inlined in it)
    p,
    climb,
    up,
    lists: ti.template(),
    tables: ti.template(),
    c_in: ti.template(),
    c_out: ti.template(),
    p_in: ti.template(),
    p_out: ti.template(),
):
    """A colouring round of pair p (see the module's docstring), from the colours ``c_in`` and
    proposals ``p_in`` of the round before into ``c_out`` and ``p_out``."""
    c_now = c_in[p]
    if c_now != UNCOLOURED:
        c_out[p], p_out[p] = c_now, UNCOLOURED
    else:
        i = tables.owner[p]
        j = lists.upper[i, p - lists.first[i]]
        below = i
        if lists.x_at_build[j].dot(up) < lists.x_at_build[i].dot(up):
            below = j
        mine, key_p = p_in[p], tables.key[p]
        taken, proposed, level, waiting, lost = 0, 0, 0, 0, 0
        bits = slot_bits(lists.upper.shape[1])
        for side in ti.static(range(2)):
            b = i if ti.static(side == 0) else j
            yb = lists.x_at_build[b].dot(up)
            owned = listed(lists.first, b)
            for m in range(owned + lists.lower_first[b + 1] - lists.lower_first[b]):
                q, other = lists.first[b] + m, 0
                if m >= owned:
                    o, k = owner_slot(lists.lower[lists.lower_first[b] + m - owned], bits)
                    q, other = lists.first[o] + k, o
                else:
                    other = lists.upper[b, m]
                if q != p:
                    from_below = b == below and lists.x_at_build[other].dot(up) < yb
                    c = c_in[q]
                    if c == UNCOLOURED:
                        t = p_in[q]
                        if t != UNCOLOURED:
                            proposed |= 1 << t
                            if t == mine and (tables.key[q] < key_p or (tables.key[q] == key_p and q < p)):
                                lost = 1
                        if from_below:
                            waiting = 1
                    elif c < COLOURS:
                        taken |= 1 << c
                        if from_below:
                            level = ti.max(level, c + 1)
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
        if ti.static(r % 2 == 0):
            for s in range(tables.count[0]):
                colour_round(
                    tables.fresh[s],
                    climb,
                    up,
                    lists,
                    tables,
                    tables.colour,
                    tables.colour_b,
                    tables.propose,
                    tables.propose_b,
                )
        else:
            for s in range(tables.count[0]):
                colour_round(
                    tables.fresh[s],
                    climb,
                    up,
                    lists,
                    tables,
                    tables.colour_b,
                    tables.colour,
                    tables.propose_b,
                    tables.propose,
                )
    left = 0
    for s in range(tables.count[0]):
        p = tables.fresh[s]
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
    the pairs of colour c (in the order their threads took places: the pairs of a colour share no
    ball, so the order among them changes nothing), the overflow set last, sorted by index (it is
    swept in that order). Uncoloured pairs (a colouring not yet finished) are left out."""
    for c in range(COLOURS + 2):
        tables.start[c] = 0
    for c in range(COLOURS + 1):
        tables.fill[c] = 0
    for p in range(listed_pairs):
        if tables.colour[p] != UNCOLOURED:
            ti.atomic_add(tables.start[tables.colour[p] + 1], 1)
    ti.loop_config(serialize=True)
    for c in range(COLOURS + 1):
        tables.start[c + 1] += tables.start[c]
    for p in range(listed_pairs):
        c = tables.colour[p]
        if c != UNCOLOURED:
            tables.pairs[tables.start[c] + ti.atomic_add(tables.fill[c], 1)] = p
    ti.loop_config(serialize=True)
    for _ in range(1):  # the overflow set by index: an insertion sort (a few pairs, if any)
        lo, hi = tables.start[OVERFLOW], tables.start[OVERFLOW + 1]
        for m in range(lo + 1, hi):
            p, q = tables.pairs[m], m
            while q > lo:
                if tables.pairs[q - 1] <= p:
                    break
                tables.pairs[q] = tables.pairs[q - 1]
                q -= 1
            tables.pairs[q] = p


@ti.func
def colour_pair(
    p,
    phase,
    contact: ti.template(),
    params: ti.template(),
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
    tables: ti.template(),
):
    """Pair p's update in a sweep of ``phase`` (:func:`.colour.sweep_pair`), as :func:`.colour.sweep_ball`
    makes it for the pairs its ball owns: none for an owner out of bounds or quiet, or in the
    restitution pass (``BOUNCE``) unmarked; the first sweep marks the owner when the pair
    approached faster than the inelastic speed."""
    i = tables.owner[p]
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
        if phase != Phase.BOUNCE or scratch.impact[i] != 0:
            ri, inv_mi = of_ball(model.radius, i), 1.0 / of_ball(model.mass, i)
            if stands_firm(contact, state.status[i]):
                inv_mi = 0.0
            j = lists.upper[i, p - lists.first[i]]
            vi, wi, hit = sweep_pair(
                i,
                j,
                p,
                phase,
                state.x[i],
                state.v[i],
                state.w[i],
                ri,
                inv_mi,
                params.h,
                inelastic_speed(contact, params),
                upward(params),
                contact,
                model,
                lists,
                state,
                scratch,
            )
            state.v[i], state.w[i] = vi, wi
            if phase == Phase.FIRST and hit != 0:
                scratch.impact[i] = 1


@ti.func
def surface_ball(
    i,
    phase,
    contact: ti.template(),
    terrain: ti.template(),
    params: ti.template(),
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
):
    """Ball i's planes and terrain in a sweep of ``phase`` (:func:`.surfaces.surface_impulses`),
    before the sweep's pairs; the first sweep also clears its mark of the restitution pass, which
    its pairs then set (:func:`colour_pair`)."""
    if phase == Phase.FIRST:
        scratch.impact[i] = 0
    firm = stands_firm(contact, state.status[i])
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET and not firm:
        vi, wi = surface_impulses(
            i,
            False,
            state.v[i],
            state.w[i],
            contact,
            terrain,
            params.h,
            inelastic_speed(contact, params),
            model,
            lists,
            state,
            scratch,
            phase,
        )
        state.v[i], state.w[i] = vi, wi


@kernel
def colour_pass(
    phase: ti.i32,
    c0: ti.i32,
    project: ti.template(),
    head: ti.template(),
    span: ti.template(),
    tail: ti.template(),
    scalars: float_array,
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
    tables: ColourTables,
):
    """Part or all of a sweep of ``phase`` (or, with ``project``, of a pass of the position
    projection): with ``head``, each ball's planes and terrain first (:func:`surface_ball`, a
    thread per ball; not in a projection); the pairs of colours ``c0`` to ``c0 + span − 1``, a
    parallel loop per colour, a thread per pair (:func:`colour_pair` or
    :func:`project_colour_pair`), each loop's bounds read from ``tables.start`` on the device;
    with ``tail``, the overflow set after, one pair after another, and in a projection each
    ball's planes last (:func:`.colour.project_planes`)."""
    _, contact, terrain, params = scalars_of(scalars)
    if ti.static(head and not project):
        for i in range(state.x.shape[0]):
            surface_ball(i, phase, contact, terrain, params, model, lists, state, scratch)
    for c in ti.static(range(span)):
        for s in range(tables.start[c0 + c], tables.start[c0 + c + 1]):
            pair_pass(tables.pairs[s], phase, project, contact, params, model, lists, state, scratch, tables)
    if ti.static(tail):
        ti.loop_config(serialize=True)
        for s in range(tables.start[OVERFLOW], tables.start[OVERFLOW + 1]):
            pair_pass(tables.pairs[s], phase, project, contact, params, model, lists, state, scratch, tables)
        if ti.static(project):
            for i in range(state.x.shape[0]):
                moving = state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET
                if moving and state.status[i] != AT_REST:
                    scratch.x_free[i] = project_planes(scratch.x_free[i], of_ball(model.radius, i), contact.k_p, model)


@ti.func
def pair_pass(
    p,
    phase,
    project: ti.template(),
    contact: ti.template(),
    params: ti.template(),
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
    tables: ti.template(),
):
    """Pair p's update in a sweep of ``phase`` (:func:`colour_pair`) or, with ``project``, its
    position projection (:func:`project_colour_pair`)."""
    if ti.static(project):
        project_colour_pair(p, contact.k_p, model, lists, state, scratch, tables)
    else:
        colour_pair(p, phase, contact, params, model, lists, state, scratch, tables)


@ti.func
def project_colour_pair(
    p,
    k_p,
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
    tables: ti.template(),
):
    """Pair p's position projection (:func:`.colour.project_pair`), as :func:`.colour.project_ball`
    makes it for the pairs its ball owns."""
    i = tables.owner[p]
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
        inv_mi = 0.0
        if state.status[i] != AT_REST:
            inv_mi = 1.0 / of_ball(model.mass, i)
        j = lists.upper[i, p - lists.first[i]]
        scratch.x_free[i] = project_pair(
            j, scratch.x_free[i], of_ball(model.radius, i), inv_mi, k_p, model, state, scratch
        )


@dataclass
class ContactColours:
    """The pairs' colours of a collision solver's lists, on the device.

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
    _used: int = COLOURS
    _up: Any = None

    TABLES = ("owner", "colour", "colour_b", "propose", "propose_b", "key", "pairs", "fresh", "count", "start", "fill")
    """The arrays of :data:`ColourTables`, in its order."""

    def saved(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        """What the next steps and rebuilds read of the colours, for a saved run: the numbers by
        name and the tables' arrays (none before the first build)."""
        values = {
            "builds": self.builds,
            "rounds": self.rounds,
            "rounds_max": self.rounds_max,
            "room": self._room,
            "n": self._n,
            "used": self._used,
        }
        arrays = {} if self.tables is None else {name: self.tables[name].to_numpy() for name in self.TABLES}
        return values, arrays

    def restore(self, values: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
        """Take back what :meth:`saved` returned."""
        self.builds, self.rounds, self.rounds_max = values["builds"], values["rounds"], values["rounds_max"]
        self._room, self._n, self._used = values["room"], values["n"], values["used"]
        if arrays:
            tables = {}
            for name in self.TABLES:
                tables[name] = ti.ndarray(ti.i32, arrays[name].shape)
                tables[name].from_numpy(arrays[name])
            self.tables = ColourTables(**tables)

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
            )
        t = self.tables
        g = np.asarray(gravity, dtype=float)
        self._up = ti.math.vec3(*(-g / np.linalg.norm(g) if np.linalg.norm(g) > 0.0 else np.zeros(3)))
        inv_band = 1.0 / self.band if self.band > 0.0 else 0.0
        with plain_compile():
            if not carried:
                colour_carry(False, False, self._up, inv_band, lists, t, t["colour"], *_no_stash(), t["count"])
            else:
                stashed, stash_first, moved, old_id = stash
                old_colour = old["colour"]
                colour_carry(True, bool(moved), self._up, inv_band, lists, t, old_colour, stashed, stash_first, old_id)

    def build(self, lists: Any) -> None:
        """Colour the pairs :meth:`carry` left uncoloured, and lay the pairs out colour by colour."""
        t, rounds, left = self.tables, 0, 1
        with plain_compile():
            while left > 0:
                last = int(rounds + ROUNDS_PER_LAUNCH >= ROUND_CAP)
                left = colour_rounds(ROUNDS_PER_LAUNCH, int(self.climb), last, self._up, lists, t)
                rounds += ROUNDS_PER_LAUNCH
        self.builds += 1
        self.rounds += rounds
        self.rounds_max = max(self.rounds_max, rounds)
        if self.record:
            self.fresh.append(int(t["count"].to_numpy()[0]))
        if colours_per_launch() < COLOURS:  # the launches a pass takes follow the colours in use
            self._used = self.sizes()[0]

    def sizes(self) -> tuple[int, tuple[int, ...], int]:
        """(colours in use, the pairs of each, the pairs in the overflow set) of the last build."""
        start = self.tables["start"].to_numpy()
        sizes = np.diff(start)
        used = np.nonzero(sizes[:COLOURS])[0]
        colours = int(used[-1]) + 1 if used.size else 0
        return colours, tuple(int(s) for s in sizes[:colours]), int(sizes[OVERFLOW])

    def spans(self, project: bool) -> list[tuple[int, bool, int, bool]]:
        """(first colour, head, colours, tail) of each launch of :func:`colour_pass` in a pass (with
        ``project``, of the projection): one launch with a span of ``COLOURS``; else ``SPAN``
        colours a launch (a sweep's first with the balls' surfaces), then the overflow set (and
        a projection's planes) a launch of its own, so that a pile of more colours compiles no
        more kernels than the warm-up's few colours did."""
        span = colours_per_launch()
        if span == COLOURS:
            return [(0, True, COLOURS, True)]
        chunks = [(c0, c0 == 0 and not project, span, False) for c0 in range(0, max(self._used, 1), span)]
        return chunks + [(0, False, 0, True)]

    def launches(self, n: int, iterations: int) -> list[int]:
        """The work items (balls or pairs, each a thread that no other shares) of each parallel loop
        of a step's sweeps and projections with these colours (:func:`gauss_seidel_step`), in
        order, an empty colour's loop included; the overflow set's serial loop counts one item."""
        _, sizes, _ = self.sizes()
        loops = []
        for project, count in ((False, len(step_phases(iterations))), (True, PROJECTIONS)):
            items = []
            for c0, head, span, tail in self.spans(project):
                items += [n] if head and not project else []
                items += [sizes[c] if c < len(sizes) else 0 for c in range(c0, c0 + span)]
                items += ([1] + ([n] if project else [])) if tail else []
            loops += items * count
        return loops


def _no_stash() -> tuple:
    """Stand-ins for :func:`colour_carry`'s stash arguments when nothing is carried (never read)."""
    global _STAND_INS
    if _STAND_INS is None:
        _STAND_INS = (ti.ndarray(float, (1, 2)), ti.ndarray(ti.i32, 1))
    return _STAND_INS


_STAND_INS: tuple | None = None


def gauss_seidel_step(
    colours: ContactColours, iterations: int, scalars: Any, model: Any, lists: Any, state: Any, scratch: Any
) -> None:
    """A step's Gauss–Seidel sweeps (``iterations`` of them and the restitution pass,
    :func:`.colour.step_phases`) laid out by contact colours, from the warm start to the end of the
    sweeps (:func:`colour_pass`: one launch a sweep on GPU backends). The caller finishes the
    step (``collide.collision_step``) and then calls :func:`project`."""
    passes(colours, step_phases(iterations), False, scalars, model, lists, state, scratch)


def project(colours: ContactColours, scalars: Any, model: Any, lists: Any, state: Any, scratch: Any) -> None:
    """The ``PROJECTIONS`` passes of the position projection at the end of a step, laid out as the
    sweeps are: the colours, the overflow set, then each ball's planes."""
    passes(colours, [Phase.FIRST] * PROJECTIONS, True, scalars, model, lists, state, scratch)


def passes(
    colours: ContactColours, phases: Any, proj: bool, scalars: Any, model: Any, lists: Any, state: Any, scratch: Any
) -> None:
    """A pass of :func:`colour_pass` for each of ``phases`` (with ``proj``: of the projection)."""
    t, spans = colours.tables, colours.spans(proj)
    with plain_compile():  # see runtime.plain_compile
        for phase in phases:
            for c0, head, span, tail in spans:
                colour_pass(phase, c0, proj, head, span, tail, scalars, model, lists, state, scratch, t)
