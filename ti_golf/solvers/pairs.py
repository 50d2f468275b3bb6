"""Ball pairs in a collision step: their impulses from the owner's side, gathered by each ball.

A pair (a, b) is owned by one ball, a (see :func:`ti_golf.solvers.grid.owns`); the owner
evaluates the pair's impulse P once per sweep (:func:`owned_pairs`), −P acting on b, and each
ball then sums the impulses of its pairs in id order (:func:`gather`): no float atomics, and
momentum is conserved to round-off. Resting impulses carry from step to step (:func:`warm_start`),
and a ball takes one impact per sweep (:func:`impact_keys`, :func:`matched`).
"""

import taichi as ti

from ti_golf.physics.contact import (
    PRESSED,
    TOUCHING_GAP,
    clamp_friction,
    pair_impulse,
)
from ti_golf.physics.types import (
    GAP,
    GAP_LOW,
    INV,
    P_X,
    P_Y,
    P_Z,
    is_f64,
    of_ball,
    zero3,
)
from ti_golf.scene.schema import AT_REST, OUT_OF_BOUNDS
from ti_golf.solvers.links import listed, owner_slot
from ti_golf.solvers.stale import in_play

QUIET = -1.0  # the calm time of a quiet ball (see warm_start): below any rest timer


@ti.func
def pair_geometry(x: ti.template(), radius: ti.template(), a, b):
    """(1/|x_a − x_b| [1/m], zero when the centres of balls a and b coincide, and their surface
    gap [m]); :func:`pair_normal` turns the first into the unit normal."""
    dist = (x[a] - x[b]).norm()
    inv = 0.0
    if dist > 0.0:
        inv = 1.0 / dist
    return inv, dist - of_ball(radius, a) - of_ball(radius, b)


@ti.func
def pair_normal(x_a, x_b, inv):
    """Unit normal from ball b at ``x_b`` to ball a at ``x_a`` [m] (zero when their centres
    coincide), from their inverse distance ``inv`` (:func:`pair_geometry`). The sweeps keep
    ``inv`` rather than the normal (one float a pair rather than three) and recompute the normal
    from the start-of-step positions, which do not change during them: bit for bit the normal
    that the warm start used."""
    return (x_a - x_b) * inv


@ti.func
def kept_normal(x_a, x_b, inv32):
    """:func:`pair_normal` from the inverse distance as the Gauss–Seidel sweeps keep it, in f32
    (``inv32``, see ``types.pair_table_type``; never marked negative, as the Jacobi sweeps mark
    an impact: :func:`impact_mark`): in f64 refined by a Newton step
    of 1/√(d·d), y(3 − d·d y²)/2, whose relative error is 3/2 of the square of the f32 value's
    (at most 2^-24), so 2^-47 (a normal 1 ± 10^-14 long). The warm start and every sweep refine
    the same f32 value on the same start-of-step positions: the same normal, bit for bit."""
    d = x_a - x_b
    y = ti.cast(inv32, float)
    if ti.static(is_f64()):
        y = y * (1.5 - 0.5 * d.norm_sqr() * y * y)
    return d * y


@ti.func
def put_gap(J: ti.template(), p, gap):
    """Write the surface gap ``gap`` [m] of the pair in row p of the Gauss–Seidel sweeps' f32 table
    (see ``types.pair_table_type``): in f64 its 64 bits, the high half in ``GAP`` and the low in
    ``GAP_LOW`` (never read as numbers), so that the sweeps close a gap to the last bit as they
    would from the positions (rounded to f32, the gaps left balls of a settled pile waking one
    another for seconds); in f32 into ``GAP``."""
    if ti.static(is_f64()):
        bits = ti.bit_cast(gap, ti.i64)
        J[p, GAP] = ti.bit_cast(ti.cast(bits >> 32, ti.i32), ti.f32)
        J[p, GAP_LOW] = ti.bit_cast(ti.cast(bits, ti.i32), ti.f32)  # (the cast keeps the low 32 bits)
    else:
        J[p, GAP] = gap


