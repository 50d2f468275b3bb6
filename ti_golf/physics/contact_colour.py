"""Gauss–Seidel sweeps laid out by contact colours (``contact.layout = "contacts"``).

The column layout (:mod:`.colour`) hands each thread a block of 2 × 2 grid columns and walks its
balls bottom-up: a pour of 100,000 balls gives about a hundred blocks of a colour, so a GPU runs
about a hundred threads. This layout hands each thread one *pair*: the listed pairs are given
colours so that no two pairs of a colour share a ball (an edge colouring of the contact graph, as
Box2D v3's constraint graph does), and a sweep takes the colours in turn, every pair of a colour
at once, one thread each. The update of a pair is the column layout's (:func:`.colour.sweep_pair`:
the same equations, :func:`.contact.pair_step`); only the order in which the pairs meet differs.

**The colouring** (:func:`colour_rounds`) is made on the device each time the neighbour lists are
rebuilt. Each pair has a priority: the lower the height of its midpoint (in bands of
``band`` [m] along "up"), the earlier, ties broken by a hash of its index, then the index. In
each round every ball finds its uncoloured pair of highest priority and the colours its coloured
pairs hold (a gather over its upper and lower lists, into a bit mask); a pair that is the first of
both its balls takes the lowest colour free in both masks (Jones and Plassmann's parallel greedy
colouring, on pairs). A round reads only what the round before wrote, so the colours are those of
the greedy colouring in priority order, whatever the order the threads run in: the runs stay
bit-for-bit repeatable. A pair that finds all ``COLOURS`` colours taken at its balls goes to an
*overflow* set, swept after the colours one pair after another, in index order.
:func:`colour_sort` then lays the pairs out colour by colour (``pairs[start[c] : start[c + 1]]``).
Every listed pair is coloured, so the pairs of balls set apart (:mod:`.apart`) need no pass of
their own.

**A sweep** (:func:`gauss_seidel_step`): each ball meets its planes and the terrain
(:func:`surface_sweep`, a thread per ball), then the colours follow one another
(:func:`pair_sweep`, ``COLOURS_PER_LAUNCH`` colours a launch, a thread per pair), then the
overflow set. A sweep's launches therefore each hold a ball per thread, or a pair per thread: work
in proportion to the balls. The position projection (B.18) is laid out the same way.
"""

from dataclasses import dataclass
from typing import Any

import numpy as np
import taichi as ti

from ti_golf.physics.colour import (
    PROJECTIONS,
    inelastic_speed,
    project_pair,
    project_planes,
    stands_firm,
    step_phases,
    sweep_pair,
    upward,
)
from ti_golf.physics.contact import BOUNCE, FIRST
from ti_golf.physics.links import listed, owner_slot, slot_bits
from ti_golf.physics.pairs import QUIET
from ti_golf.physics.surfaces import surface_impulses
from ti_golf.physics.types import (
    BallState,
    ModelArrays,
    NeighbourLists,
    StepScratch,
    float_array,
    int_array,
    kernel,
    of_ball,
    scalars_of,
)
from ti_golf.runtime import on_cpu, plain_compile
from ti_golf.scene.schema import AT_REST, OUT_OF_BOUNDS

COLOURS = 32
"""Colours of the pairs (the bits of a ball's mask): a pair that finds them all taken at its balls
goes to the overflow set. A ball has about a dozen pairs in a pile, and a greedy colouring needs
at most 2·pairs − 1 colours at a ball."""

OVERFLOW = COLOURS
"""The colour of the pairs swept one after another after the colours."""

UNCOLOURED = -1
"""The colour of a pair before a round gives it one."""

COLOURS_PER_LAUNCH = 4
"""Colours a launch of :func:`pair_sweep` takes, one parallel loop each: a launch per colour would
cost a host call each, and one launch for all ``COLOURS`` would compile the pair update that many
times and loop over the colours no pile uses."""

ROUNDS_PER_LAUNCH = 8
"""Colouring rounds a launch of :func:`colour_rounds` makes before it says how many pairs are left."""

KEY_BITS = 20
"""Low bits of a pair's priority key that hold the hash of its index (the height band is above)."""

BAND_DIAMETERS = 0.25
"""Height of the priority's bands, in diameters of the balls the lists are built for: a pair of a
lower band is coloured before the pairs of the bands above that share a ball with it, so the
colours run roughly bottom-up."""

BAND_LIMIT = 1 << 10
"""Height bands of the priority key, either side of zero (a height beyond is taken as the last band)."""


def resolve_layout(layout: str) -> str:
    """The layout the sweeps take for ``contact.layout``: ``auto`` is the column layout on CPU
    backends (a few threads, each walking its columns bottom-up, is the fastest there) and the
    contact colours elsewhere (a GPU needs thousands of threads)."""
    if layout == "auto":
        return "columns" if on_cpu() else "contacts"
    return layout


