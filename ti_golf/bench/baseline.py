"""Yardstick kernels for the benchmarks, measured in the same run as the step they compare with:
what the memory system allows, and what the report's pair impulse costs at the least."""

from ti_golf.physics.contact import pair_impulse
from ti_golf.physics.types import (
    ContactParams,
    float_array,
    int_array,
    int_table,
    kernel,
    of_ball,
    vec3,
    vec3_array,
    zero3,
)
from ti_golf.solvers.links import listed, owner_slot, slot_bits
from ti_golf.solvers.pairs import pair_geometry, pair_normal


@kernel
def bare_gather(x: vec3_array, nbr: int_table, out: vec3_array):
    """out[i] = Σ_k (x[i] − x[nbr[i, k]]): a contact gather with no physics (memory traffic only)."""
    for i in range(x.shape[0]):
        acc = zero3()
        for k in range(nbr.shape[1]):
            acc += x[i] - x[nbr[i, k]]
        out[i] = acc


@kernel
def one_pass_contacts(
    contact: ContactParams,
    gravity: vec3,
    h: float,
    x: vec3_array,
    v: vec3_array,
    w: vec3_array,
    radius: float_array,
    mass: float_array,
    upper: int_table,
    first: int_array,
    lower: int_array,
    lower_first: int_array,
    dv: vec3_array,
    dw: vec3_array,
):
    """The least one step of the collision model can cost: a single pass over the balls in which
    every ball meets each of its listed neighbours (both its lists, as ``pairs.gather`` reads
    them) through the report's pair impulse (:func:`.contact.pair_impulse`, B.5–B.18: normal
    jolt, resting impulse, Coulomb friction with both spins) from the start-of-step velocities
    after gravity, and keeps the sum: dv[i] [m/s] and dw[i] [rad/s]. A pair is evaluated twice,
    once from each ball, and nothing is stored per pair; no air, planes, warm start, position
    projection, rest detection or list rebuild. Both balls of a pair see the same normal and
    relative velocity with the roles swapped, so they receive opposite impulses: Σ m·dv = 0 to
    round-off (the test of this yardstick). Not a step of the model (one Jacobi sweep, no
    resting impulses kept): the floor under the real step's cost, in the same run."""
    bits = slot_bits(upper.shape[1])
    v_inelastic = contact.v_bounce + 2.0 * gravity.norm() * h
    for i in range(x.shape[0]):
        r_i, inv_m_i, xi = of_ball(radius, i), 1.0 / of_ball(mass, i), x[i]
        vi = v[i] + h * gravity
        P, T = zero3(), zero3()
        n_low = lower_first[i + 1] - lower_first[i]
        for q in range(n_low + listed(first, i)):
            j = 0
            if q < n_low:
                j = owner_slot(lower[lower_first[i] + q], bits)[0]
            else:
                j = upper[i, q - n_low]
            inv, gap = pair_geometry(x, radius, i, j)
            n = pair_normal(xi, x[j], inv)
            P_q, _, _, _ = pair_impulse(
                n,
                gap,
                vi,
                w[i],
                r_i,
                inv_m_i,
                v[j] + h * gravity,
                w[j],
                of_ball(radius, j),
                1.0 / of_ball(mass, j),
                0.0,
                contact.e,
                contact.mu,
                v_inelastic,
                h,
                contact.relax,
            )
            P += P_q
            T += n.cross(P_q)
        dv[i] = P * inv_m_i
        dw[i] = T * (-2.5 * inv_m_i / r_i)