@ti.func
def kept_gap(J: ti.template(), p):
    """The surface gap [m] of the pair in row p of the Gauss–Seidel sweeps' table (:func:`put_gap`)."""
    gap = 0.0
    if ti.static(is_f64()):
        high = ti.cast(ti.bit_cast(J[p, GAP], ti.i32), ti.i64)
        low = ti.cast(ti.cast(ti.bit_cast(J[p, GAP_LOW], ti.i32), ti.u32), ti.i64)
        gap = ti.bit_cast((high << 32) | low, ti.f64)
    else:
        gap = J[p, GAP]
    return gap


@ti.func
def skip_pair(status: ti.template(), i, j):
    """Whether the pair (i, j) gets no impulse: a ball is out of bounds, or both are at rest."""
    return status[i] == OUT_OF_BOUNDS or status[j] == OUT_OF_BOUNDS or (status[i] == AT_REST and status[j] == AT_REST)


@ti.func
def owned_pairs(i, final: ti.template(), h, v_inelastic, s: ti.template()):
    """One Jacobi sweep over the pairs that ball i owns (``s``: the step's :class:`.step.Step`;
    the arrays below are its lists', state's and scratch's), with its neighbours j = upper[i, k]: the
    impulse P on i (−P acts on j) from the current velocities (which updates the resting impulse
    ``lam``), stored in the pair's row p = first[i] + k of J (columns ``P_X`` to ``P_Z``). The
    inverse distance [1/m] (``INV``), which gives the unit normal n̂ from j to i
    (:func:`pair_normal`), and the surface gap [m] (``GAP``) were stored there by
    :func:`warm_start` (positions do not change during the sweeps).
    An impact (see :func:`ti_golf.physics.contact.pair_impulse`) is marked by the inverse distance's sign, negative
    (:func:`impact_mark`; and ``flag[1]`` is set, so that :func:`impact_keys` looks for the balls'
    first impacts; :func:`gather` takes one impact per ball, see :func:`matched`).

    With ``final`` (the last sweep) the gap's place, J[p, GAP], takes, for an overlapping pair,
    q = k_p·overlap/(1/m_i + 1/m_j) ≥ 0, the pair's position projection (B.18: ball i moves by
    q/m_i along n̂, which is k_p·m_red·Δx, and j by q/m_j the other way); for a pair apart,
    −gap ≤ 0 (the surface gap [m]: the balls touch while it is below 1 % of a radius)."""
    contact, x, radius, mass, status = ti.static((s.contact, s.state.x, s.model.radius, s.model.mass, s.state.status))
    upper, first, lam, J, v, w, flag = ti.static(
        (s.lists.upper, s.lists.first, s.lists.lam, s.scratch.J, s.state.v, s.state.w, s.scratch.flag)
    )
    inv_mi, xi, p0 = 1.0 / of_ball(mass, i), x[i], first[i]
    for k in range(listed(first, i)):
        j, p = upper[i, k], p0 + k
        inv = ti.abs(J[p, INV])  # (the mark of an impact in the last sweep, see impact_mark)
        n, gap = pair_normal(xi, x[j], inv), J[p, GAP]
        ok = n.norm_sqr() > 0.0
        inv_mj = 1.0 / of_ball(mass, j)
        P = zero3()
        kick = 0
        if status[i] == OUT_OF_BOUNDS or status[j] == OUT_OF_BOUNDS:
            lam[p] = ti.f32(0.0)  # a frozen ball no longer supports anything (no warm start from it)
        elif ok and not skip_pair(status, i, j):  # (Jacobi only: the Gauss–Seidel step's end reads the gaps alone)
            P, lam_p, _, kick = pair_impulse(
                n,
                gap,
                v[i],
                w[i],
                of_ball(radius, i),
                inv_mi,
                v[j],
                w[j],
                r_b=of_ball(radius, j),
                inv_m_b=inv_mj,
                lam=ti.cast(lam[p], float),
                e=contact.e,
                mu=contact.mu,
                v_inelastic=v_inelastic,
                h=h,
                relax=contact.relax,
            )
            lam[p] = ti.cast(lam_p, ti.f32)
            if kick != 0:
                flag[1] = 1  # every thread that writes, writes 1
        g = gap
        if ti.static(final):
            g = -gap
            if gap < 0.0:
                g = 0.0
                if ok:
                    g = -contact.k_p * gap / (inv_mi + inv_mj)
        if kick != 0:
            inv = -inv
        J[p, INV], J[p, GAP], J[p, P_X], J[p, P_Y], J[p, P_Z] = inv, g, P[0], P[1], P[2]