ColourTables = ti.types.argpack(
    owner=int_array,  # the ball that owns each pair (its upper list holds it), (pairs,)
    colour=int_array,  # each pair's colour, 0 to COLOURS − 1, or OVERFLOW, (pairs,)
    key=int_array,  # each pair's priority key, lower first (height band, hash), (pairs,)
    pairs=int_array,  # the pairs colour by colour, (pairs,)
    start=int_array,  # where each colour starts in pairs; the overflow set last, (COLOURS + 2,)
    fill=int_array,  # scratch: the pairs placed of each colour, (COLOURS + 1,)
    mask=int_array,  # each ball's colours taken by its coloured pairs, a bit each, (N,)
    best=int_array,  # each ball's uncoloured pair of highest priority, or −1, (N,)
    level=int_array,  # each ball's colour after those of the pairs that hold it from below, (N,)
)
"""The pairs' colours (:mod:`.contact_colour`)."""


@ti.func
def index_hash(p):
    """A hash of the pair index p in ``KEY_BITS`` bits (Wellons' lowbias32): pairs of one height
    band are taken in an order with no runs along the storage order (which follows space), so
    that a colouring round leaves no long chains of pairs waiting on one another."""
    x = ti.cast(p, ti.u32)
    x ^= x >> 16
    x *= ti.u32(0x7FEB352D)
    x ^= x >> 15
    x *= ti.u32(0x846CA68B)
    x ^= x >> 16
    return ti.cast(x & ti.u32((1 << KEY_BITS) - 1), ti.i32)


@ti.func
def first_of(key: ti.template(), q, top, top_key):
    """Whether pair q comes before pair ``top`` (key ``top_key``; −1: none) in priority: the
    lower key, then the lower index."""
    return top < 0 or key[q] < top_key or (key[q] == top_key and q < top)


@kernel
def colour_init(up: ti.math.vec3, inv_band: float, lists: NeighbourLists, tables: ColourTables) -> ti.i32:
    """Start a colouring of the listed pairs: every pair uncoloured, its owner noted and its
    priority key made from the height of its midpoint along ``up`` at the lists' build, in bands
    ``1/inv_band`` [m] high (one band with ``inv_band`` 0). Returns the pairs listed."""
    for i in range(lists.first.shape[0] - 1):
        for k in range(listed(lists.first, i)):
            p, j = lists.first[i] + k, lists.upper[i, k]
            height = 0.5 * (lists.x_at_build[i] + lists.x_at_build[j]).dot(up)
            band = ti.cast(ti.floor(height * inv_band), ti.i32)
            band = ti.max(-BAND_LIMIT, ti.min(BAND_LIMIT - 1, band))
            tables.owner[p] = i
            tables.colour[p] = UNCOLOURED
            tables.key[p] = (band << KEY_BITS) | index_hash(p)
    return lists.first[lists.first.shape[0] - 1]


@kernel
def colour_rounds(
    rounds: ti.template(), climb: ti.i32, up: ti.math.vec3, lists: NeighbourLists, tables: ColourTables
) -> ti.i32:
    """``rounds`` rounds of the colouring (see the module's docstring); returns how many pairs are
    still uncoloured. With ``climb``, a pair's colour is looked for from the colour after those
    of the pairs that hold its lower ball from below (cyclically), so that a column's pairs take
    rising colours and the sweeps' support climbs it in one sweep."""
    n = lists.first.shape[0] - 1
    bits = slot_bits(lists.upper.shape[1])
    for _ in ti.static(range(rounds)):
        for i in range(n):  # each ball: the colours of its pairs, and its first uncoloured pair
            taken, top, top_key, held = 0, -1, 0, 0
            yi = lists.x_at_build[i].dot(up)
            for m in range(listed(lists.first, i) + lists.lower_first[i + 1] - lists.lower_first[i]):
                q, other = lists.first[i] + m, 0
                if m >= listed(lists.first, i):
                    o, k = owner_slot(lists.lower[lists.lower_first[i] + m - listed(lists.first, i)], bits)
                    q, other = lists.first[o] + k, o
                else:
                    other = lists.upper[i, m]
                c = tables.colour[q]
                if c == UNCOLOURED:
                    if first_of(tables.key, q, top, top_key):
                        top, top_key = q, tables.key[q]
                elif c < COLOURS:
                    taken |= 1 << c
                    if lists.x_at_build[other].dot(up) < yi:  # a pair that holds ball i from below
                        held = ti.max(held, c + 1)
            tables.mask[i], tables.best[i], tables.level[i] = taken, top, held
        for p in range(lists.first[n]):  # each pair first at both its balls: the lowest colour free at both
            if tables.colour[p] == UNCOLOURED:
                i = tables.owner[p]
                j = lists.upper[i, p - lists.first[i]]
                if tables.best[i] == p and tables.best[j] == p:
                    taken = tables.mask[i] | tables.mask[j]
                    below = i
                    if lists.x_at_build[j].dot(up) < lists.x_at_build[i].dot(up):
                        below = j
                    c0 = 0
                    if climb != 0:
                        c0 = tables.level[below] % COLOURS
                    c, tried = c0, 0
                    while tried < COLOURS and (taken >> c) & 1 != 0:
                        c = (c + 1) % COLOURS
                        tried += 1
                    if tried == COLOURS:
                        c = OVERFLOW
                    tables.colour[p] = c
    left = 0
    for p in range(lists.first[n]):
        if tables.colour[p] == UNCOLOURED:
            left += 1  # (an integer sum: the same on every thread order)
    return left


