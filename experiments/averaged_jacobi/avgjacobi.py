"""Prototype (measurement only): Jacobi sweeps with constraint averaging and over-relaxation
(FleX, Macklin et al. 2014) in place of the contacts layout's coloured Gauss-Seidel sweeps.

Each sweep: a pair loop (a thread per pair) computes the pair's update from the velocities of the
sweep before, the increment of its accumulated impulses scaled by OMEGA / max(n_i, n_j) (n: the
ball's pairs that press, counted once a step), and stores each ball's velocity and spin change;
then a ball loop (a thread per ball) gathers them (owned pairs, then lower) and meets its
surfaces. The projection likewise. Installed by monkeypatching contact_colour's step functions,
so it runs wherever contact.layout = "contacts" runs (the colouring is still made at each build,
unused). Knobs (environment): AJ_OMEGA (over-relaxation of the SOLVE and SHOCK sweeps; the FIRST
sweep and the restitution pass take 1), AJ_EXTRA (sweeps beyond contact.iterations), AJ_PROJ
(projection passes), AJ_POMEGA (their over-relaxation), AJ_PSHOCK / AJ_PCOS (the projection's
lower ball of a stacked pair standing firm), AJ_MSCALE (FleX's mass scaling: in the SOLVE sweeps
the lower ball of a stacked pair gets this share of its inverse mass), AJ_GSPROJ=1 (the colours'
projection after these sweeps). Measured with AJ_OMEGA=1.5 AJ_POMEGA=1.5 AJ_EXTRA=4 AJ_PROJ=6:
see this commit's message.

    python experiments/averaged_jacobi/run.py bench pit --n 2250 --set contact.layout=contacts
    python experiments/averaged_jacobi/check.py contacts|contacts_lively|column
"""

import os

import taichi as ti

from ti_golf.physics.contact import inverse_inertia, kinetic_change, pivot_impulse, spin_jolt
from ti_golf.physics.types import (
    INV,
    BallState,
    ModelArrays,
    NeighbourLists,
    StepScratch,
    float_array,
    kernel,
    of_ball,
    scalars_of,
    zero3,
)
from ti_golf.scene.schema import AT_REST, OUT_OF_BOUNDS
from ti_golf.solvers import contact_colour
from ti_golf.solvers.colour import PROJECTIONS, step_phases
from ti_golf.solvers.links import listed, owner_slot
from ti_golf.solvers.pairs import QUIET, kept_gap, kept_normal, skip_pair
from ti_golf.solvers.phases import Phase
from ti_golf.solvers.sequential import body, inelastic_speed, pair_step, shock_masses, stands_firm, sweep_constants, upward
from ti_golf.solvers.step import Step
from ti_golf.solvers.surfaces import surface_impulses
from ti_golf.solvers.sequential import project_planes

OMEGA = float(os.environ.get("AJ_OMEGA", "1.0"))
PROJ_OMEGA = float(os.environ.get("AJ_POMEGA", "1.0"))
EXTRA = int(os.environ.get("AJ_EXTRA", "0"))  # extra SOLVE sweeps beyond contact.iterations
PSHOCK = os.environ.get("AJ_PSHOCK", "0") == "1"
PSHOCK_COS = float(os.environ.get("AJ_PCOS", "0.5"))
MSCALE = float(os.environ.get("AJ_MSCALE", "1.0"))
PROJ_PASSES = int(os.environ.get("AJ_PROJ", str(PROJECTIONS)))

_buf = {}


def buffers(pairs, n):
    key = (pairs, n)
    if _buf.get("key") != key:
        _buf["key"] = key
        _buf["d"] = ti.Vector.ndarray(12, float, max(pairs, 1))  # dv_a, dw_a, dv_b, dw_b
        _buf["cnt"] = ti.ndarray(ti.i32, n)
    return _buf["d"], _buf["cnt"]


@kernel
def count_pressed(lists: NeighbourLists, scratch: StepScratch, cnt: ti.types.ndarray(), bits: ti.i32):
    """n_i: ball i's pairs with an accumulated impulse or a gap closed (at least 1)."""
    for i in range(cnt.shape[0]):
        c = 0
        for m in range(lists.lower_first[i], lists.lower_first[i + 1]):
            j, k = owner_slot(lists.lower[m], bits)
            p = lists.first[j] + k
            if lists.lam[p] > 0 or kept_gap(scratch.J, p) <= 0.0:
                c += 1
        for k in range(listed(lists.first, i)):
            p = lists.first[i] + k
            if lists.lam[p] > 0 or kept_gap(scratch.J, p) <= 0.0:
                c += 1
        cnt[i] = ti.max(c, 1)