@ti.func
def impulse_of(J: ti.template(), p):
    """The impulse P [N·s] on the owner of the pair in row p of the Jacobi sweeps' table."""
    return ti.Vector([J[p, P_X], J[p, P_Y], J[p, P_Z]])


@ti.func
def impact_mark(J: ti.template(), p):
    """Whether the pair in row p of the sweep's table (:func:`owned_pairs`) met as an impact in the
    sweep: its stored inverse distance is then negative. The sign is the mark, so that no table
    of marks is kept (the inverse distance is positive for every pair that gets an impact: the
    centres of the pair's balls are apart)."""
    return J[p, INV] < 0.0


@ti.func
def quiet_ball(
    i,
    status: ti.template(),
    upper: ti.template(),
    first: ti.template(),
    lower: ti.template(),
    lower_first: ti.template(),
    bits,
):
    """Whether ball i is *quiet*: at rest, and every listed neighbour at rest or out of bounds
    (see :func:`warm_start`)."""
    quiet = status[i] == AT_REST
    if quiet:
        for m in range(lower_first[i], lower_first[i + 1]):
            if in_play(status[owner_slot(lower[m], bits)[0]]) != 0:
                quiet = False
                break  # (an early exit: also keeps LLVM from vectorising a loop of a few pairs)
    if quiet:
        for k in range(listed(first, i)):
            if in_play(status[upper[i, k]]) != 0:
                quiet = False
                break
    return quiet


@ti.func
def still_quiet(i, s: ti.template()):
    """Whether ball i is quiet (:func:`quiet_ball`) because it was at the last step's warm start
    and no neighbour has woken since (``s``: the step's :class:`.step.Step`): with the
    Gauss–Seidel sweeps (``s.kinds.gauss_seidel``) and ``t_rest`` > 0 its quiet calm time
    (``scratch.calm[i]``, ``QUIET``) then still holds. In those sweeps a ball asleep stands firm,
    takes no impulse and keeps its status and rest timer (> 0 at rest, as ``t_rest`` > 0), so the
    neighbours of a quiet ball stay at rest or out of bounds and none moved (:func:`moved`): it
    is not woken, and stays quiet unless a neighbour of it wakes in the step's first loop, which
    then takes its quiet calm time back (:func:`stir_neighbours`). The calm times are forgotten
    (``Stepping.forget_quiet``) whenever the lists are built or the balls' statuses edited
    between steps. So a pile asleep is not asked of its neighbours at every step."""
    quiet = False
    if ti.static(s.kinds.gauss_seidel):
        if s.scratch.calm[i] == QUIET:  # (nested: Taichi evaluates both sides of an `and`)
            if s.state.status[i] == AT_REST:
                quiet = s.params.t_rest > 0.0
    return quiet


@ti.func
def stir_neighbours(i, bits, lists: ti.template(), calm: ti.template()):
    """Take back the quiet calm time (``calm``, see :func:`still_quiet`) of every listed neighbour
    of ball i, which has just woken: each is then asked of its neighbours again
    (:func:`quiet_ball`). Several threads may write a neighbour's entry, all the same value."""
    for m in range(lists.lower_first[i], lists.lower_first[i + 1]):
        calm[owner_slot(lists.lower[m], bits)[0]] = 0.0
    for k in range(listed(lists.first, i)):
        calm[lists.upper[i, k]] = 0.0