@kernel
def colour_sort(listed_pairs: ti.i32, tables: ColourTables):
    """Lay the ``listed_pairs`` pairs out colour by colour: ``tables.pairs[start[c] : start[c + 1]]`` are
    the pairs of colour c (in the order their threads took places: the pairs of a colour share no
    ball, so the order among them changes nothing), the overflow set last, sorted by index (it is
    swept in that order)."""
    for c in range(COLOURS + 2):
        tables.start[c] = 0
    for c in range(COLOURS + 1):
        tables.fill[c] = 0
    for p in range(listed_pairs):
        ti.atomic_add(tables.start[tables.colour[p] + 1], 1)
    ti.loop_config(serialize=True)
    for c in range(COLOURS + 1):
        tables.start[c + 1] += tables.start[c]
    for p in range(listed_pairs):
        c = tables.colour[p]
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
        if phase != BOUNCE or scratch.impact[i] != 0:
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
            if phase == FIRST and hit != 0:
                scratch.impact[i] = 1


@kernel
def surface_sweep(
    phase: ti.i32,
    scalars: float_array,
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
):
    """Each ball's planes and terrain in a sweep of ``phase`` (:func:`.surfaces.surface_impulses`),
    a thread per ball, before the sweep's pairs; the first sweep also clears the marks of the
    restitution pass, which its pairs then set (:func:`colour_pair`)."""
    _, contact, terrain, params = scalars_of(scalars)
    for i in range(state.x.shape[0]):
        if phase == FIRST:
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
def pair_sweep(
    phase: ti.i32,
    c0: ti.i32,
    serial: ti.template(),
    project: ti.template(),
    scalars: float_array,
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
    tables: ColourTables,
):
    """The pairs of colours ``c0`` to ``c0 + COLOURS_PER_LAUNCH − 1`` in a sweep of ``phase``, a
    parallel loop per colour, a thread per pair (:func:`colour_pair`), or with ``project`` in a
    pass of the position projection (:func:`project_colour_pair`); with ``serial``, the overflow
    set instead, one pair after another (``c0`` unused)."""
    _, contact, _terrain, params = scalars_of(scalars)
    if ti.static(serial):
        ti.loop_config(serialize=True)
        for s in range(tables.start[OVERFLOW], tables.start[OVERFLOW + 1]):
            pair_pass(tables.pairs[s], phase, project, contact, params, model, lists, state, scratch, tables)
    else:
        for c in ti.static(range(COLOURS_PER_LAUNCH)):
            for s in range(tables.start[c0 + c], tables.start[c0 + c + 1]):
                pair_pass(tables.pairs[s], phase, project, contact, params, model, lists, state, scratch, tables)


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
    p, k_p, model: ti.template(), lists: ti.template(), state: ti.template(), scratch: ti.template(), tables: ti.template()
):
    """Pair p's position projection (:func:`.colour.project_pair`), as :func:`.colour.project_ball`
    makes it for the pairs its ball owns."""
    i = tables.owner[p]
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
        inv_mi = 0.0
        if state.status[i] != AT_REST:
            inv_mi = 1.0 / of_ball(model.mass, i)
        j = lists.upper[i, p - lists.first[i]]
        scratch.x_free[i] = project_pair(j, scratch.x_free[i], of_ball(model.radius, i), inv_mi, k_p, model, state, scratch)


@kernel
def project_surfaces(scalars: float_array, model: ModelArrays, state: BallState, scratch: StepScratch):
    """Each ball awake moved out of the planes it overlaps (:func:`.colour.project_planes`), after a
    projection pass's pairs, a thread per ball."""
    _, contact, _terrain, _params = scalars_of(scalars)
    for i in range(state.x.shape[0]):
        if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET and state.status[i] != AT_REST:
            scratch.x_free[i] = project_planes(scratch.x_free[i], of_ball(model.radius, i), contact.k_p, model)