@kernel
def jacobi_pass(
    phase: ti.i32,
    omega: float,
    bits: ti.i32,
    kinds: ti.template(),
    scalars: float_array,
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
    owner: ti.types.ndarray(),
    d: ti.types.ndarray(),
    cnt: ti.types.ndarray(),
):
    _, contact, terrain, params = scalars_of(scalars)
    s = ti.static(Step(contact, terrain, params, model, lists, state, scratch, kinds=kinds))
    n_balls = state.x.shape[0]
    if phase == Phase.FIRST:
        for i in range(n_balls):
            scratch.impact[i] = 0
    for p in range(lists.first[n_balls]):
        d[p] = ti.Vector([0.0] * 12, dt=float)
        i = owner[p]
        if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
            if phase != Phase.BOUNCE or scratch.impact[i] != 0:
                j = lists.upper[i, p - lists.first[i]]
                if state.status[j] == OUT_OF_BOUNDS:
                    lists.lam[p] = ti.f32(0.0)
                elif not skip_pair(state.status, i, j):
                    n = kept_normal(state.x[i], state.x[j], scratch.J[p, INV])
                    if n.norm_sqr() > 0.0:
                        d[p] = pair_update(i, j, p, phase, n, omega / ti.max(cnt[i], cnt[j]), s)
    for i in range(n_balls):
        if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
            vi, wi = state.v[i], state.w[i]
            for k in range(listed(lists.first, i)):
                dk = d[lists.first[i] + k]
                vi += ti.Vector([dk[0], dk[1], dk[2]])
                wi += ti.Vector([dk[3], dk[4], dk[5]])
            for m in range(lists.lower_first[i], lists.lower_first[i + 1]):
                j, k = owner_slot(lists.lower[m], bits)
                dk = d[lists.first[j] + k]
                vi += ti.Vector([dk[6], dk[7], dk[8]])
                wi += ti.Vector([dk[9], dk[10], dk[11]])
            if not stands_firm(s.kinds, state.status[i]):
                vi, wi = surface_impulses(
                    i, warm=False, vi=vi, wi=wi, h=params.h, v_inelastic=inelastic_speed(contact, params), s=s, phase=phase
                )
            state.v[i], state.w[i] = vi, wi


@ti.func
def pair_update(i, j, p, phase, n, scale, s: ti.template()):
    contact, model, lists, state, scratch = ti.static((s.contact, s.model, s.lists, s.state, s.scratch))
    k = sweep_constants(contact, s.params)
    ri, inv_mi = of_ball(model.radius, i), 1.0 / of_ball(model.mass, i)
    if stands_firm(s.kinds, state.status[i]):
        inv_mi = 0.0
    rj, inv_mj = of_ball(model.radius, j), 1.0 / of_ball(model.mass, j)
    if stands_firm(s.kinds, state.status[j]):
        inv_mj = 0.0
    vi, wi, vj, wj = state.v[i], state.w[i], state.v[j], state.w[j]
    out = ti.Vector([0.0] * 12, dt=float)
    F = ti.cast(lists.friction[p], float)
    lam = ti.cast(lists.lam[p], float)
    inv_a, inv_b = shock_masses(phase, n, k.up, inv_mi, inv_mj)
    if ti.static(MSCALE < 1.0):
        if phase == Phase.SOLVE:
            up_n = n.dot(k.up)
            if up_n > 0.5:
                inv_b *= MSCALE
            elif up_n < -0.5:
                inv_a *= MSCALE
    if inv_a + inv_b > 0.0:
        v_n0 = 0.0
        if phase == Phase.FIRST or phase == Phase.BOUNCE:
            v_n0 = (scratch.v_free[i] - scratch.v_free[j]).dot(n)
            if phase == Phase.FIRST and v_n0 < -k.v_inelastic:
                scratch.impact[i] = 1
        shocked = inv_a + inv_b != inv_mi + inv_mj
        P, lam_new, F_new = zero3(), lam, F
        gap = kept_gap(scratch.J, p)
        for attempt in range(2):
            P, lam_new, F_new = pair_step(
                phase, n, gap, v_n0,
                body(vi, wi, ri, inv_a / scale), body(vj, wj, rj, inv_b / scale),
                lam, F, e=contact.e, mu=contact.mu, v_inelastic=k.v_inelastic, h=k.h,
            )
            if attempt == 1 or not shocked or P.norm_sqr() == 0.0:
                break
            if kinetic_change(vi, wi, ri, inv_a, P, n) + kinetic_change(vj, wj, rj, inv_b, -P, -n) <= 0.0:
                break
            inv_a, inv_b = inv_mi, inv_mj
        lists.lam[p] = ti.cast(lam_new, ti.f32)
        lists.friction[p] = ti.cast(F_new, ti.f32)
        dva, dwa = P * inv_a, spin_jolt(P, n, ri, inv_a)
        dvb, dwb = zero3(), zero3()
        if scratch.calm[j] != QUIET:
            dvb, dwb = -P * inv_b, spin_jolt(-P, -n, rj, inv_b)
        if phase == Phase.SHOCK and lam_new > 0.0:
            inv_Ia, inv_Ib = inverse_inertia(ri, inv_mi), inverse_inertia(rj, inv_mj)
            if scratch.calm[j] == QUIET:
                inv_Ib = 0.0
            L = pivot_impulse(((wi + dwa) - (wj + dwb)).dot(n), inv_Ia / scale, inv_Ib / scale,
                              contact.mu_roll * lam_new * ti.min(ri, rj))
            dwa += L * inv_Ia * n
            dwb -= L * inv_Ib * n
        out = ti.Vector([dva[0], dva[1], dva[2], dwa[0], dwa[1], dwa[2], dvb[0], dvb[1], dvb[2], dwb[0], dwb[1], dwb[2]])
    return out