@ti.func
def warm_start(i, bits, hop, s: ti.template()):
    """Δv [m/s] and Δω [rad/s] of ball i (``s``: the step's :class:`.step.Step`; the arrays below
    are its model's, lists', state's and scratch's; μ its contact's; ``bits``: see
    :func:`.links.slot_bits`) from last step's resting impulses λ of its ball pairs, each
    along the pair's normal at the start of the step, summed in id order (lower then upper). A
    normal impulse gives no spin; friction is left to the sweeps, but with the Gauss–Seidel sweeps
    (``s.kinds.gauss_seidel``), where each pair's friction impulse F from the last step is applied too,
    in the pair's tangent plane and at most μ·λ (:func:`ti_golf.physics.contact.clamp_friction`: the same on both
    balls, bit for bit). Also stores the geometry of the pairs
    ball i owns for the sweeps in their rows first[i] + k of J: 1/|x_i − x_j| (``INV``, positive:
    no impact, see :func:`impact_mark`), the surface gap [m] (``GAP``) and, in a table with the
    Jacobi sweeps' columns, no impulse yet; with the Gauss–Seidel sweeps in f32, their pairs'
    normals then those of :func:`kept_normal`. Reads only
    what the free-flight loop does not write (start-of-step positions, status, λ, rest timers),
    so it runs inside that loop. Returns (Δv [m/s], Δω [rad/s], the calm time [s] of ball i: the least of its rest
    timer and the rest timers of the balls it touches, each plus ``hop`` [s] (:func:`island_calm`),
    see :func:`finish`; or ``QUIET`` for a ball at rest
    whose listed neighbours are all at rest or out of bounds: nothing can touch it this step, so
    the step leaves it exactly as it is and the sweeps skip it)."""
    x, radius, mass, status, rest_time = ti.static(
        (s.state.x, s.model.radius, s.model.mass, s.state.status, s.state.rest_time)
    )
    upper, first, lower, lower_first = ti.static((s.lists.upper, s.lists.first, s.lists.lower, s.lists.lower_first))
    lam, J, friction, mu = ti.static((s.lists.lam, s.scratch.J, s.lists.friction, s.contact.mu))
    P, T = zero3(), zero3()
    calm, xi = rest_time[i], x[i]
    quiet = quiet_ball(i, status, upper, first, lower, lower_first, bits)
    if not quiet:  # (a quiet ball's impulses and calm time would not be used: see the caller)
        for m in range(lower_first[i], lower_first[i + 1]):
            slot = lower[m]
            j, k = owner_slot(slot, bits)  # the pair's owner j keeps its λ
            p = first[j] + k
            inv, gap = pair_geometry(x, radius, i, j)
            n = zero3()
            if ti.static(s.kinds.gauss_seidel):  # (the normal of the owner's row, see below, turned)
                n = kept_normal(xi, x[j], ti.cast(inv, ti.f32))
            else:
                n = pair_normal(xi, x[j], inv)
            P += resting_impulse(status, i, j, n, lam[p])
            if ti.static(s.kinds.gauss_seidel):
                F = carried_friction(status, i, j, n, lam[p], friction[p], mu)
                P -= F
                T += n.cross(F)
            calm = island_calm(calm, gap, of_ball(radius, i), status[j], rest_time[j], hop, s.params)
    p0 = first[i]
    for k in range(listed(first, i)):  # (a quiet ball's too: the gaps of its neighbours' lower pairs)
        j, p = upper[i, k], p0 + k
        inv, gap = pair_geometry(x, radius, i, j)
        n = zero3()
        if ti.static(s.kinds.gauss_seidel):  # the f32 table: the normal its sweeps will see
            J[p, INV] = ti.cast(inv, ti.f32)
            put_gap(J, p, gap)
            n = kept_normal(xi, x[j], J[p, INV])
        else:  # the Jacobi sweeps' table, in the float type (a quiet ball's pairs keep no impulse: they skip them)
            J[p, INV], J[p, GAP], J[p, P_X], J[p, P_Y], J[p, P_Z] = inv, gap, 0.0, 0.0, 0.0
            n = pair_normal(xi, x[j], inv)
        if not quiet:
            P += resting_impulse(status, i, j, n, lam[p])
            if ti.static(s.kinds.gauss_seidel):
                F = carried_friction(status, i, j, n, lam[p], friction[p], mu)
                P += F
                T -= n.cross(F)
            calm = island_calm(calm, gap, of_ball(radius, i), status[j], rest_time[j], hop, s.params)
    if quiet:
        calm = QUIET
    m = of_ball(mass, i)
    return P / m, T * (2.5 / (m * of_ball(radius, i))), calm


