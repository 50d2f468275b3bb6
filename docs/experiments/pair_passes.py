"""What one pass over a pile's pairs costs at the least, one pair at a time and 8 at a time.

A measurement behind docs/performance.md ("What a pass over the pairs costs"), not part of the
package. It reads a saved pour (``ti-golf run scenes/ball_pit.toml --t 0.8 --out pit08.npz``)
and times, on its listed pairs, the Gauss–Seidel pair update of the sweeps
(``contact.pair_step`` in its ``SOLVE`` phase: normal impulse toward closing the gap, Coulomb
friction with both spins, the clamps) in four loops, each stripped of the solver's bookkeeping
(status, sleeping, carried friction, planes):

- ``independent``: every pair on its own from the balls' velocities, the result kept per pair
  (as a Jacobi sweep computes them), one pair at a time;
- ``independent_lanes``: the same, 8 pairs at a time in lane vectors (``LANES``);
- ``chained``: ball after ball, each ball's velocity and spin carried from one of its pairs to the
  next and the other ball's changed at once (as a Gauss–Seidel sweep does), one ball at a time;
- ``chained_lanes``: the same, 8 balls at a time in lane vectors, each lane's other balls gathered
  and written back one lane at a time.

The chained loops race on the other balls' writes (both threads write them): they are timed, not
checked. The independent loops give the same impulses to round-off, which the script checks.

    python docs/experiments/pair_passes.py pit08.npz [--lanes 8] [--repeats 10]
"""

import argparse
import time

import numpy as np
import taichi as ti

from ti_golf import runtime