@kernel
def jacobi_project(
    omega: float,
    bits: ti.i32,
    scalars: float_array,
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
    owner: ti.types.ndarray(),
    d: ti.types.ndarray(),
    cnt: ti.types.ndarray(),
):
    _, contact, terrain, params = scalars_of(scalars)
    n_balls = state.x.shape[0]
    for p in range(lists.first[n_balls]):
        d[p] = ti.Vector([0.0] * 12, dt=float)
        i = owner[p]
        if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
            j = lists.upper[i, p - lists.first[i]]
            if state.status[j] != OUT_OF_BOUNDS:
                inv_mi, inv_mj = 0.0, 0.0
                if state.status[i] != AT_REST:
                    inv_mi = 1.0 / of_ball(model.mass, i)
                if state.status[j] != AT_REST and scratch.calm[j] != QUIET:
                    inv_mj = 1.0 / of_ball(model.mass, j)
                dd = scratch.x_free[i] - scratch.x_free[j]
                dist = dd.norm()
                overlap = of_ball(model.radius, i) + of_ball(model.radius, j) - dist
                if ti.static(PSHOCK) and dist > 0.0:
                    up_n = (dd / dist).dot(upward(params))
                    if up_n > PSHOCK_COS and inv_mi > 0.0:
                        inv_mj = 0.0
                    elif up_n < -PSHOCK_COS and inv_mj > 0.0:
                        inv_mi = 0.0
                if overlap > 0.0 and dist > 0.0 and inv_mi + inv_mj > 0.0:
                    scale = omega / ti.max(cnt[i], cnt[j])
                    q = (scale * contact.k_p * overlap / (inv_mi + inv_mj)) * (dd / dist)
                    a, b = q * inv_mi, -q * inv_mj
                    d[p] = ti.Vector([a[0], a[1], a[2], 0.0, 0.0, 0.0, b[0], b[1], b[2], 0.0, 0.0, 0.0])
    for i in range(n_balls):
        if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
            xi = scratch.x_free[i]
            for k in range(listed(lists.first, i)):
                dk = d[lists.first[i] + k]
                xi += ti.Vector([dk[0], dk[1], dk[2]])
            for m in range(lists.lower_first[i], lists.lower_first[i + 1]):
                j, k = owner_slot(lists.lower[m], bits)
                dk = d[lists.first[j] + k]
                xi += ti.Vector([dk[6], dk[7], dk[8]])
            if state.status[i] != AT_REST:
                xi = project_planes(xi, of_ball(model.radius, i), contact.k_p, model)
            scratch.x_free[i] = xi


def _setup(colours, arguments):
    scalars, _, _, _, kinds, model, lists, state, _, scratch = arguments
    pairs = colours.tables.owner.shape[0]
    d, cnt = buffers(pairs, state.x.shape[0])
    width, bits = lists.upper.shape[1], 0
    while (1 << bits) < width:
        bits += 1
    return d, cnt, bits


def gauss_seidel_step(colours, iterations, arguments):
    scalars, _, _, _, kinds, model, lists, state, _, scratch = arguments
    d, cnt, bits = _setup(colours, arguments)
    count_pressed(lists, scratch, cnt, bits)
    phases = step_phases(iterations + EXTRA)
    for phase in phases:
        omega = OMEGA if phase in (Phase.SOLVE, Phase.SHOCK) else 1.0
        jacobi_pass(phase, omega, bits, kinds, scalars, model, lists, state, scratch, colours.tables.owner, d, cnt)


def project(colours, arguments):
    scalars, _, _, _, kinds, model, lists, state, _, scratch = arguments
    d, cnt, bits = _setup(colours, arguments)
    for _ in range(PROJ_PASSES):
        jacobi_project(PROJ_OMEGA, bits, scalars, model, lists, state, scratch, colours.tables.owner, d, cnt)


def install():
    if os.environ.get("AJ_GSSWEEP", "0") != "1":
        contact_colour.gauss_seidel_step = gauss_seidel_step
    if os.environ.get("AJ_GSPROJ", "0") != "1":
        contact_colour.project = project