@ti.func
def carried_friction(status: ti.template(), i, j, n, lam, F, mu):
    """The friction impulse [N·s] that a pair (i, j) with normal ``n`` and resting impulse ``lam``
    carries into the step, from its stored impulse ``F`` (f32) on the pair's owner; zero when the
    pair gets no impulse."""
    F_t = zero3()
    if lam > 0.0 and not skip_pair(status, i, j):
        F_t = clamp_friction(ti.cast(F, float), n, mu * lam)
    return F_t


@ti.func
def island_calm(calm, gap, r, status_j, rest_time_j, hop, params: ti.template()):
    """The calm time [s] so far, lowered to the rest timer of a neighbour that touches the ball
    (surface gap below 1 % of its radius ``r``) and is not out of bounds, plus ``hop`` [s]
    (``params``: the step's ``t_rest`` and ``h``).

    With ``hop`` 0 a calm group falls asleep as a whole (an island: every ball of it calm for
    ``t_rest``). With ``hop`` = t_rest / ``colour.REGION_HOPS`` (the Gauss–Seidel sweeps) a ball
    falls asleep once every ball within ``REGION_HOPS`` contacts of it is calm, each for as much
    longer as it is nearer: a ball moving somewhere in a pile of 100,000 keeps only its region
    awake. There a ball also waits for each ball it touches that will not reach ``t_rest`` in this
    step (rest timer + h below it): its calm time is then at most t_rest − 1.5·h, so it stays awake,
    and ends the step with a timer half a step short of ``t_rest``, which its other neighbours read
    as ready and do not wait for. So two touching balls fall asleep in the same step. A ball whose
    supports fell asleep ``hop`` before it would have them stand firm under it while it still
    creeps, roll off them and wake them, over and over (with ``hop`` 0 its timer holds it already)."""
    if gap < TOUCHING_GAP * r and status_j != OUT_OF_BOUNDS:
        calm = ti.min(calm, rest_time_j + hop)
        if hop > 0.0 and rest_time_j + params.h < params.t_rest:
            calm = ti.min(calm, ti.max(params.t_rest - 1.5 * params.h, 0.0))
    return calm


@ti.func
def touched_by_moving(i, status: ti.template(), rest_time: ti.template(), lists: ti.template(), bits):
    """Whether a listed neighbour of ball i moved faster than ``v_rest`` in the last step or flew
    (its rest timer is 0) and is not out of bounds: a ball asleep among the Gauss–Seidel sweeps
    wakes then (the first loop of ``collide.start_step``). Reads only rest timers and the
    out-of-bounds status, which waking does not change."""
    moving = False
    for m in range(lists.lower_first[i], lists.lower_first[i + 1]):
        if moved(status, rest_time, owner_slot(lists.lower[m], bits)[0]):
            moving = True
            break  # (an early exit: also keeps LLVM from vectorising a loop of a few pairs)
    if not moving:
        for k in range(listed(lists.first, i)):
            if moved(status, rest_time, lists.upper[i, k]):
                moving = True
                break
    return moving


@ti.func
def moved(status: ti.template(), rest_time: ti.template(), j):
    """Whether ball j moved faster than ``v_rest`` in the last step or flew (its rest timer is 0)
    and is not out of bounds."""
    return rest_time[j] == 0.0 and status[j] != OUT_OF_BOUNDS