@dataclass
class ContactColours:
    """The pairs' colours of a collision solver's lists, on the device.

    Attributes:
        band: height [m] of the priority's bands (pairs of a lower band are coloured first).
        colours: colours in use at the last build (the highest colour of a pair, plus one).
        overflow: pairs in the overflow set at the last build.
        sizes: pairs of each colour in use at the last build (for the benchmarks).
        rounds: colouring rounds the last build took.
    """

    band: float
    climb: bool = True
    colours: int = 0
    overflow: int = 0
    sizes: tuple[int, ...] = ()
    rounds: int = 0
    tables: Any = None
    _room: int = 0
    _n: int = 0
    _start: Any = None

    def build(self, lists: Any, n: int, pairs_room: int, gravity: Any) -> None:
        """Colour the pairs of the neighbour lists ``lists`` (a ``NeighbourLists`` pack of ``n``
        balls whose pair tables hold ``pairs_room`` entries) with "up" against ``gravity``."""
        t = self.tables
        if t is None or self._room < pairs_room or self._n != n:
            self._room, self._n = max(pairs_room, 1), n
            pair_arrays = {name: ti.ndarray(ti.i32, self._room) for name in ("owner", "colour", "key", "pairs")}
            t = self.tables = ColourTables(
                **pair_arrays,
                start=ti.ndarray(ti.i32, COLOURS + 2),
                fill=ti.ndarray(ti.i32, COLOURS + 1),
                mask=ti.ndarray(ti.i32, n),
                best=ti.ndarray(ti.i32, n),
                level=ti.ndarray(ti.i32, n),
            )
            self._start = t["start"]
        g = np.asarray(gravity, dtype=float)
        up = -g / np.linalg.norm(g) if np.linalg.norm(g) > 0.0 else np.zeros(3)
        with plain_compile():
            up_vec = ti.math.vec3(*up)
            pairs = colour_init(up_vec, 1.0 / self.band if self.band > 0.0 else 0.0, lists, t)
            left, self.rounds = pairs, 0
            while left > 0:
                left = colour_rounds(ROUNDS_PER_LAUNCH, int(self.climb), up_vec, lists, t)
                self.rounds += ROUNDS_PER_LAUNCH
            colour_sort(pairs, t)
        start = self._start.to_numpy()
        sizes = np.diff(start)
        used = np.nonzero(sizes[:COLOURS])[0]
        self.colours = int(used[-1]) + 1 if used.size else 0
        self.overflow = int(sizes[OVERFLOW])
        self.sizes = tuple(int(s) for s in sizes[: self.colours])

    def launches(self, n: int, iterations: int) -> list[int]:
        """The work items (balls or pairs, each a thread that no other shares) of each parallel loop
        of a step's sweeps and projections with these colours (:func:`gauss_seidel_step`), in
        order; the overflow set's serial loop counts one item."""
        padded = -(-self.colours // COLOURS_PER_LAUNCH) * COLOURS_PER_LAUNCH
        sizes = list(self.sizes) + [0] * (padded - self.colours)
        serial = [1] if self.overflow else []
        sweep = [n] + sizes + serial
        project = sizes + serial + [n]
        return sweep * len(step_phases(iterations)) + project * PROJECTIONS


def gauss_seidel_step(
    colours: ContactColours, iterations: int, scalars: Any, model: Any, lists: Any, state: Any, scratch: Any
) -> None:
    """A step's Gauss–Seidel sweeps (``iterations`` of them and the restitution pass,
    :func:`.colour.step_phases`) laid out by contact colours, from the warm start to the end of the
    sweeps: each sweep the balls' planes and terrain (:func:`surface_sweep`), then the colours
    ``COLOURS_PER_LAUNCH`` a launch (:func:`pair_sweep`), then the overflow set. The caller
    finishes the step (``collide.collision_step``) and then calls :func:`project`."""
    t = colours.tables
    with plain_compile():  # see runtime.plain_compile
        for phase in step_phases(iterations):
            surface_sweep(phase, scalars, model, lists, state, scratch)
            for c0 in range(0, colours.colours, COLOURS_PER_LAUNCH):
                pair_sweep(phase, c0, False, False, scalars, model, lists, state, scratch, t)
            if colours.overflow:
                pair_sweep(phase, 0, True, False, scalars, model, lists, state, scratch, t)


def project(colours: ContactColours, scalars: Any, model: Any, lists: Any, state: Any, scratch: Any) -> None:
    """The ``PROJECTIONS`` passes of the position projection at the end of a step, laid out as the
    sweeps are: the colours, the overflow set, then each ball's planes."""
    t = colours.tables
    with plain_compile():
        for _ in range(PROJECTIONS):
            for c0 in range(0, colours.colours, COLOURS_PER_LAUNCH):
                pair_sweep(FIRST, c0, False, True, scalars, model, lists, state, scratch, t)
            if colours.overflow:
                pair_sweep(FIRST, 0, True, True, scalars, model, lists, state, scratch, t)
            project_surfaces(scalars, model, state, scratch)