R, MASS, H, MU, E = 0.021335, 0.04593, 1e-3, 0.3, 0.5
"""A golf ball's radius [m] and mass [kg], the pit's step [s], friction and restitution."""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("saved", help="a run saved by `ti-golf run ... --out`")
    ap.add_argument("--lanes", type=int, default=8)
    ap.add_argument("--repeats", type=int, default=10)
    args = ap.parse_args()
    runtime.init("cpu", "f64")
    from ti_golf.physics.contact import SOLVE, pair_step, spin_jolt
    from ti_golf.physics.types import zero3
    from ti_golf.sim.saved_run import read_run
    from ti_golf.sim.simulation import Simulation

    sim = read_run(Simulation, args.saved)
    sim.run(steps=1)  # (builds the lists)
    solver = sim.solver
    first, upper = solver.first.to_numpy(), solver.upper.to_numpy()
    n, pairs = len(first) - 1, int(first[-1])
    counts = np.diff(first)
    owner = np.repeat(np.arange(n), counts).astype(np.int32)
    other = upper[np.arange(upper.shape[1])[None, :] < counts[:, None]].astype(np.int32)
    x, v, w = (a.to_numpy() for a in (sim.state.x, sim.state.v, sim.state.w))
    lam0 = solver.lam.to_numpy()[:pairs].astype(np.float64)

    def array(values, dtype):
        a = ti.ndarray(dtype, values.shape[:1] if dtype == ti.math.vec3 else values.shape)  # (vec3: one per row)
        a.from_numpy(values)
        return a

    X, V, W = array(x, ti.math.vec3), array(v, ti.math.vec3), array(w, ti.math.vec3)
    FIRST, UPPER = array(first.astype(np.int32), ti.i32), array(upper.astype(np.int32), ti.i32)
    OWNER, OTHER, LAM = array(owner, ti.i32), array(other, ti.i32), array(lam0, float)
    OUT_P, OUT_W = ti.ndarray(ti.math.vec3, pairs), ti.ndarray(ti.math.vec3, pairs)
    vec3s = ti.types.ndarray(dtype=ti.math.vec3, ndim=1)
    ints, floats = ti.types.ndarray(dtype=ti.i32, ndim=1), ti.types.ndarray(dtype=float, ndim=1)
    table = ti.types.ndarray(dtype=ti.i32, ndim=2)
    L = args.lanes
    lane = ti.types.vector(L, float)
    inv_m, inv_I = 1.0 / MASS, 2.5 / (MASS * R * R)

    @ti.func
    def lane_update(xa, va, wa, xb, vb, wb, lam, on):
        """pair_step(SOLVE) for L pairs at once: (P, Δω_a, λ) per lane, lanes with ``on`` 0 idle.
        Vectors are 3-lists of lane vectors."""
        d = [xa[k] - xb[k] for k in ti.static(range(3))]
        dist = ti.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        inv_d = 1.0 / dist
        nv = [d[k] * inv_d for k in ti.static(range(3))]
        gap = dist - 2.0 * R
        m_eff = 1.0 / (2.0 * inv_m)
        rv = [va[k] - vb[k] for k in ti.static(range(3))]
        v_n = rv[0] * nv[0] + rv[1] * nv[1] + rv[2] * nv[2]
        lam_new = ti.max(lam + m_eff * (-ti.max(gap, 0.0) / H - v_n), 0.0) * on
        j_n = lam_new - lam * on
        ra = [-R * nv[k] for k in ti.static(range(3))]
        ca = [wa[(k + 1) % 3] * ra[(k + 2) % 3] - wa[(k + 2) % 3] * ra[(k + 1) % 3] for k in ti.static(range(3))]
        cb = [wb[(k + 1) % 3] * (-ra[(k + 2) % 3]) - wb[(k + 2) % 3] * (-ra[(k + 1) % 3]) for k in ti.static(range(3))]
        slip = [rv[k] + ca[k] - cb[k] for k in ti.static(range(3))]
        s_n = slip[0] * nv[0] + slip[1] * nv[1] + slip[2] * nv[2]
        t = [slip[k] - s_n * nv[k] for k in ti.static(range(3))]
        s = ti.sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2])
        bound = MU * lam_new
        scale = ti.select(s > 1e-12, -ti.min(bound, s * m_eff * (2.0 / 7.0)) / ti.max(s, 1e-300), 0.0)
        scale = ti.select(lam_new > 0.0, scale, 0.0)
        f = [scale * t[k] for k in ti.static(range(3))]
        f_n = f[0] * nv[0] + f[1] * nv[1] + f[2] * nv[2]
        ft = [f[k] - f_n * nv[k] for k in ti.static(range(3))]
        size = ti.sqrt(ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2])
        clamp = ti.select(size > bound, bound / ti.max(size, 1e-300), 1.0)
        P = [j_n * nv[k] + ft[k] * clamp for k in ti.static(range(3))]
        dw = [
            (ra[(k + 1) % 3] * P[(k + 2) % 3] - ra[(k + 2) % 3] * P[(k + 1) % 3]) * inv_I for k in ti.static(range(3))
        ]
        return P, dw, lam_new

    @ti.func
    def solve(n, gap, va, wa, vb, wb, lam):
        """The sweeps' pair update (P on a, λ) of a pair carrying no friction yet."""
        P, lam_new, _ = pair_step(SOLVE, n, gap, 0.0, va, wa, R, inv_m, vb, wb, R, inv_m, lam, zero3(), E, MU, 0.5, H)
        return P, lam_new

    @ti.func
    def lanes3():
        return [lane(0.0) for _ in ti.static(range(3))]

    @ti.kernel
    def independent(x: vec3s, v: vec3s, w: vec3s, a: ints, b: ints, lam: floats, out_p: vec3s, out_w: vec3s):
        for p in range(a.shape[0]):
            i, j = a[p], b[p]
            d = x[i] - x[j]
            dist = d.norm()
            n = d / dist
            P, _ = solve(n, dist - 2 * R, v[i], w[i], v[j], w[j], lam[p])
            out_p[p] = P
            out_w[p] = spin_jolt(P, n, R, inv_m)

    @ti.kernel
    def independent_lanes(x: vec3s, v: vec3s, w: vec3s, a: ints, b: ints, lam: floats, out_p: vec3s, out_w: vec3s):
        for q in range(a.shape[0] // L):
            xa, va, wa = lanes3(), lanes3(), lanes3()
            xb, vb, wb = lanes3(), lanes3(), lanes3()
            lam_q = lane(0.0)
            for k in ti.static(range(L)):
                p = q * L + k
                i, j = a[p], b[p]
                for c in ti.static(range(3)):
                    xa[c][k], va[c][k], wa[c][k] = x[i][c], v[i][c], w[i][c]
                    xb[c][k], vb[c][k], wb[c][k] = x[j][c], v[j][c], w[j][c]
                lam_q[k] = lam[p]
            P, dw, _ = lane_update(xa, va, wa, xb, vb, wb, lam_q, lane(1.0))
            for k in ti.static(range(L)):
                out_p[q * L + k] = ti.Vector([P[0][k], P[1][k], P[2][k]])
                out_w[q * L + k] = ti.Vector([dw[0][k], dw[1][k], dw[2][k]])

    @ti.kernel
    def chained(x: vec3s, v: vec3s, w: vec3s, first: ints, upper: table, lam: floats):
        for i in range(x.shape[0]):
            vi, wi, xi = v[i], w[i], x[i]
            for k in range(first[i + 1] - first[i]):
                j, p = upper[i, k], first[i] + k
                d = xi - x[j]
                dist = d.norm()
                n = d / dist
                P, lam_new = solve(n, dist - 2 * R, vi, wi, v[j], w[j], lam[p])
                lam[p] = lam_new
                vi += P * inv_m
                wi += spin_jolt(P, n, R, inv_m)
                v[j] -= P * inv_m
                w[j] += spin_jolt(-P, -n, R, inv_m)
            v[i], w[i] = vi, wi

    @ti.kernel
    def chained_lanes(x: vec3s, v: vec3s, w: vec3s, first: ints, upper: table, lam: floats):
        for q in range(x.shape[0] // L):
            xa, va, wa = lanes3(), lanes3(), lanes3()
            most = 0
            for k in ti.static(range(L)):
                i = q * L + k
                for c in ti.static(range(3)):
                    xa[c][k], va[c][k], wa[c][k] = x[i][c], v[i][c], w[i][c]
                most = ti.max(most, first[i + 1] - first[i])
            for m in range(most):
                xb, vb, wb = lanes3(), lanes3(), lanes3()
                lam_q, on = lane(0.0), lane(0.0)
                for k in ti.static(range(L)):
                    i = q * L + k
                    xb[0][k] = xa[0][k] + 1.0  # (an idle lane: a ball a metre away)
                    if m < first[i + 1] - first[i]:
                        j = upper[i, m]
                        on[k] = 1.0
                        for c in ti.static(range(3)):
                            xb[c][k], vb[c][k], wb[c][k] = x[j][c], v[j][c], w[j][c]
                        lam_q[k] = lam[first[i] + m]
                P, dw, lam_new = lane_update(xa, va, wa, xb, vb, wb, lam_q, on)
                for c in ti.static(range(3)):
                    va[c] += P[c] * inv_m
                    wa[c] += dw[c]
                for k in ti.static(range(L)):
                    i = q * L + k
                    if m < first[i + 1] - first[i]:
                        j = upper[i, m]
                        lam[first[i] + m] = lam_new[k]
                        v[j] -= ti.Vector([P[0][k], P[1][k], P[2][k]]) * inv_m
                        w[j] += ti.Vector([dw[0][k], dw[1][k], dw[2][k]])
            for k in ti.static(range(L)):
                i = q * L + k
                v[i] = ti.Vector([va[0][k], va[1][k], va[2][k]])
                w[i] = ti.Vector([wa[0][k], wa[1][k], wa[2][k]])

    loops = {
        "independent": lambda: independent(X, V, W, OWNER, OTHER, LAM, OUT_P, OUT_W),
        "independent_lanes": lambda: independent_lanes(X, V, W, OWNER, OTHER, LAM, OUT_P, OUT_W),
        "chained": lambda: chained(X, V, W, FIRST, UPPER, LAM),
        "chained_lanes": lambda: chained_lanes(X, V, W, FIRST, UPPER, LAM),
    }
    impulses = {}
    for name, run in loops.items():  # compile, and keep what the independent loops give
        V.from_numpy(v), W.from_numpy(w), LAM.from_numpy(lam0)
        run()
        ti.sync()
        impulses[name] = OUT_P.to_numpy()
    a, b = impulses["independent"], impulses["independent_lanes"]
    whole = pairs // L * L
    print(
        f"{n:,} balls, {pairs:,} listed pairs; the independent loops' impulses agree to "
        f"{np.abs(a[:whole] - b[:whole]).max() / np.abs(a).max():.1e} of the largest"
    )
    best = {}
    for _ in range(3):
        for name, run in loops.items():
            seconds = []
            for _ in range(args.repeats):
                V.from_numpy(v), W.from_numpy(w), LAM.from_numpy(lam0)
                ti.sync()
                t0 = time.perf_counter()
                run()
                ti.sync()
                seconds.append(time.perf_counter() - t0)
            best[name] = min(best.get(name, np.inf), float(np.median(seconds)))
    for name, s in best.items():
        print(f"{name:18s} {s * 1e3:7.2f} ms a pass, {s / pairs * 1e9:6.1f} ns a pair")


if __name__ == "__main__":
    main()