@ti.func
def resting_impulse(status: ti.template(), i, j, n, lam):
    """λ·n̂ [N·s] on ball i from its pair with j (n̂ from j to i), or zero when the pair gets no impulse."""
    P = zero3()
    if lam > 0.0 and not skip_pair(status, i, j):
        P = lam * n
    return P


@ti.func
def impact_keys(i, bits, lists: ti.template(), scratch: ti.template()):
    """Keep in ``scratch.impact[i]`` the greatest key of ball i's impacts in this sweep (0 when it has
    none): the key of a pair is its slot, owner·2^bits + column (as in the
    lower lists, see :func:`.links.owner_slot`), plus one. Gathered from the pairs' marks
    (:func:`impact_mark`), as the impulses are: no atomics."""
    first, lower, lower_first = ti.static((lists.first, lists.lower, lists.lower_first))
    J, impact = ti.static((scratch.J, scratch.impact))
    key = 0
    for m in range(lower_first[i], lower_first[i + 1]):
        slot = lower[m]
        j, k = owner_slot(slot, bits)
        if impact_mark(J, first[j] + k):
            key = ti.max(key, slot + 1)
    for k in range(listed(first, i)):
        if impact_mark(J, first[i] + k):
            key = ti.max(key, (i << bits) + k + 1)
    impact[i] = key


@ti.func
def matched(impact: ti.template(), a, b, key):
    """Whether the impact of balls a and b with ``key`` (see :func:`impact_keys`) is taken in this
    sweep: it is the first of both balls' impacts in the sweep's order, the greatest key.

    A Jacobi sweep evaluates every pair from the same velocities, so a ball that meets several
    balls at once would take each impact's whole jolt, as if the others were not there: a ball at
    v into two touching balls at ±30° with e = 1 would leave at −v/2 and send both off at
    0.87 v, 75 % more kinetic energy than it brought. So each sweep takes, for every ball, at most
    one of its impacts, a binary collision by B.9 that keeps kinetic energy with e = 1 and loses
    some with e < 1; the others are evaluated again in the next sweep, from the velocities that
    collision left (the next step's sweeps when this was the last). The impacts are taken one
    after another in a fixed order, as if the balls had met a moment apart."""
    return impact[a] == key and impact[b] == key


@ti.func
def contact_state(g, r, inv_m_i, mass: ti.template(), j, k_p, pressed):
    """0, 1 or ``PRESSED`` (see :func:`gather`) for the pair of ball i (radius ``r``, 1/m_i
    ``inv_m_i``) with ball j whose last-sweep J[·, GAP] is ``g`` (the projection q ≥ 0 of an
    overlap, or minus the gap: see :func:`owned_pairs`): pressed when they overlap by more than
    ``pressed`` of ``r``. Ball j's mass is read only for an overlap (this runs for every pair of
    the step's last sweep)."""
    state = 0
    if g > -TOUCHING_GAP * r:
        state = 1
        if g > 0.0:
            if g * (inv_m_i + 1.0 / of_ball(mass, j)) > pressed * r * k_p:
                state = PRESSED
    return state


@ti.func
def touching_by_gaps(i, r, bits, k_p, pressed, lists: ti.template(), scratch: ti.template()):
    """Whether ball i (radius ``r`` [m]) touches a ball, as :func:`gather` tells it with ``final``
    (0, 1 or ``PRESSED``), from the surface gaps [m] its pairs keep in J[·, GAP] through the
    Gauss–Seidel sweeps (:func:`warm_start` stores them; the sweeps apply their impulses at once
    and leave nothing else in J): touching below 1 % of ``r``, pressed when overlapping by more
    than ``pressed`` of ``r`` (with a projection, ``k_p`` > 0, as :func:`contact_state`)."""
    first, lower, lower_first, J = ti.static((lists.first, lists.lower, lists.lower_first, scratch.J))
    touching = 0
    for m in range(lower_first[i], lower_first[i + 1]):
        j, k = owner_slot(lower[m], bits)
        touching = ti.max(touching, gap_state(kept_gap(J, first[j] + k), r, k_p, pressed))
        if touching == PRESSED:
            break  # (the most it can be: an early exit, which also keeps LLVM from vectorising the loop)
    if touching != PRESSED:
        for k in range(listed(first, i)):
            touching = ti.max(touching, gap_state(kept_gap(J, first[i] + k), r, k_p, pressed))
            if touching == PRESSED:
                break
    return touching


@ti.func
def gap_state(gap, r, k_p, pressed):
    """:func:`contact_state` of a pair from its surface gap [m] (see :func:`touching_by_gaps`)."""
    state = 0
    if gap < TOUCHING_GAP * r:
        state = 1
        if k_p > 0.0 and -gap > pressed * r:
            state = PRESSED
    return state


@ti.func
def gather(i, final: ti.template(), bits, k_p, pressed, s: ti.template()):
    """What ball i gets from all its pairs (``s``: the step's :class:`.step.Step`), summed in id order
    (lower then upper): (Δv [m/s], Δω [rad/s], and with ``final`` the position projection Δx [m]
    and whether it touches a ball: 0 when no gap is below 1 % of its radius, ``PRESSED`` when
    some ball overlaps it by more than that (the overlap is q·(1/m_i + 1/m_j)/k_p, q the pair's
    projection in J), else 1).

    An impulse ±P at the contact point −r·n̂ᵢ of a solid sphere (n̂ᵢ = ±n̂ from the other ball to
    i) gives Δv = ±P/m and Δω = (−r n̂ᵢ) × (±P)·5/(2 m r²) = −(5/(2 m r))·(n̂ × P) for both balls
    of the pair (n̂ᵢ and the sign of P flip together). Of a ball's impacts, only the one
    :func:`matched` in this sweep acts (``any_impact``: whether the sweep has any, ``flag[1]``)."""
    x, radius, mass = ti.static((s.state.x, s.model.radius, s.model.mass))
    upper, first, lower, lower_first = ti.static((s.lists.upper, s.lists.first, s.lists.lower, s.lists.lower_first))
    J, impact = ti.static((s.scratch.J, s.scratch.impact))
    any_impact = s.scratch.flag[1]
    P, T, q_n = zero3(), zero3(), zero3()
    touching = 0
    r = of_ball(radius, i)
    inv_m, xi = 1.0 / of_ball(mass, i), x[i]
    for m in range(lower_first[i], lower_first[i + 1]):
        slot = lower[m]
        j, k = owner_slot(slot, bits)  # the pair's owner j stores it
        p = first[j] + k
        P_k, n_k = impulse_of(J, p), pair_normal(x[j], xi, ti.abs(J[p, INV]))
        if any_impact != 0:  # (the marks are read only in a sweep that has impacts)
            if impact_mark(J, p) and not matched(impact, i, j, slot + 1):
                P_k = zero3()
        P -= P_k
        T += n_k.cross(P_k)
        if ti.static(final):
            q_n -= ti.max(J[p, GAP], 0.0) * n_k
            touching = ti.max(touching, contact_state(J[p, GAP], r, inv_m, mass, j, k_p, pressed))
    for k in range(listed(first, i)):
        p = first[i] + k
        P_k, n_k = impulse_of(J, p), pair_normal(xi, x[upper[i, k]], ti.abs(J[p, INV]))
        if any_impact != 0:
            if impact_mark(J, p) and not matched(impact, i, upper[i, k], (i << bits) + k + 1):
                P_k = zero3()
        P += P_k
        T += n_k.cross(P_k)
        if ti.static(final):
            q_n += ti.max(J[p, GAP], 0.0) * n_k
            touching = ti.max(touching, contact_state(J[p, GAP], r, inv_m, mass, upper[i, k], k_p, pressed))
    return P * inv_m, T * (-2.5 * inv_m / r), q_n * inv_m, touching
