"""Ball–ball collisions (report Appendix B): neighbour search, closed-form two-ball results,
conservation laws, Newton's cradle, stacking and determinism."""

from __future__ import annotations

import dataclasses
import textwrap
from collections.abc import Callable
from pathlib import Path

import background
import numpy as np
import pytest
from conftest import NO_VULKAN_BACKEND, ON_CPU, ON_VULKAN, SERIAL_OR_PARALLEL

import ti_golf as tg
from ti_golf.bench.collide import pile_scene
from ti_golf.bench.pit import pit_scene
from ti_golf.scene.schema import AT_REST, Plane
from ti_golf.solvers import CollisionSolver, apart, grid, links, sort, stale, stepping
from ti_golf.solvers.pairs import QUIET
from ti_golf.solvers.stepping import RELIST_MAX_BALLS

# no gravity, air, walls or friction unless a test says otherwise
FREE = [
    "world.ground=false",
    "air.rho=0",
    "world.gravity=[0,0,0]",
    "world.integrator=semi_implicit",
    "world.dt=0.0005",
    "contact.mu=0",
    "world.v_rest=0",
]


F32 = 2.0 * float(np.finfo(np.float32).eps)
"""Two f32 roundings, relative: the solver keeps each surface contact's impulses in f32."""


def scene(*overrides: str) -> tg.Scene:
    return tg.load_scene("lab_vacuum", [*FREE, *overrides])


# ---------------------------------------------------------------------------------------------
# Neighbour search
# ---------------------------------------------------------------------------------------------
def _brute_force_pairs(x, r, skin, v=None, h=0.0):
    # listed: surface gap below the skin, or below h·|v_a − v_b| when larger (grid.pair_reach: a
    # pair that can close its gap within the step after a build must be listed by it)
    d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=-1)
    reach = np.full(d.shape, skin)
    if v is not None:
        reach = np.maximum(skin, h * np.linalg.norm(v[:, None, :] - v[None, :, :], axis=-1))
    close = d < r[:, None] + r[None, :] + reach
    np.fill_diagonal(close, False)
    return {(i, j) for i, j in zip(*np.nonzero(close))}


def _random_sets():
    rng = np.random.default_rng(3)
    n = 1500
    mixed = rng.uniform(0.01, 0.05, n)
    clustered = np.concatenate([rng.normal(c, 0.08, (n // 3, 3)) for c in ([0, 0, 0], [5, 1, -2], [-3, 0, 4])])
    sparse = rng.uniform(-3, 3, (n, 3))
    far = np.concatenate([rng.uniform(-0.5, 0.5, (n // 2, 3)), rng.uniform(-0.5, 0.5, (n // 2, 3)) + 1e4])
    negative = rng.uniform(-0.6, 0.6, (n, 3)) - 1234.5  # cells with negative coordinates
    # balls of one size, closer than a diameter on average: many pairs lie just within reach, in
    # every direction, some in the cells diagonal to a ball's own
    dense = rng.uniform(0.0, 0.25, (n, 3))
    return {
        "dense": (dense, np.full(n, 0.02)),
        "clustered": (clustered, mixed[: len(clustered)]),
        "sparse": (sparse, mixed),
        "far_apart": (far, np.full(len(far), 0.03)),
        "negative": (negative, mixed),
    }


def _velocities(n, fast):
    """Resting balls, or (``fast``) balls at up to 1 m/s with one in twenty at up to 40 m/s: 20 mm
    per 0.5 ms step, ten times the skin of 2-cm balls; or (``few_fast``) balls at up to 1 m/s with
    six at 150 to 3,000 m/s, moving 1.5 to 30 of the largest diameters in two steps
    (apart.APART_MAX); or (``few_big``) balls at up to 1 m/s."""
    if not fast:
        return np.zeros((n, 3))
    rng = np.random.default_rng(5)
    v = rng.uniform(-1.0, 1.0, (n, 3))
    if fast == "few_big":
        return v
    if fast == "few_fast":
        few = rng.choice(n, 6, replace=False)
        u = rng.normal(size=(6, 3))
        v[few] = u / np.linalg.norm(u, axis=1)[:, None] * np.array([150, 300, 600, 1000, 2000, 3000])[:, None]
    else:
        v[rng.random(n) < 0.05] *= 40.0
    return v


@pytest.mark.parametrize("fast", [False, True, "few_fast", "few_big"], ids=["at_rest", "fast", "few_fast", "few_big"])
@pytest.mark.parametrize("name", ["clustered", "sparse", "far_apart", "negative", "dense"])
def test_grid_neighbours_equal_brute_force(name, fast):
    x, r = _random_sets()[name]
    if fast == "few_big":  # five boulders, 3 to 67 times the radius of the rest
        r = r.copy()
        r[np.random.default_rng(6).choice(len(r), 5, replace=False)] = [0.15, 0.3, 0.6, 1.0, 2.0]
    v = _velocities(len(x), fast)
    sim = tg.Simulation(scene(), x=x, v=v, radius=r, mass=0.045 * (r / 0.02) ** 3)
    solver: CollisionSolver = sim.solver
    solver.build(sim.state)
    # a few balls more than twice the size of all but the 32 biggest (apart.APART_MAX), or faster
    # than a diameter of the rest (or the skin) in two steps, are set apart: they own none of their
    # pairs with the others (see _owns), and on CPU backends they are listed apart (each tests
    # every ball), so that the cells and the skin are as small as the others need: the rest's
    # largest radius r_ref sets the skin, and the cells are at most 2·r_ref + max(skin, 2·r_ref).
    # With many fast balls (one in twenty), or none, or on a GPU, the cells are sized for the
    # fastest pair and the largest ball
    r_desc = np.sort(r)[::-1]
    r_cut = 2 * r_desc[apart.APART_MAX] if r_desc[0] > 2 * r_desc[apart.APART_MAX] else np.inf
    r_ref = r[r <= r_cut].max()
    assert solver.skin == pytest.approx(sim.scene.contact.skin * r_ref, rel=1e-12)
    fast_balls = 2 * sim.dt * np.linalg.norm(v, axis=1) > max(solver.skin, 2 * r_ref)
    set_apart = fast_balls | (r > r_cut)  # they own no pair with the others, on every backend
    if np.sum(set_apart) > apart.APART_MAX:
        set_apart[:] = False
    assert solver.n_apart == np.sum(set_apart)
    if fast in ("few_fast", "few_big") and ON_CPU:
        assert solver.n_apart == {"few_fast": 6, "few_big": 5}[fast]
        assert solver.cell <= 2 * r_ref + max(solver.skin, 2 * r_ref)
        if fast == "few_big":
            assert solver.cell < 0.25 * (2 * r.max())  # not sized for the boulders
    pairs = solver.pairs()
    assert np.all(pairs[:, 0] < pairs[:, 1])  # each pair reported once, by id
    found = {(int(i), int(j)) for i, j in pairs} | {(int(j), int(i)) for i, j in pairs}
    expected = _brute_force_pairs(x, r, solver.skin, v, sim.dt)
    assert found == expected
    assert len(expected) > 0
    if fast in (True, "few_fast") and name != "sparse":
        # the closing speeds list pairs the skin alone would not (the sparse set's balls are too
        # far apart for that: there the lists must just miss nothing)
        assert len(expected) > len(_brute_force_pairs(x, r, solver.skin))
    xs = sim.state.x.to_numpy()  # the positions the kernels saw (float type of the run)
    upper, n_upper = solver.upper.to_numpy(), _n_upper(solver)
    lower, lower_first = solver.lower.to_numpy(), solver.lower_first.to_numpy()
    assert upper.shape[1] <= 1 << solver.slot_bits
    within = [set() for _ in range(len(x))]  # each ball's expected neighbours
    for a, j in expected:
        within[a].add(j)
    for i in range(len(x)):  # lists are sorted by id: sums over them do not depend on threads
        assert np.all(np.diff(upper[i, : n_upper[i]]) > 0)
        assert set(upper[i, : n_upper[i]].tolist()) == {j for j in within[i] if _owns(xs, i, j, set_apart)}
        slots = lower[lower_first[i] : lower_first[i + 1]]  # where each lower pair is stored: owner · 2^bits + column
        owners, entries = slots >> solver.slot_bits, slots & ((1 << solver.slot_bits) - 1)
        assert np.all(np.diff(owners) > 0)
        assert set(owners.tolist()) == {j for j in within[i] if _owns(xs, j, i, set_apart)}
        assert np.all(upper[owners, entries] == i)


def test_a_pair_just_within_reach_across_a_cells_edge_or_corner_is_listed():
    # a ball looks for its neighbours in its own cell and the 26 around it (grid.list_ball): a pair
    # 0.995 of a cell apart (a cell is as wide as a pair reaches, grid.cell_size) straddling a
    # cell's face, edge or corner, each ball a hair from it on its side, must be listed. For each
    # of the 26 directions o a pair lies around its own point P, on a boundary along each axis
    # that o crosses and mid-cell along the others
    sc = scene()
    r, d = 0.02, 0.995
    probe = tg.Simulation(sc, x=np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), radius=np.full(2, r))
    probe.solver = CollisionSolver(probe.model, serial=False)
    probe.solver.build(probe.state)
    cell = probe.solver.cell
    x = []
    for k, o in enumerate(o for o in np.ndindex(3, 3, 3) if o != (1, 1, 1)):
        o = np.array(o) - 1
        u = o / np.linalg.norm(o)
        p = np.array([4 * k + (0.0 if o[0] else 0.5), 0.0 if o[1] else 0.5, 0.0 if o[2] else 0.5]) * cell
        x += [p - (d - 1e-6) * cell * u, p + 1e-6 * cell * u]  # |x_j − x_i| = 0.995 cells
    x = np.array(x)
    sim = tg.Simulation(sc, x=x, radius=np.full(len(x), r))
    sim.solver = solver = CollisionSolver(sim.model, serial=False)
    solver.build(sim.state)
    assert solver.cell == cell
    found = {(int(i), int(j)) for i, j in solver.pairs()}
    assert found == {(2 * k, 2 * k + 1) for k in range(26)}


def _n_upper(solver: CollisionSolver) -> np.ndarray:
    """The length of each ball's upper list (in storage order)."""
    return np.diff(solver.first.to_numpy())


def _owns(x, i, j, apart):
    """Whether ball i owns its pair with j (grid.owns): j is listed apart and i is not (``apart``:
    bool (n,); so a boulder's hundreds of pairs do not widen the upper table, which keeps each
    pair's impulse), or neither or both are and j lies ahead along the axis of their largest
    separation (the first of equals), or, at the same point, has the higher id."""
    if apart[i] != apart[j]:
        return bool(apart[j])
    d = x[j] - x[i]
    ahead = d[np.argmax(np.abs(d))]
    return bool(ahead > 0 or (ahead == 0 and j > i))


def test_a_ball_that_moved_past_half_the_skin_is_seen_wherever_it_is():
    # the positions at the last list build are kept in f32 (collide.moved_past), which rounds
    # them by up to 2^-24·|x|: 6e-3 m at 100 km, more than half the skin (1 mm). The rebuild test
    # adds |x_build|·2^-23, so a ball that moved more than half the skin from where it was at
    # the build is seen as such (lists rebuilt), near the origin and far from it, in every
    # direction; and near the origin a ball that moved well within half the skin is not
    import taichi as ti

    from ti_golf.physics.types import kernel, vec3, vec3_array, vec3f, vec3f_array
    from ti_golf.solvers.collide import moved_past

    def moved(x1, x_build, half_skin, out):
        for i in range(x1.shape[0]):
            out[i] = ti.cast(moved_past(x1[i], x_build[i], 0.0, half_skin), ti.i32)

    # (this module's annotations are strings: from __future__ import annotations)
    moved.__annotations__ = {
        "x1": vec3_array,
        "x_build": vec3f_array,
        "half_skin": float,
        "out": ti.types.ndarray(ti.i32, ndim=1),
    }
    moved = kernel(moved)  # ti.kernel, applied once the float type is chosen

    rng = np.random.default_rng(3)
    n, half_skin = 20_000, 1e-3
    scale = 10.0 ** rng.uniform(-1, 5, n)[:, None]  # 0.1 m to 100 km from the origin
    p = rng.normal(size=(n, 3)) * scale
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    out = ti.ndarray(ti.i32, n)
    for step, expect in ((1.0001 * half_skin, 1), (0.9 * half_skin, 0)):
        x1, xb = ti.ndarray(vec3.get(), n), ti.ndarray(vec3f, n)
        x1.from_numpy(p + step * u)
        xb.from_numpy(p.astype(np.float32))
        moved(x1, xb, half_skin, out)
        seen = out.to_numpy()
        if expect:
            assert seen.all(), p[seen == 0][:3]
        else:  # within half the skin: not seen where the margin is small (within 100 m of the origin)
            near = np.linalg.norm(p, axis=1) < 100.0
            assert not seen[near].any() and near.sum() > 1000


@pytest.mark.parametrize("buckets", [1, 16, 256, 1024])
def test_a_spread_loop_takes_every_bucket_once(buckets):
    # sort.spread_turns cuts a loop over buckets into tasks, each a run of CPU_TASK_ITEMS
    # iterations of its own on the CPU, so that the threads share a loop of a few hundred blocks;
    # every bucket must still be taken by exactly one iteration (each block swept once, by one
    # thread), whatever the number of tasks
    import taichi as ti

    from ti_golf.physics.types import kernel

    def visit(tasks, buckets, seen):
        for t in range(tasks * ti.static(sort.task_stride())):
            turn0, turns = sort.spread_turns(t, tasks, buckets)
            for k in range(turns):
                ti.atomic_add(seen[sort.bucket_in_turn(turn0 + k * tasks, buckets)], 1)  # (integers)

    visit.__annotations__ = {"tasks": ti.i32, "buckets": ti.i32, "seen": ti.types.ndarray(ti.i32, ndim=1)}
    visit = kernel(visit)  # (this module's annotations are strings: from __future__ import annotations)
    seen = ti.ndarray(ti.i32, buckets)
    for tasks in sorted({1, 3, 16, buckets, sort.bucket_tasks(buckets)}):
        if tasks > buckets:
            continue
        seen.fill(0)
        visit(tasks, buckets, seen)
        np.testing.assert_array_equal(seen.to_numpy(), np.ones(buckets, np.int32), err_msg=f"{tasks} tasks")
    assert 1 <= sort.bucket_tasks(buckets) <= buckets


def test_a_boulder_owns_none_of_its_pairs_so_the_impulse_table_stays_narrow():
    # the upper table keeps each pair's impulse and geometry (52 bytes a pair in f64) and is as
    # wide as the longest upper list, for every ball; a ball set apart (apart.APART_MAX: here a
    # boulder five times the radius of the rest) owns none of its pairs with the others
    # (grid.owns), so the ~100 balls within its reach each own one pair more, and its long list
    # goes to the lower table (4 bytes a link). By the axis rule alone it would own about half of
    # them (the balls ahead of it), and every ball's row would be that wide.
    sc, x = pile_scene(4096)
    centre = x.mean(axis=0)
    x = np.vstack([x, centre])  # lists only: no step is taken with it inside the pile
    r = np.full(len(x), 0.02)
    r[-1] = 0.1
    sim = tg.Simulation(sc, x=x, radius=r)
    solver = sim.solver
    solver.build(sim.state)
    assert solver.n_apart == 1 and solver.reorder is False  # (storage index = ball id)
    reach = r[-1] + r[:-1] + solver.skin
    within = set(np.flatnonzero(np.linalg.norm(x[:-1] - centre, axis=1) < reach).tolist())
    assert len(within) > 80
    n_upper, lower_first = _n_upper(solver), solver.lower_first.to_numpy()
    assert n_upper[-1] == 0 and lower_first[-1] - lower_first[-2] == len(within)
    owners = solver.lower.to_numpy()[lower_first[-2] : lower_first[-1]] >> solver.slot_bits
    assert set(owners.tolist()) == within
    assert solver.capacity <= 4  # a lattice ball's three pairs and the boulder's
    ahead = sum(_owns(x, len(x) - 1, j, np.zeros(len(x), bool)) for j in within)
    assert ahead > 30  # what the boulder would own by the axis rule


def test_each_ball_of_a_jostled_lattice_owns_three_pairs():
    # ownership by the axis of largest separation: a ball of a cubic lattice owns its pairs in
    # +x, +y and +z, whatever its shifts (so the pair tables stay three wide); ownership by id or
    # storage order gives a ball a fourth pair whenever neighbours straddle a cell boundary
    sc, x = pile_scene(4096)
    x = x + np.random.default_rng(8).uniform(-4e-4, 4e-4, x.shape)  # 2 % of a radius either way: all listed
    for reorder in (False, True):
        sim = tg.Simulation(sc, x=x[np.random.default_rng(9).permutation(len(x))])
        solver = _grid_ordered(sim) if reorder else sim.solver
        solver.build(sim.state)
        assert solver.capacity == 3
        n_upper = sim.state.to_ids(_n_upper(solver))
        top, right, back = (np.isclose(sim.x[:, k], x[:, k].max(), atol=0.003) for k in (1, 0, 2))
        np.testing.assert_array_equal(n_upper, 3 - top - right - back)


def test_a_pair_that_changes_hands_keeps_its_resting_impulse():
    # a pair is owned by the ball behind the other along their main axis; as two balls move
    # round each other that axis changes, and the pair's λ must move to the other ball's list
    sc = scene()
    r = sc.ball.radius
    s = 2.04 * r / np.sqrt(2.0)  # ball 1 at s·(1, 0.97) from ball 0, then at s·(0.97, −1): 2.01 r apart
    before, after = np.array([1.0, 0.97, 0.0]), np.array([0.97, -1.0, 0.0])
    for reorder in (False, True):
        sim = tg.Simulation(sc, x=np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0] + s * before]))
        solver = _grid_ordered(sim) if reorder else sim.solver
        solver.build(sim.state)
        owner = int(sim.state.from_ids(np.arange(2))[0])  # ball 0 (behind along x) owns the pair
        assert _n_upper(solver)[owner] == 1
        lam, first = solver.lam.to_numpy(), solver.first.to_numpy()
        lam[first[owner]] = 0.25
        solver.lam.from_numpy(lam)
        sim.x = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0] + s * after])  # ball 1 now behind along y
        solver.build(sim.state)
        owner = int(sim.state.from_ids(np.arange(2))[1])
        assert _n_upper(solver)[owner] == 1 and _n_upper(solver)[1 - owner] == 0
        assert solver.lam.to_numpy()[solver.first.to_numpy()[owner]] == 0.25


# A pile of 70,000 balls: its hash grid has 2^18 buckets, more than the 65,535 iterations after
# which Taichi's Vulkan backend silently stops a serial loop.
_GPU_PILE = textwrap.dedent("""
    import dataclasses
    import sys
    import numpy as np
    import ti_golf as tg
    from ti_golf.bench.collide import pile_scene
    from ti_golf.solvers import CollisionSolver

    info = tg.init()
    if info.arch != "vulkan":
        sys.exit(77)  # Taichi fell back to another backend: nothing to compare
    scene, x = pile_scene(70_000)
    scene = dataclasses.replace(scene, contact=dataclasses.replace(scene.contact, solver="jacobi"))
    x = x + np.random.default_rng(5).uniform(-0.002, 0.002, x.shape)
    # and the same pile with a ball shot into its top, kept in id order (see the test)
    x_shot = np.vstack([x, [x[:, 0].mean(), x[:, 1].max() + 0.03, x[:, 2].mean()]])
    v_shot = np.zeros_like(x_shot)
    v_shot[-1] = [0.0, -60.0, 0.0]
    runs = {}
    for name, positions, velocities, reorder in (("", x, None, None), ("_shot", x_shot, v_shot, False)):
        sim = tg.Simulation(scene, x=positions, v=velocities)
        sim.solver = CollisionSolver(sim.model, serial=False, reorder=reorder)
        sim.solver.build(sim.state)
        runs["pairs" + name] = sim.solver.pairs()
        sim.step(2)
        runs["x" + name] = sim.x
    np.savez(sys.argv[1], x0=x, x0_shot=x_shot, v0_shot=v_shot, **runs)
""")


def _gpu_pile(workdir: Path) -> background.Command:
    (workdir / "gpu_pile.py").write_text(_GPU_PILE)
    return background.python(str(workdir / "gpu_pile.py"), str(workdir / "gpu.npz")), {
        "TI_GOLF_ARCH": "vulkan",
        "TI_GOLF_PRECISION": "f64",
    }


background.declare("gpu-pile", _gpu_pile, timeout=600)


@ON_VULKAN
@pytest.mark.background("gpu-pile")
def test_a_gpu_backend_lists_the_neighbours_and_steps_as_the_cpu_does(background_runs):
    # Vulkan is the GPU backend that CI can run (in software, mesa's lavapipe): it compiles the
    # kernels as a GPU does, every loop in parallel. The grid once scanned its bucket counts in a
    # serial loop, and there Taichi's Vulkan backend stops after 65,535 iterations without a
    # word: most balls of this pile then had no neighbours, and it fell through itself. Then a ball
    # is shot into the pile's top: on the CPU the grid lists it apart (apart.APART_MAX), testing it
    # against all 70,001 balls in one thread, which on Vulkan would stop at 65,535 (its
    # neighbours, in the top layers, come last); there the cells are widened for it instead. On
    # both it owns none of its pairs (grid.owns). Both must list the same pairs and take the same
    # step; that pile is kept in id order, since the grid's order follows the cells, and the order
    # of a ball's simultaneous impacts the storage.
    _, workdir = background_runs.succeeded("gpu-pile", NO_VULKAN_BACKEND)
    gpu = np.load(workdir / "gpu.npz")
    for name, v, reorder in (("", None, None), ("_shot", gpu["v0_shot"], False)):
        scene = pile_scene(70_000)[0]
        scene = dataclasses.replace(scene, contact=dataclasses.replace(scene.contact, solver="jacobi"))
        sim = tg.Simulation(scene, x=gpu["x0" + name], v=v)
        sim.solver = CollisionSolver(sim.model, serial=False, reorder=reorder)
        sim.solver.build(sim.state)
        assert sim.solver.n_apart == (1 if name else 0)
        pairs = gpu["pairs" + name]
        assert len(pairs) > 2 * 70_000  # about three pairs per ball in the lattice
        if name:
            assert np.sum(pairs == 70_000) > 10  # the shot ball's pairs (h·v = 6 cm: two layers deep)
        np.testing.assert_array_equal(pairs, sim.solver.pairs())
        sim.step(2)
        # the same step, up to round-off: a GPU need not round as the CPU does (SPIR-V, for one,
        # lets a driver fuse a multiply and an add), and a contact decided on a threshold (impact
        # or resting, see contact.pair_impulse) can then go the other way and move its neighbours
        # in the next sweeps. Measured: 2e-16 m on one host; on another (a Xeon with AVX-512,
        # both sides deterministic) 82 % of the balls identical, none more than 0.24 mm apart,
        # the same deepest overlap. A missed pair or a race would leave overlaps ~0.1 mm deeper.
        d = np.linalg.norm(gpu["x" + name] - sim.x, axis=1)
        assert np.mean(d <= 1e-12) > 0.5 and d.max() < 5e-4, (np.mean(d <= 1e-12), d.max())
        cpu_deepest = sim.deepest_overlap()
        gpu_deepest = tg.Simulation(sim.scene, x=gpu["x" + name]).deepest_overlap()
        assert abs(gpu_deepest.depth - cpu_deepest.depth) < 1e-6, (gpu_deepest, cpu_deepest)


# Every array access of the grid's and the step's kernels checked against the array's bounds
# (Taichi's debug mode), on balls that share cells, with and without the grid's order, tracked or
# not (then the flight records hold one entry), stepped serially, in parallel (the Jacobi sweeps,
# and the Gauss-Seidel sweeps in both layouts) and without collisions, and on the terrain; in f32
# the Gauss-Seidel sweeps again, whose pair table has a column more there (FRIC).
_BOUNDS_CHECKED = textwrap.dedent("""
    import dataclasses
    import sys

    import numpy as np
    import ti_golf as tg

    precision = sys.argv[1]
    tg.init(precision=precision, debug=True)  # before importing the kernels' modules (they initialise)
    from ti_golf.bench.collide import pile_scene
    from ti_golf.solvers import CollisionSolver

    scene, x = pile_scene(300)
    x = np.vstack([x[:1], [[0.021, 0.015, 0.021]], x[1:]])  # ball 1 shares ball 0's cell, below it: stored first
    for layout in ("columns", "contacts"):  # the Gauss-Seidel sweeps, by grid columns and by contact colours
        contact = dataclasses.replace(scene.contact, solver="gauss_seidel", layout=layout)
        sim = tg.Simulation(dataclasses.replace(scene, contact=contact), x=x, track=False)
        sim.solver = CollisionSolver(sim.model, serial=False)  # (302 balls: the serial step by default)
        sim.step(3)
        sim.x = sim.x[::-1]
        sim.step(2)
    if precision == "f32":
        sys.exit()
    for track in (True, False):
        for serial, reorder in ((True, False), (False, False), (False, True)):
            sim = tg.Simulation(scene, x=x, track=track)
            sim.solver = CollisionSolver(sim.model, serial=serial, reorder=reorder)
            sim.step(3)
            sim.x = sim.x[::-1]  # every ball moved: the lists are rebuilt, impulses carried
            sim.step(2)
    v = np.zeros_like(x)
    v[-1] = [0.0, -60.0, 0.0]  # a fast ball, listed apart by the grid (apart.APART_MAX)
    r = np.full(len(x), 0.02)
    r[-1] = 0.2  # or a boulder, listed apart too
    for big, reorder in ((False, False), (False, True), (True, False), (True, True)):
        sim = tg.Simulation(scene, x=x, v=None if big else v, radius=r if big else None, track=False)
        sim.solver = CollisionSolver(sim.model, serial=False, reorder=reorder)
        sim.step(1)
        assert sim.solver.n_apart == 1  # the first build set the ball apart
        sim.step(2)
        sim.x = sim.x + [0.0, 0.003, 0.0]  # every ball moved: the lists are rebuilt
        sim.step(1)
        assert sim.solver.rebuilds > 1
    free = tg.Simulation(tg.load_scene("lab_vacuum", ["world.collisions=false"]), x=x[:5], track=False)
    free.step(3)
    for name in ("terrain_2d", "terrain_3d"):  # a height field: one ball alone, 400 colliding (serially)
        tg.Simulation.from_scene(name).step(3)
    on_terrain = tg.Simulation.from_scene("terrain_3d")
    on_terrain.solver = CollisionSolver(on_terrain.model, serial=False)  # ... and in parallel
    on_terrain.step(3)
""")


def _bounds_checked(precision: str) -> Callable[[Path], background.Command]:
    def make(workdir: Path) -> background.Command:
        (workdir / "bounds_checked.py").write_text(_BOUNDS_CHECKED)
        return background.python(str(workdir / "bounds_checked.py"), precision), {"TI_GOLF_ARCH": "cpu"}

    return make


for _precision in ("f64", "f32"):
    background.declare(f"bounds-checked-{_precision}", _bounds_checked(_precision), timeout=900)


@pytest.mark.parametrize(
    "precision", [pytest.param(p, marks=pytest.mark.background(f"bounds-checked-{p}")) for p in ("f64", "f32")]
)
def test_kernels_stay_within_their_arrays(background_runs, precision):
    # an access out of bounds reads or writes another array's memory: at best garbage, at worst a
    # crash or a race that depends on where the allocator put the arrays. The grid's insertion sort
    # once read sorted_ids[-1] (Taichi evaluates both sides of an `and`), and that crashed a CI run;
    # the warm start once zeroed columns 3 and 4 of the f32 Gauss-Seidel sweeps' 3-column pair
    # table, the next pair's normal and gap, which made f32 runs differ with the threads' timing.
    done = background_runs.result(f"bounds-checked-{precision}")[0]
    assert done.returncode == 0, done.stderr[-3000:]


# ---------------------------------------------------------------------------------------------
# Storage order: a large pile is stored in the grid's order (CollisionSolver.reorder)
# ---------------------------------------------------------------------------------------------
def _grid_ordered(sim: tg.Simulation) -> CollisionSolver:
    sim.solver = CollisionSolver(sim.model, serial=False, reorder=True)
    return sim.solver


def test_balls_stored_in_grid_order_are_read_and_written_by_id():
    x, r = _random_sets()["clustered"]
    m = 0.045 * (r / 0.02) ** 3
    sim = tg.Simulation(scene(), x=x, radius=r, mass=m)
    solver = _grid_ordered(sim)
    solver.build(sim.state)
    order = sim.state.order
    assert order is not None and sorted(order) == list(range(len(x))) and np.any(order != np.arange(len(x)))
    # stored in the new order (ball order[p] at index p), every per-ball array alike ...
    np.testing.assert_array_equal(sim.state.x.to_numpy(), x[order])
    np.testing.assert_array_equal(sim.model.radius.to_numpy(), r[order])
    np.testing.assert_array_equal(sim.model.mass.to_numpy(), m[order])
    # ... and read by ball id: a permutation moves values, it does no arithmetic
    np.testing.assert_array_equal(sim.x, x)
    assert np.all(sim.flight().apex == x[:, 1])  # the flight records start at the launch point
    for i in (0, int(order[0]), len(x) - 1):  # one ball read alone, as a view of it reads it every frame
        np.testing.assert_array_equal(sim.ball(i)[0], x[i])
    with pytest.raises(IndexError, match=f"ball {len(x)} is not one of the {len(x)} balls"):
        sim.ball(len(x))
    found = {(int(i), int(j)) for i, j in solver.pairs()}
    assert found == {(i, j) for i, j in _brute_force_pairs(x, r, solver.skin) if i < j}
    sim.v = np.tile([0.0, 0.0, 1e-3], (len(x), 1)) * np.arange(len(x))[:, None]  # ball k moves at k mm/s
    sim.step(1)
    moved = sim.x - x
    far = np.array([not any(k in p for p in found) for k in range(len(x))])  # balls that touch none
    np.testing.assert_allclose(moved[far, 2], 1e-3 * np.arange(len(x))[far] * sim.dt, rtol=1e-9)
    x1, v1, w1 = sim.x, sim.v, sim.w
    for i in (1, int(order[1]), len(x) - 2):
        for one, every in zip(sim.ball(i), (x1, v1, w1)):
            np.testing.assert_array_equal(one, every[i])


def test_a_non_finite_ball_is_named_by_id_in_grid_order():
    x, r = _random_sets()["sparse"]
    sim = tg.Simulation(scene(), x=x, radius=r)
    _grid_ordered(sim).build(sim.state)
    v = np.zeros((len(x), 3))
    v[1234] = np.nan
    sim.state.write("v", v)
    with pytest.raises(tg.SimulationError, match="ball 1234 "):
        sim.step(1)


@pytest.mark.slow
def test_balls_stored_in_grid_order_step_as_in_id_order():
    # storing the balls in another order changes nothing but the order of sums over a ball's
    # neighbours. A lattice pile settling under gravity with friction and walls, rebuilt every 5
    # steps: each rebuild stores the balls anew and must carry every pair's resting impulse over
    # to its new numbering (the warm start holds the pile up; a lost impulse changes the next
    # step by far more than round-off); and a gas of mixed balls whose pairs change all the time.
    # Both are compared with the same run stored in id order, by ball id. (The pile is bit-identical
    # for 55 steps; then a last-bit difference flips a branch, an inelastic threshold, and it
    # drifts by microns: a mere renumbering of its balls does the same at the same step.) A sweep
    # takes a ball's simultaneous impacts one at a time, in the order of their slots in the pair
    # tables (pairs.matched), which the storage order sets: the gas's balls meet as resting
    # contacts here (v_bounce above every approach), whose impulses accumulate and must be carried.
    # (the Jacobi sweeps: the Gauss-Seidel sweeps meet the pairs in the storage order, so there the
    # two orders are two different runs)
    sc, x = pile_scene(2048)
    sc = dataclasses.replace(sc, contact=dataclasses.replace(sc.contact, solver="jacobi"))
    gas = tg.load_scene("lab_vacuum", [*FREE, "contact.mu=0.3", "contact.v_bounce=100", "contact.solver=jacobi"])
    rng = np.random.default_rng(4)
    r = rng.uniform(0.01, 0.03, 3000)
    cases = [
        (sc, {"x": x[rng.permutation(len(x))]}),
        (
            gas,
            {
                "x": rng.uniform(-0.6, 0.6, (3000, 3)),
                "v": rng.normal(0.0, 1.0, (3000, 3)),
                "radius": r,
                "mass": 0.045 * (r / 0.02) ** 3,
            },
        ),
    ]
    for (sc, balls), rounds in zip(cases, (8, 20)):
        runs = []
        for reorder in (True, False):
            sim = tg.Simulation(sc, **balls)
            sim.solver = CollisionSolver(sim.model, serial=False, reorder=reorder)
            for _ in range(rounds):
                sim.step(5)
                sim.solver.invalidate()
            runs.append(sim)
        grid_order, id_order = runs
        assert grid_order.solver.rebuilds == id_order.solver.rebuilds >= rounds
        assert np.any(grid_order.state.order != np.arange(grid_order.n))
        # a round-off of the last bits per sum, 100 steps on: 3e-15 m and 1e-14 m/s measured in the gas
        np.testing.assert_allclose(grid_order.x, id_order.x, rtol=0, atol=1e-12)
        np.testing.assert_allclose(grid_order.v, id_order.v, rtol=0, atol=1e-10)
        np.testing.assert_allclose(grid_order.w, id_order.w, rtol=0, atol=1e-8)
        np.testing.assert_array_equal(grid_order.status, id_order.status)
        np.testing.assert_array_equal(grid_order.solver.pairs(), id_order.solver.pairs())


@pytest.mark.parametrize(
    "serial, reorder",
    [
        pytest.param(True, False, marks=pytest.mark.skipif(not ON_CPU, reason="serial stepping runs on the CPU only")),
        (False, False),
        (False, True),
    ],
    ids=["serial", "parallel", "grid_order"],
)
def test_a_pile_that_tracks_no_flight_keeps_no_flight_record_and_steps_the_same(serial, reorder):
    # the flight record (apex, landing, the launch heights it is measured from) is bookkeeping that
    # never feeds back into the step: a pile of balls that are not tracked, as a scene's
    # [[blocks]] without launch ranges are, keeps one entry per record instead of one per ball and
    # must step bit for bit as the same pile with every ball tracked, rebuilt (and, stored in the
    # grid's order, gathered anew) every 5 steps
    sc, x = pile_scene(200 if serial else 600)
    x = x + np.random.default_rng(5).uniform(-1e-4, 1e-4, x.shape)  # so the pile shifts and lists change
    runs = []
    for track in (True, False):
        sim = tg.Simulation(sc, x=x, track=track)
        sim.solver = CollisionSolver(sim.model, serial=serial, reorder=reorder)
        for _ in range(6):
            sim.step(5)
            sim.solver.invalidate()
        runs.append(sim)
    tracked, untracked = runs
    for name in ("x", "v", "w", "status"):
        np.testing.assert_array_equal(getattr(untracked, name), getattr(tracked, name))
    assert tracked.flight().apex.shape == (len(x),) and np.all(np.isfinite(tracked.flight().apex))
    st = untracked.state
    assert not st.tracking and st.apex.shape == st.land_x.shape == untracked.model.launch_height.shape == (1,)
    assert untracked.launch_x is None
    f = untracked.flight()
    assert f.apex.shape == (len(x),) and not f.landed.any()
    assert np.all(np.isnan(f.apex)) and np.all(np.isnan(f.carry)) and np.all(np.isnan(f.flight_time))
    t = untracked.t  # (waiting for no ball to land stopped at the first check, 0.05 s on: refused)
    with pytest.raises(ValueError, match="until='landed' has no effect: no ball is tracked"):
        untracked.run(steps=100, until="landed")
    assert untracked.t == t


@pytest.mark.slow
@pytest.mark.parametrize("method", ["jacobi", "gauss_seidel"])
def test_rebuild_keeps_each_pairs_resting_impulse(method):
    # the warm start needs each pair's accumulated impulse λ to survive a rebuild of the lists
    # (rebuilt in place, widened when a list overflows): the same pair keeps the same λ, and under
    # Gauss–Seidel the friction impulse F (on the ball of the lower id: a pair can change owner)
    # that the next step uses of it, F in the tangent plane of the pair's normal n and at most μ·λ
    # long (contact.clamp_friction), kept in the stash to 1/links.FRICTION_STEPS of μ·λ in each of
    # two tangent components
    x, r = _random_sets()["clustered"]
    sc = scene("world.gravity=[0,-9.81,0]", "world.ground=true", "contact.mu=0.3", f"contact.solver={method}")
    sim = tg.Simulation(sc, x=x[:400] * 0.3 + [0, 0.2, 0], radius=np.full(400, 0.02))
    sim.solver = CollisionSolver(sim.model, serial=False)  # (400 balls: the serial step by default)
    sim.run(t=0.3)  # a heap on the ground: many pairs with λ > 0
    solver: CollisionSolver = sim.solver
    with_friction = method == "gauss_seidel"

    def by_pair():
        upper, n_upper, lam = solver.upper.to_numpy(), _n_upper(solver), solver.lam.to_numpy()
        first = solver.first.to_numpy()
        F = solver.friction.to_numpy() if with_friction else np.zeros((len(lam), 3))
        pairs = {}
        for i in range(len(n_upper)):
            for k in range(n_upper[i]):
                j, p = int(upper[i, k]), first[i] + k
                pairs[(min(i, j), max(i, j))] = (lam[p], *(F[p] if i < j else -F[p]))
        return pairs

    x, mu = sim.state.x.to_numpy(), 0.3  # (storage order, as the lists)

    def used(pair, values):  # what the next step uses of a pair's (λ, F): F clamped as clamp_friction does
        lam, F = values[0], np.asarray(values[1:], float)
        n = x[pair[0]] - x[pair[1]]
        n /= np.linalg.norm(n)
        F_t = F - F.dot(n) * n
        size = np.linalg.norm(F_t)
        return lam, F_t * min(1.0, mu * lam / size) if size > 0.0 else F_t

    before = by_pair()
    assert sum(v[0] > 0 for v in before.values()) > 20
    if with_friction:
        assert sum(any(v[1:]) for v in before.values()) > 20  # pairs with a friction impulse
    # in place, then from width 1 (widened again), then into new pair tables
    for capacity, pair_capacity in ((solver.capacity, solver.pair_capacity), (1, solver.pair_capacity), (None, 1)):
        solver.capacity, solver.pair_capacity = capacity or solver.capacity, pair_capacity
        solver.build(sim.state)
        after = by_pair()
        for p in after:  # new pairs start at 0
            lam, F = after[p][0], np.asarray(after[p][1:])
            lam0, F0 = used(p, before.get(p, (0.0, 0.0, 0.0, 0.0)))
            assert lam == lam0
            # f32 storage (2^-24 of |F|) and the stash's steps of μ·λ/FRICTION_STEPS in each of two components
            tol = 1e-7 * np.linalg.norm(F0) + 0.71 * np.sqrt(2) * mu * lam / links.FRICTION_STEPS
            assert np.linalg.norm(F - F0) <= tol
        assert sum(after[p][0] > 0 for p in after) == sum(before[p][0] > 0 for p in before)  # no pressing pair lost
        assert sum(any(after[p][1:]) for p in after) == sum(any(before[p][1:]) for p in before)
        before = after
    if not with_friction:
        return
    # the heap turned a quarter turn about the vertical: the pairs keep their distances, but many
    # change owner (the ball behind the other along their main axis), and their friction is
    # carried from the other ball's stash, in its own tangent basis and with the opposite sign
    owners = {(i, int(j)) for i in range(len(x)) for j in solver.upper.to_numpy()[i, : _n_upper(solver)[i]]}
    c = x.mean(axis=0)
    x = np.stack([x[:, 2] - c[2] + c[0], x[:, 1], c[0] - x[:, 0] + c[2]], axis=1)
    sim.state.x.from_numpy(x)
    solver.build(sim.state)
    after = by_pair()
    turned = {(i, int(j)) for i in range(len(x)) for j in solver.upper.to_numpy()[i, : _n_upper(solver)[i]]}
    changed = [p for p in after if (p[1], p[0]) in owners and p in turned or p in owners and (p[1], p[0]) in turned]
    assert sum(any(after[p][1:]) for p in changed) >= 10  # (enough of them to test)
    for p in after:
        lam0, F0 = used(p, before.get(p, (0.0, 0.0, 0.0, 0.0)))
        assert after[p][0] == lam0
        tol = 1e-7 * np.linalg.norm(F0) + 0.71 * np.sqrt(2) * mu * lam0 / links.FRICTION_STEPS
        assert np.linalg.norm(np.asarray(after[p][1:]) - F0) <= tol


# A Gauss–Seidel heap in f32 (its own process: the test session runs in f64), whose friction
# impulses a rebuild stashes in a third column of the sweep's table (types.FRIC): each pair's
# resting and friction impulses before and after a rebuild in place, then after the heap is
# turned a quarter turn about the vertical (pairs change owner).
_F32_CARRY = textwrap.dedent("""
    import sys
    import numpy as np
    import ti_golf as tg
    from ti_golf.solvers import CollisionSolver

    tg.init(precision="f32")
    free = ["world.ground=true", "air.rho=0", "world.gravity=[0,-9.81,0]", "world.integrator=semi_implicit"]
    sc = tg.load_scene("lab_vacuum", [*free, "world.dt=0.0005", "contact.mu=0.3", "contact.solver=gauss_seidel"])
    x = np.random.default_rng(3).normal(0.0, 0.08, (400, 3)) * 0.3 + [0.0, 0.2, 0.0]
    sim = tg.Simulation(sc, x=x, radius=np.full(400, 0.02), track=False)
    s = sim.solver = CollisionSolver(sim.model, serial=False, reorder=False)
    sim.run(t=0.3)

    def by_pair():
        upper, first = s.upper.to_numpy(), s.first.to_numpy()
        lam, F = s.lam.to_numpy(), s.friction.to_numpy()
        out = {}
        for i in range(len(first) - 1):
            for k in range(first[i + 1] - first[i]):
                j, p = int(upper[i, k]), first[i] + k
                out[(min(i, j), max(i, j))] = (lam[p], *(F[p] if i < j else -F[p]))
        return out

    out = {"columns": s.impulse.shape[1]}
    for name in ("in_place", "turned"):
        if name == "turned":
            x = sim.state.x.to_numpy().astype(float)
            c = x.mean(axis=0)
            sim.state.x.from_numpy(np.stack([x[:, 2] - c[2] + c[0], x[:, 1], c[0] - x[:, 0] + c[2]], 1).astype(np.float32))
        before = by_pair()
        s.build(sim.state)
        after = by_pair()
        keys = sorted(after)
        out[name + "_pairs"] = np.array(keys)
        out[name + "_before"] = np.array([before.get(p, (0.0, 0.0, 0.0, 0.0)) for p in keys], float)
        out[name + "_after"] = np.array([after[p] for p in keys], float)
        out[name + "_x"] = sim.state.x.to_numpy().astype(float)
    np.savez(sys.argv[1], **out)
""")


def _f32_carry(workdir: Path) -> background.Command:
    (workdir / "f32_carry.py").write_text(_F32_CARRY)
    return background.python(str(workdir / "f32_carry.py"), str(workdir / "carry.npz")), {}


background.declare("f32-carry", _f32_carry)


@pytest.mark.background("f32-carry")
def test_an_f32_rebuild_carries_the_friction_impulses_in_a_column_of_their_own(background_runs):
    # In f32 the stash's id and resting impulse fill its two columns, so the friction impulse
    # gets a third (in f64 it shares the id's 64 bits). A rebuild must carry what the next step
    # uses of each pair's friction impulse F, F in the tangent plane of its normal and at most
    # mu·lambda long (contact.clamp_friction), to one step of mu·lambda/links.FRICTION_STEPS (half a
    # step in each of two components, and the f32 normal's round-off), and lambda exactly; in
    # place, and after a quarter turn that makes pairs change owner.
    done, workdir = background_runs.result("f32-carry")
    assert done.returncode == 0, done.stderr[-2000:]
    run = np.load(workdir / "carry.npz")
    assert int(run["columns"]) == 3
    for name in ("in_place", "turned"):
        pairs, before, after, x = (run[name + k] for k in ("_pairs", "_before", "_after", "_x"))
        n = x[pairs[:, 0]] - x[pairs[:, 1]]
        n /= np.linalg.norm(n, axis=1)[:, None]
        F = before[:, 1:] - np.sum(before[:, 1:] * n, axis=1)[:, None] * n
        bound = 0.3 * before[:, 0]
        size = np.linalg.norm(F, axis=1)
        F *= np.minimum(1.0, bound / np.maximum(size, 1e-30))[:, None]
        np.testing.assert_array_equal(after[:, 0], before[:, 0])
        carried = (bound > 0) & (size > 0)
        assert carried.sum() > 50  # (93-106 pressing pairs of some 500 in the sets of seeds 1 to 5)
        steps = np.linalg.norm(after[:, 1:] - F, axis=1)[carried] / (bound[carried] / links.FRICTION_STEPS)
        assert steps.max() < 1.0, steps.max()


@pytest.mark.slow
def test_widening_the_pair_tables_never_holds_the_old_and_the_new_together(monkeypatch):
    # the peak memory of a pour is reached while its lists widen and its pairs grow in number: the
    # narrower or shorter tables must be freed before the new ones are allocated (the stash of the
    # old impulses, shorter than the new sweep table, aside), so that the tables alive at any
    # allocation take no more than they do once the lists are built. And the pair tables hold
    # the pairs listed, ball after ball, not as many per ball as the longest list
    import gc

    import taichi as ti
    from taichi.lang._ndarray import Ndarray

    n = 2250
    gc.collect()
    # the arrays other tests of the process left: held, so that none is collected (or its id taken)
    # while the pour's are counted, and left out of the count
    before = [a for a in gc.get_objects() if isinstance(a, Ndarray)]
    earlier = {id(a) for a in before}
    sim = tg.Simulation(pit_scene(n)[0])  # a pour into a bin: the lists widen as the balls land

    def table_bytes():  # every array with an entry per ball or more, alive or not yet collected
        total = 0
        for a in gc.get_objects():
            if isinstance(a, Ndarray) and id(a) not in earlier and (a.shape[0] >= n or n in a.shape):
                item = 8 if "64" in str(a.dtype) else 4
                total += int(np.prod(a.shape)) * int(np.prod(getattr(a, "element_shape", ()) or (1,))) * item
        return total

    allocate, peaks = ti.ndarray, []

    def counting(*args, **kwargs):
        out = allocate(*args, **kwargs)
        peaks.append(table_bytes())
        return out

    monkeypatch.setattr(ti, "ndarray", counting)
    widths, lengths = {sim.solver.capacity}, {sim.solver.pair_capacity}
    for _ in range(10):
        sim.run(t=0.03)
        widths.add(sim.solver.capacity)
        lengths.add(sim.solver.pair_capacity)
    monkeypatch.undo()
    assert len(widths) >= 3 and len(lengths) >= 3  # widened and grown at least twice
    assert max(peaks) <= table_bytes()
    s = sim.solver
    first = s.first.to_numpy()
    assert first[0] == 0 and np.all(np.diff(first) >= 0)  # each ball's pairs after the last one's
    assert first[-1] <= s.pair_capacity == len(s.lam.to_numpy()) == len(s.friction.to_numpy())
    assert s.pair_capacity < 0.75 * n * s.capacity  # the longest list is well above the mean


# ---------------------------------------------------------------------------------------------
# Two balls against closed form
# ---------------------------------------------------------------------------------------------
def _collide(sc, v, mass=(0.045, 0.045), w=None, offset=(0.0, 0.0, 0.0), t=0.1):
    x = np.array([[0.0, 1.0, 0.0], [0.05, 1.0, 0.0]]) + np.array([[0, 0, 0], offset])
    sim = tg.Simulation(sc, x=x, v=v, w=w, mass=list(mass))
    sim.run(t=t)
    return sim


def test_equal_masses_head_on_exchange_velocities():
    sim = _collide(scene("contact.e=1"), v=[[1.5, 0, 0], [-0.5, 0, 0]])
    np.testing.assert_allclose(sim.v, [[-0.5, 0, 0], [1.5, 0, 0]], atol=1e-12)


@pytest.mark.parametrize("e", [0.0, 0.3, 0.8])
def test_unequal_masses_with_restitution(e):
    # textbook 1-D impact: v1' = (m1 u1 + m2 u2 + m2 e (u2 − u1)) / (m1 + m2), likewise v2'
    m1, m2, u1, u2 = 0.045, 0.12, 2.0, -0.5
    sim = _collide(scene(f"contact.e={e}", "contact.v_bounce=0"), v=[[u1, 0, 0], [u2, 0, 0]], mass=(m1, m2))
    v1 = (m1 * u1 + m2 * u2 + m2 * e * (u2 - u1)) / (m1 + m2)
    v2 = (m1 * u1 + m2 * u2 + m1 * e * (u1 - u2)) / (m1 + m2)
    np.testing.assert_allclose(sim.v[:, 0], [v1, v2], atol=1e-12)


def test_overlap_is_projected_out_in_proportion_to_the_other_mass():
    # B.18: an overlap Δx is reduced by k_p·m_red·Δx·n̂ per ball and step, m_red = m_other/(m_a + m_b);
    # balls at rest get no impulse, so after one step only the projection has moved them
    k_p, m1, m2, overlap = 0.2, 0.045, 0.135, 0.004
    sc = scene(f"contact.k_p={k_p}", "contact.solver=jacobi")  # (the report's step: one projection)
    x = np.array([[0.0, 1.0, 0.0], [0.04 - overlap, 1.0, 0.0]])
    sim = tg.Simulation(sc, x=x, mass=[m1, m2])
    sim.step(1)
    np.testing.assert_allclose(
        sim.x[:, 0], [-k_p * m2 / (m1 + m2) * overlap, x[1, 0] + k_p * m1 / (m1 + m2) * overlap], rtol=0, atol=1e-15
    )
    np.testing.assert_allclose(sim.v, 0.0, atol=0)  # no impulse between balls that do not approach
    assert m1 * sim.x[0, 0] + m2 * sim.x[1, 0] == pytest.approx(m2 * x[1, 0], abs=1e-15)  # centre of mass kept


def test_oblique_hit_without_friction_keeps_tangential_velocity():
    # centres offset along z: the impulse acts along the line of centres only (μ = 0)
    sim = _collide(scene("contact.e=1"), v=[[2.0, 0, 0.7], [0, 0, 0]], offset=(0.0, 0.0, 0.025))
    x = sim.x
    # the normal at impact: recover it from the final velocities (ball 2 moves along it)
    n = sim.v[1] / np.linalg.norm(sim.v[1])
    t = np.cross(n, [0, 1, 0])
    assert np.dot(sim.v[0], t) == pytest.approx(np.dot([2.0, 0, 0.7], t), abs=1e-12)
    assert np.dot(sim.v[1], t) == pytest.approx(0.0, abs=1e-12)
    assert np.isfinite(x).all()
    np.testing.assert_allclose(sim.w, 0.0, atol=1e-12)  # no friction, no spin


def test_friction_spins_colliding_balls():
    # With friction a glancing hit sets both balls spinning. The friction forces are opposite but
    # act on opposite sides of the two centres, so for equal balls the torques and the spins are
    # identical: Δω = (5/2)·(−r n̂ × P)/(m r²) for both. Kinetic energy is lost (e < 1, sliding).
    v0 = np.array([[2.0, 0, 0], [0, 0, 0]])
    sim = _collide(scene("contact.e=0.5", "contact.mu=0.3"), v=v0, offset=(0, 0, 0.03))
    np.testing.assert_allclose(sim.w[0], sim.w[1], rtol=1e-12)
    assert abs(sim.w[0, 1]) > 1.0
    m, r = 0.045, 0.02

    def ke(v, w):
        return 0.5 * m * (v**2).sum() + 0.5 * 0.4 * m * r**2 * (w**2).sum()

    assert ke(sim.v, sim.w) < ke(v0, np.zeros((2, 3)))


# ---------------------------------------------------------------------------------------------
# Many balls
# ---------------------------------------------------------------------------------------------
def _gas(sc, n=1000, seed=0):
    rng = np.random.default_rng(seed)
    side = int(np.ceil(n ** (1 / 3)))
    grid = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3)[:n]
    x = 0.05 * grid + rng.uniform(-0.004, 0.004, (n, 3))
    v = rng.normal(0, 1.0, (n, 3))
    mass = rng.uniform(0.03, 0.06, n)
    return tg.Simulation(sc, x=x, v=v, mass=mass, radius=0.02)


@pytest.mark.slow
def test_momentum_is_conserved_to_round_off_in_a_gas():
    sim = _gas(scene("contact.e=0.7", "contact.mu=0.3"))
    m = sim.model.mass_np
    p0 = (m[:, None] * sim.v).sum(axis=0)
    sim.run(t=0.5)
    p1 = (m[:, None] * sim.v).sum(axis=0)
    scale = (m[:, None] * np.abs(sim.v)).sum()
    assert np.abs(p1 - p0).max() < 1e-13 * scale
    assert sim.solver.rebuilds > 1  # the gas moved enough to rebuild the lists


def test_the_benchs_one_pass_floor_gives_the_two_balls_of_a_pair_opposite_impulses():
    # the collide bench's floor (physics.baseline.one_pass_contacts) must be a pass of the contact
    # model itself, not a cheaper stand-in: every listed pair met from both of its balls through
    # the pair impulse (B.5-B.18), which gives them opposite impulses (sum of m dv = 0 to
    # round-off), with friction spinning them (B.15). A lattice pressed 2.5 % closer than touching,
    # mixed radii and masses, random velocities and spins, restitution and friction.
    from ti_golf.bench.collide import one_pass_contacts

    rng = np.random.default_rng(5)
    grid = np.stack(np.meshgrid(*[np.arange(7)] * 3, indexing="ij"), -1).reshape(-1, 3)
    x = 0.039 * grid + rng.uniform(-0.001, 0.001, grid.shape)
    n = len(x)
    sim = tg.Simulation(
        scene("contact.e=0.7", "contact.mu=0.3"),
        x=x,
        v=rng.normal(0, 1.0, (n, 3)),
        w=rng.normal(0, 50.0, (n, 3)),
        radius=rng.uniform(0.0195, 0.0205, n),
        mass=rng.uniform(0.03, 0.06, n),
    )
    run, dv, dw = one_pass_contacts(sim)
    run()
    dv, dw, m = dv.to_numpy(), dw.to_numpy(), sim.model.mass_np
    assert not sim.solver.reorder  # (the state's storage order is the id order)
    momentum = (m[:, None] * dv).sum(axis=0)
    scale = (m[:, None] * np.abs(dv)).sum()
    assert scale > 0 and np.abs(momentum).max() < 1e-13 * scale
    assert np.count_nonzero(np.abs(dw).sum(axis=1)) > n // 2  # friction at most contacts


@pytest.mark.slow
def test_kinetic_energy_is_conserved_with_e1_mu0():
    # e = 1, μ = 0: every binary impact conserves kinetic energy exactly; simultaneous contacts
    # resolved by Jacobi sweeps and the position projection leave a small error we bound at 1 %
    # (the Gauss–Seidel sweeps, the default, bounce a group of touching balls as one and lose 2 %).
    sim = _gas(scene("contact.solver=jacobi", "contact.e=1", "contact.v_bounce=0", "contact.k_p=0"))
    m = sim.model.mass_np
    v0 = sim.v
    e0 = 0.5 * (m * (v0**2).sum(axis=1)).sum()
    sim.run(t=0.5)
    e1 = 0.5 * (m * (sim.v**2).sum(axis=1)).sum()
    assert abs(e1 - e0) / e0 < 0.01
    # and the energy was passed between the balls: no air, no gravity, so a ball's velocity changes
    # only in a collision, and most balls of the gas (1 cm apart, at about 1.6 m/s for 0.5 s) met
    # another, their velocity changed by more than a tenth of the typical speed
    changed = np.linalg.norm(sim.v - v0, axis=1) > 0.1 * np.sqrt(2.0 * e0 / m.sum())
    assert changed.mean() > 0.8, changed.mean()


def test_newtons_cradle_passes_the_impulse_through_the_row():
    sim = tg.Simulation.from_scene("newtons_cradle")
    sim.run(t=0.3)
    np.testing.assert_allclose(sim.v[:5, 0], 0.0, atol=1e-9)  # striker and four balls stop
    assert sim.v[5, 0] == pytest.approx(1.0, rel=1e-9)  # the last ball leaves with the speed
    assert sim.x[5, 0] > 0.2


def test_column_of_ten_balls_stands():
    # report Appendix B contacts with warm-started resting impulses: a column on the ground
    # stays standing and sinks less than 1 % of a radius over 10 s
    sc = tg.load_scene("lab_vacuum", ["world.integrator=semi_implicit", "world.dt=0.001", "contact.e=0.3"])
    x = np.array([[0.0, 0.02 + 0.04 * i, 0.0] for i in range(10)])
    sim = tg.Simulation(sc, x=x)
    sim.run(t=10.0)
    assert sim.x[-1, 1] > 0.38 - 0.01 * 0.02
    np.testing.assert_allclose(sim.x[:, [0, 2]], 0.0, atol=1e-9)  # still a column
    assert np.all(np.diff(sim.x[:, 1]) > 0.04 - 0.01 * 0.02)  # no pair overlaps by 1 % of a radius
    assert sim.counts()["at_rest"] == 10  # and it has come to rest, not to a limit cycle


@pytest.mark.slow
@pytest.mark.parametrize("iterations", [2, 4])
def test_a_calm_column_falls_asleep_in_one_step(iterations):
    # island-like sleeping: a ball's rest timer counts on from the least timer of the balls it
    # touches, so a column falls asleep as a whole, with either sweep count; a lowest ball put to
    # sleep alone would feel no gravity while the balls above it still move, and the column would
    # keep rocking (and sink) instead of resting
    sc = tg.load_scene(
        "lab_vacuum",
        ["world.integrator=semi_implicit", "world.dt=0.001", "contact.e=0.3", f"contact.iterations={iterations}"],
    )
    x = np.array([[0.0, 0.02 + 0.04 * i, 0.0] for i in range(10)])
    sim = tg.Simulation(sc, x=x)
    asleep_at = np.full(10, -1)
    for k in range(1, 2001):  # 2 s
        sim.step(1)
        at_rest = sim.state.status.to_numpy() == AT_REST
        asleep_at[at_rest & (asleep_at < 0)] = k
        if at_rest.all():
            break
    assert np.all(asleep_at == asleep_at[0]) and asleep_at[0] > 0, asleep_at
    assert asleep_at[0] * 0.001 >= sc.world.t_rest  # no earlier than t_rest after the drop


def test_touching_balls_fall_asleep_in_the_same_step_with_the_gauss_seidel_sweeps():
    # with the Gauss–Seidel sweeps a ball may fall asleep before balls a few contacts away
    # (pairs.island_calm), but not before a ball it touches: a ball whose supports fell asleep
    # first stood on them firm while it still crept, rolled off and woke them, over and over (so
    # the top of the 100,000-ball pour stayed awake). Two balls side by side on the ground, one
    # spinning about the vertical (R|ω| = 6 cm/s, above v_rest) until the pivot friction stops it:
    # the other's rest timer runs ahead of it, yet the two fall asleep in one step
    sc = tg.load_scene("break_shot", ['contact.solver="gauss_seidel"', "world.dt=0.001"])
    r = sc.ball.radius
    sim = tg.Simulation(sc, x=np.array([[0.0, r, 0.0], [2.0 * r, r, 0.0]]), w=np.array([[0.0] * 3, [0.0, 3.0, 0.0]]))
    asleep_at, calm_from = np.full(2, -1), np.full(2, -1)
    for k in range(1, 1001):  # 1 s
        sim.step(1)
        calm_from[(sim.state.rest_time.to_numpy() > 0.0) & (calm_from < 0)] = k
        at_rest = sim.state.status.to_numpy() == AT_REST
        asleep_at[at_rest & (asleep_at < 0)] = k
        if at_rest.all():
            break
    assert calm_from[0] < calm_from[1], calm_from  # the still ball's timer ran ahead
    assert asleep_at[0] == asleep_at[1] > 0, asleep_at


@pytest.mark.parametrize("solver", ["gauss_seidel", "jacobi"])
def test_with_no_rest_time_only_slow_balls_rest(solver):
    # world.t_rest = 0 put every touching ball at rest in its first step, whatever its speed: the
    # break's cue ball (6 m/s) stayed where it was; now it rolls on, and balls at rest stay so
    sim = tg.Simulation.from_scene("break_shot", ["world.t_rest=0", f'contact.solver="{solver}"'])
    sim.step(50)  # the cue ball does not reach the rack at x = 1 m
    x, v = sim.x, sim.v
    assert sim.state.status.to_numpy()[0] != AT_REST and 0.9 * 6.0 * sim.t < x[0, 0] < 6.0 * sim.t, x[0]
    assert np.all(sim.state.status.to_numpy()[1:] == AT_REST) and np.all(v[1:] == 0.0)
    if solver == "gauss_seidel":  # one ball (no collision solver): the putt rolls too
        putt = tg.Simulation.from_scene("putting_green", ["world.t_rest=0"])
        x0 = putt.x[0].copy()
        putt.step(50)
        assert (
            putt.counts()["at_rest"] == 0 and np.linalg.norm(putt.x[0] - x0) > 0.5 * np.linalg.norm(putt.v[0]) * putt.t
        )


def test_a_sleeping_column_stays_put_until_a_ball_lands_on_it():
    # balls asleep whose neighbours are all asleep are skipped by the sweeps and stay exactly where
    # they are (docs, physics: "put at rest and stays exactly where it is"); a ball falling onto the top of
    # the column enters its neighbour list, wakes it, and comes to rest on it (no tunnelling)
    sc = tg.load_scene("lab_vacuum", ["world.integrator=semi_implicit", "world.dt=0.001", "contact.e=0.3"])
    x = np.array([[0.0, 0.02 + 0.04 * i, 0.0] for i in range(10)] + [[0.0, 2.0, 0.0]])
    sim = tg.Simulation(sc, x=x)
    sim.step(450)  # the column is asleep after 0.35 s (see above); the ball falls 1.58 m in 0.57 s
    status = sim.state.status.to_numpy()
    assert np.all(status[:10] == AT_REST) and status[10] != AT_REST
    column = sim.x[:10].copy()
    woken = False
    while sim.x[10, 1] > 0.45:
        sim.step(1)
        np.testing.assert_array_equal(sim.x[:10], column)  # asleep: not moved by a single bit
    for _ in range(20):  # the impact wakes the top of the column
        sim.step(1)
        woken |= sim.state.status.to_numpy()[9] != AT_REST
    assert woken
    sim.run(t=5.0)
    assert sim.counts()["at_rest"] == 11  # the column with its new top ball rests again, as a whole
    np.testing.assert_allclose(sim.x[:, [0, 2]], 0.0, atol=1e-9)  # still a column, the new ball on top ...
    assert np.all(np.diff(sim.x[:, 1]) > 0.04 - 0.01 * 0.02)  # ... and no pair overlaps by 1 % of a radius


def _outcome(sim, asleep: int, *arrays: np.ndarray) -> tuple:
    """What two runs that must agree bit for bit are compared on: ``asleep`` (the most balls
    asleep seen), x, v, ω, the status and rest timers, ``arrays``, the time and the rebuilds."""
    st = sim.state
    return (
        asleep,
        sim.x,
        sim.v,
        sim.w,
        st.status.to_numpy(),
        st.rest_time.to_numpy(),
        *arrays,
        np.float64(sim.t),
        np.float64(sim.solver.rebuilds),
    )


def _gauss_seidel_column() -> tg.Simulation:
    """A column of 10 touching balls on the ground (e = 0.3, the Gauss–Seidel sweeps, 1 ms steps),
    no air: it falls asleep by t = 0.2 s."""
    sc = tg.load_scene(
        "lab_vacuum",
        ["world.integrator=semi_implicit", "world.dt=0.001", "contact.e=0.3", 'contact.solver="gauss_seidel"'],
    )
    return tg.Simulation(sc, x=np.array([[0.0, 0.02 + 0.04 * i, 0.0] for i in range(10)]))


@pytest.mark.slow
def test_a_step_with_every_ball_asleep_is_skipped_and_changes_nothing():
    # with the Gauss–Seidel sweeps a ball asleep takes no impulse and does not move
    # (colour.stands_firm), and only a moving ball wakes it: a step in which no ball is awake
    # changes nothing, and the parallel step skips it (CollisionSolver.skip_still). A column
    # stepped with and without the skip must be the same bit for bit: while it falls asleep (by
    # t = 0.2 s), asleep (the steps skipped), and after its top ball, tossed up between steps
    # (set_ball), lands back on it, wakes the balls below and sleeps with them again: those steps
    # must find every impulse and list as the skipped steps left them
    runs, skipped, woken = [], [], []
    for skip in (True, False):
        sim = _gauss_seidel_column()
        sim.solver = solver = CollisionSolver(sim.model, serial=False)
        solver.skip_still = skip
        sim.step(250)
        asleep, before = sim.counts()["at_rest"], solver.still_steps
        sim.set_ball(9, v=[0.0, 0.3, 0.0])  # it rises 4.6 mm and falls back within 0.07 s
        most_awake = 0
        for _ in range(30):  # 0.3 s
            sim.step(10)
            most_awake = max(most_awake, 10 - sim.counts()["at_rest"])
        runs.append(
            _outcome(sim, asleep, solver.lam.to_numpy(), solver.friction.to_numpy(), solver.surface_impulse.to_numpy())
        )
        skipped.append((before, solver.still_steps - before))
        woken.append(most_awake)
    for a, b in zip(*runs):
        np.testing.assert_array_equal(a, b)
    assert runs[0][0] == 10 and woken[0] >= 2  # the column slept, and the tossed ball woke the one below
    assert np.all(runs[0][4] == AT_REST)  # ... and slept again
    assert skipped[0][0] > 20 and skipped[0][1] > 20 and skipped[1] == (0, 0)  # the steps asleep, skipped


@SERIAL_OR_PARALLEL
def test_a_ball_still_quiet_is_not_asked_again_and_the_steps_are_the_same(serial):
    # with the Gauss–Seidel sweeps a ball quiet at one step (asleep among balls asleep) stays
    # quiet unless a neighbour wakes in the next step's first loop, which takes its calm time
    # back (pairs.still_quiet, stir_neighbours); so the step asks it of nothing. A column stepped
    # so, and stepped with every ball asked at every step (Stepping.forget_quiet before each),
    # must be the same bit for bit: asleep, then while its top ball, tossed up between steps
    # (set_ball), lands back and wakes the ball below, which wakes the ball below it: that ball
    # was quiet, and owns its pair with the ball woken above it (the lower ball owns a pair
    # along y), so that, were it left quiet, the pair would go unswept and the column would sink
    runs, woken, quiet = [], [], []
    for ask_every_step in (False, True):
        sim = _gauss_seidel_column()
        sim.solver = solver = CollisionSolver(sim.model, serial=serial)
        solver.skip_still = False  # (every step taken, asleep or not)
        most_quiet, most_awake = 0, 0
        for k in range(550):
            if k == 250:
                sim.set_ball(9, v=[0.0, 0.3, 0.0])  # it rises 4.6 mm and falls back within 0.07 s
            if ask_every_step:
                solver.forget_quiet()
            sim.step(1)
            most_quiet = max(most_quiet, int(np.sum(solver.calm.to_numpy() == QUIET)))
            most_awake = max(most_awake, 10 - sim.counts()["at_rest"]) if k >= 250 else 0
        runs.append(_outcome(sim, most_quiet, solver.lam.to_numpy(), solver.friction.to_numpy()))
        woken.append(most_awake)
        quiet.append(most_quiet)
    for a, b in zip(*runs):
        np.testing.assert_array_equal(a, b)
    assert quiet[0] >= 8 and woken[0] >= 3  # quiet balls, and a wake that went two balls down
    assert np.all(runs[0][4] == AT_REST)  # ... and the column slept again


@pytest.mark.slow
@pytest.mark.skipif(not ON_CPU, reason="serial stepping runs on the CPU only")
def test_serial_launches_skip_the_steps_of_a_pile_asleep_as_the_parallel_steps_do():
    # beyond RELIST_MAX_BALLS the serial launches stop when no ball is awake, and the steps left
    # of the call are skipped (none would change anything, so neither would the next): a slab of
    # touching balls falls asleep, is woken by a ball tossed onto it and sleeps again, the same bit
    # for bit serially and in parallel, skipping or not
    sc = tg.load_scene(
        "lab_vacuum",
        ["world.integrator=semi_implicit", "world.dt=0.001", "contact.e=0.3", 'contact.solver="gauss_seidel"'],
    )
    probe = tg.Simulation(sc)
    d = 2.0 * float(probe.model.radius_np.max())
    side, layers = 10, (RELIST_MAX_BALLS + 99) // 100 + 1
    x = np.array([[d * i, d * (k + 0.5), d * j] for k in range(layers) for j in range(side) for i in range(side)])
    assert len(x) > RELIST_MAX_BALLS
    runs, skipped = [], []
    for serial, skip in ((True, True), (False, True), (True, False)):
        sim = tg.Simulation(sc, x=x)
        sim.solver = solver = CollisionSolver(sim.model, serial=serial)
        solver.skip_still = skip
        assert not solver.relists
        sim.step(250)
        asleep, before = sim.counts()["at_rest"], solver.still_steps
        sim.set_ball(len(x) - 45, v=[0.0, 0.3, 0.0])  # a ball amid the top layer, tossed up between steps
        for _ in range(30):
            sim.step(10)
        runs.append(_outcome(sim, asleep, solver.lam.to_numpy(), solver.friction.to_numpy()))
        skipped.append((before, solver.still_steps - before))
    for run in runs[1:]:
        for a, b in zip(runs[0], run):
            np.testing.assert_array_equal(a, b)
    assert runs[0][0] == len(x) and np.all(runs[0][4] == AT_REST)  # asleep, woken, and asleep again
    assert skipped[0] == skipped[1] and skipped[0][0] > 20 and skipped[0][1] > 20 and skipped[2] == (0, 0)


@pytest.mark.skipif(not ON_CPU, reason="serial stepping runs on the CPU only")
@pytest.mark.parametrize("solver", ["jacobi", "gauss_seidel"])
def test_a_relisting_solver_lists_in_its_kernel_what_the_grid_lists(solver, monkeypatch):
    # a serial solver of a few balls (RELIST_MAX_BALLS) makes its lists in its kernel: the first
    # ones too, and those asked for between steps (balls moved), in a launch of no steps, without
    # the grid's kernels; they are the lists a build through the grid makes on the same positions,
    # pairs, links and carried impulses alike
    sc = tg.load_scene("break_shot", [f'contact.solver="{solver}"'])
    sim = tg.Simulation(sc)
    solver_ = sim.solver
    assert solver_.relists
    listed = []
    real = grid.list_neighbours
    monkeypatch.setattr(grid, "list_neighbours", lambda *a, **k: listed.append(1) or real(*a, **k))
    sim.step(40)
    assert solver_.rebuilds > 0 and len(solver_.pairs()) > 0
    solver_.invalidate()  # (as balls moved between steps would)
    solver_.ensure_lists(sim.state)
    assert listed == [] and int(solver_.flag.to_numpy()[0]) == 0
    names = ["upper", "first", "lower", "lower_first", "lam", "friction"]
    in_kernel = {name: getattr(solver_, name).to_numpy() for name in names}
    solver_.build(sim.state)  # the same positions, through the grid
    assert listed == [1]
    for name in names:
        np.testing.assert_array_equal(getattr(solver_, name).to_numpy(), in_kernel[name], err_msg=name)


@pytest.mark.parametrize(
    "name, steps",
    [
        ("break_shot", 600),
        ("newtons_cradle", 600),
        ("terrain_3d", 400),
        ("sleeping_column", 900),
        ("fast_into_pile", 40),
        ("boulder_into_pile", 40),
    ],
)
@pytest.mark.skipif(not ON_CPU, reason="serial stepping runs on the CPU only")
def test_serial_steps_equal_parallel_steps(name, steps):
    # few balls step serially, many steps per launch, with their lists rebuilt in the kernel by
    # testing every pair (CollisionSolver.serial); many balls take one parallel launch per step and
    # the hash grid. The two must be the same step: the same lists (the same distance test), the
    # same arithmetic per ball and the same order of every sum, so bit-identical results, whatever
    # the chunks of steps per launch. The scenes cover a break (fast balls: lists rebuilt nearly
    # every step), the cradle, a terrain with surface types and out-of-bounds balls, and balls
    # that fall asleep and are woken, and a ball shot at 60 m/s into a pile or a boulder five times
    # the size of the others dropped on it (the grid lists them apart: apart.APART_MAX). The
    # Jacobi sweeps' claim: the Gauss-Seidel sweeps meet the pairs in id order serially and by
    # columns in parallel, so there the two orders give different round-off
    v, r, m = None, None, None
    if name == "sleeping_column":
        sc = tg.load_scene("lab_vacuum", ["world.integrator=semi_implicit", "world.dt=0.001", "contact.e=0.3"])
        x = np.array([[0.0, 0.02 + 0.04 * i, 0.0] for i in range(10)] + [[0.0, 2.0, 0.0]])  # see the test above
    elif name == "fast_into_pile":
        sc, x = pile_scene(200)
        x = np.vstack([x, [x[:, 0].mean() - 0.05, x[:, 1].max() + 0.1, x[:, 2].mean() + 0.03]])
        v = np.zeros_like(x)
        v[-1] = [5.0, -60.0, 0.0]
    elif name == "boulder_into_pile":
        sc, x = pile_scene(200)
        x = np.vstack([x, [x[:, 0].mean() - 0.01, x[:, 1].max() + 0.125, x[:, 2].mean() + 0.02]])
        v = np.zeros_like(x)
        v[-1] = [0.3, -2.0, 0.0]  # 5 mm above the pile's top at 2 m/s: it lands within three steps
        r = np.full(len(x), 0.02)
        r[-1] = 0.1
        m = sc.ball.mass * (r / 0.02) ** 3
    else:
        sc, x = tg.load_scene(name), None
    sc = dataclasses.replace(sc, contact=dataclasses.replace(sc.contact, solver="jacobi"))
    runs = []
    for serial in (True, False):
        sim = tg.Simulation(sc, x=x, v=v, radius=r, mass=m) if x is not None else tg.Simulation(sc)
        sim.solver = CollisionSolver(sim.model, serial=serial)
        done, asleep = 0, 0
        for chunk in (1, 2, 37, 410, steps):  # launches of one, a few and many steps
            k = min(chunk, steps - done)
            sim.step(k)
            if name in ("fast_into_pile", "boulder_into_pile") and done == 0:
                assert sim.solver.n_apart == 1  # the first build listed the shot ball or the boulder apart
            done += k
            asleep = max(asleep, int(np.sum(sim.status == AT_REST)))
        runs.append(_outcome(sim, asleep, sim.state.apex.to_numpy(), sim.state.t_land.to_numpy()))
    serial, parallel = runs
    for a, b in zip(serial, parallel):
        np.testing.assert_array_equal(a, b)
    assert serial[-1] > 1  # the lists were rebuilt in the kernel
    if name == "sleeping_column":
        assert serial[0] == 10 and np.any(serial[4] != AT_REST)  # the column slept, the falling ball woke it


@pytest.mark.slow
def test_a_step_split_into_launches_equals_the_unrolled_step(monkeypatch):
    # a parallel step of more than solver.UNROLL_MAX_SWEEPS sweeps is split into launches: the
    # free flight, warm start and first sweeps, more sweeps, the last sweep (solver.sweep_launches).
    # The loops and the arithmetic are those of the unrolled step, in the same order, so the
    # results must be the same bit for bit: here a boulder dropped on a pile (impacts, a ball
    # listed apart, lists rebuilt) with the default 4 sweeps, once in one launch and once in two
    from ti_golf.solvers import collide
    from ti_golf.solvers import jacobi as solver

    assert solver.sweep_launches(8) == [(True, 4, False), (False, 3, True)]
    assert solver.sweep_launches(9) == [(True, 4, False), (False, 4, False), (False, 0, True)]
    sc, x = pile_scene(300)
    sc = dataclasses.replace(sc, contact=dataclasses.replace(sc.contact, solver="jacobi"))  # (their launches)
    x = np.vstack([x, [x[:, 0].mean() - 0.01, x[:, 1].max() + 0.125, x[:, 2].mean() + 0.02]])
    v = np.zeros_like(x)
    v[-1] = [0.3, -2.0, 0.0]
    r = np.full(len(x), 0.02)
    r[-1] = 0.1
    m = sc.ball.mass * (r / 0.02) ** 3
    kernel, launches = collide.collision_step, []

    def counted(*args):
        launches.append(args[-3:])  # (warm, sweeps, last)
        return kernel(*args)

    monkeypatch.setattr(collide, "collision_step", counted)
    runs = []
    for unroll_max in (4, 2):
        monkeypatch.setattr(solver, "UNROLL_MAX_SWEEPS", unroll_max)
        launches.clear()
        sim = tg.Simulation(sc, x=x, v=v, radius=r, mass=m)
        sim.solver = CollisionSolver(sim.model, serial=False)
        sim.step(40)
        assert launches == 40 * ([(True, 3, True)] if unroll_max == 4 else [(True, 2, False), (False, 1, True)])
        st = sim.state
        runs.append((sim.x, sim.v, sim.w, st.status.to_numpy(), st.rest_time.to_numpy(), sim.solver.rebuilds))
    assert runs[0][-1] > 1  # the lists were rebuilt
    assert np.abs(runs[0][1]).max() > 0.1  # and the boulder hit the pile: balls move
    for a, b in zip(*runs):
        np.testing.assert_array_equal(a, b)


@SERIAL_OR_PARALLEL
def test_balls_moved_between_steps_collide_in_the_next_step(serial):
    # assigning sim.x moves balls outside a step: the neighbour lists built before must not hide a
    # pair that now touches. Ball 1 is put 0.1 mm from ball 0, closing at 1 m/s, so it meets ball 0
    # within the next 0.5 ms step; with e = 1 and equal masses they exchange velocities (B.9) in it
    sim = tg.Simulation(scene("contact.e=1"), x=[[0.0, 1.0, 0.0], [10.0, 1.0, 0.0]])
    sim.solver = CollisionSolver(sim.model, serial=serial)
    sim.step(3)  # lists built with the balls 10 m apart: no pair
    sim.x = [[0.0, 1.0, 0.0], [0.0401, 1.0, 0.0]]
    sim.v = [[0.0, 0.0, 0.0], [-1.0, 0.0, 0.0]]
    sim.step(1)
    np.testing.assert_allclose(sim.v, [[-1.0, 0, 0], [0, 0, 0]], atol=1e-12)


@SERIAL_OR_PARALLEL
@pytest.mark.parametrize("gap", [0.003, 0.006, 0.0095])
def test_a_fast_ball_meets_a_ball_it_reaches_within_the_step(serial, gap):
    # Ball 0 flies at 20 m/s at ball 1, which rests `gap` away: 10 mm of flight per 0.5 ms step,
    # more than the 2 mm skin, so the lists built before the step must list the pair by its closing
    # speed (grid.pair_reach), or the balls meet only a step later, after flying into each other.
    # Contact is speculative (gap + h·v_n < 0, B.5–B.9 on the whole step): with e = 1 and equal
    # masses they exchange velocities in the first step, ball 0 stays where it was and ball 1
    # moves h·20 m/s = 10 mm; they never overlap.
    r = tg.load_scene("lab_vacuum").ball.radius
    sim = tg.Simulation(scene("contact.e=1"), x=[[0.0, 1.0, 0.0], [2 * r + gap, 1.0, 0.0]], v=[[20.0, 0, 0], [0, 0, 0]])
    sim.solver = CollisionSolver(sim.model, serial=serial)
    x0 = sim.x.copy()
    sim.step(1)
    np.testing.assert_allclose(sim.v, [[0, 0, 0], [20.0, 0, 0]], rtol=0, atol=1e-12)
    np.testing.assert_allclose(sim.x - x0, [[0, 0, 0], [0.5e-3 * 20.0, 0, 0]], rtol=0, atol=1e-12)
    sim.step(10)
    assert sim.deepest_overlap() is None


def _kinetic_energy(sim):
    m, r = sim.model.mass_np, sim.model.radius_np
    return 0.5 * (m * (sim.v**2).sum(axis=1)).sum() + 0.5 * (0.4 * m * r**2 * (sim.w**2).sum(axis=1)).sum()


def _binary_impact(v, a, b, n):
    """B.9 for equal masses with e = 1, μ = 0 between balls a and b along the unit normal n: they
    exchange their velocity components along n."""
    u = np.dot(v[a] - v[b], n)
    v[a] -= u * n
    v[b] += u * n


@SERIAL_OR_PARALLEL
def test_simultaneous_impacts_are_taken_one_at_a_time(serial):
    # Ball 0 at v = 1 m/s touches balls 1 and 2, which touch each other, at ±30° from its path
    # (e = 1, μ = 0). A Jacobi sweep that gave ball 0 both jolts of B.9 at once, each as if the
    # other ball were not there, stopped it at v − 2·v·cos² 30° = −v/2 and sent the others off at
    # v·cos 30°: 75 % more kinetic energy than it brought. A sweep takes one impact per ball
    # (pairs.matched), so the balls meet as if a moment apart: ball 0 and one of the two first,
    # B.9 along their line of centres, then, in the next sweep, ball 0 and the other (still
    # approaching). Which goes first is fixed by the lists' order; either way kinetic energy is
    # kept to round-off, as in every binary impact with e = 1, and so is momentum.
    r = tg.load_scene("lab_vacuum").ball.radius
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    x = np.array([[0.0, 1.0, 0.0], [2 * r * c, 1.0, -2 * r * s], [2 * r * c, 1.0, 2 * r * s]])
    v0 = np.array([[1.0, 0, 0], [0, 0, 0], [0, 0, 0]])
    sim = tg.Simulation(scene("contact.e=1", "contact.k_p=0", "contact.v_bounce=0", "contact.solver=jacobi"), x=x, v=v0)
    sim.solver = CollisionSolver(sim.model, serial=serial)
    e0 = _kinetic_energy(sim)
    sim.step(5)
    orders = []
    for first, second in ((1, 2), (2, 1)):
        v = v0.copy()
        for b in (first, second):
            _binary_impact(v, 0, b, (x[b] - x[0]) / (2 * r))
        orders.append(v)
    assert min(np.abs(sim.v - v).max() for v in orders) < 1e-12, (sim.v, orders)
    np.testing.assert_allclose(sim.v.sum(axis=0), [1.0, 0, 0], rtol=0, atol=1e-15)
    assert _kinetic_energy(sim) == pytest.approx(e0, rel=1e-12)


def test_gauss_seidel_simultaneous_impacts_bounce_by_poisson_and_add_no_energy():
    # the three balls above under the Gauss–Seidel sweeps: the sweeps stop the impact as one
    # inelastic group (its compression), then the restitution pass gives each contact at most e
    # times its compressing impulse back (Poisson's restitution; and at most −e·v_n0, Newton's),
    # so the energy left is at most the inelastic impact's plus e² of what the compression took,
    # KE(0) + e²·(KE0 − KE(0)) ≤ KE0, and with e = 1 all of it. Each contact's rebound −e·v_n0
    # met in turn (Newton's law alone) left the three with 1.29 times the energy at e = 1 and 1.13
    # at e = 0.9. To the sweeps' convergence (four sweeps: 1e-4)
    r = tg.load_scene("lab_vacuum").ball.radius
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    x = np.array([[-0.05, 1.0, 0.0], [2 * r * c, 1.0, -2 * r * s], [2 * r * c, 1.0, 2 * r * s]])  # (5 cm apart)
    ratios = {}
    for e in (0.0, 0.5, 0.9, 1.0):
        sc = scene(f"contact.e={e}", "contact.k_p=0", "contact.v_bounce=0", 'contact.solver="gauss_seidel"')
        sim = tg.Simulation(sc, x=x, v=[[1.0, 0, 0], [0, 0, 0], [0, 0, 0]])
        e0 = _kinetic_energy(sim)
        sim.run(t=0.15)
        np.testing.assert_allclose(sim.v.sum(axis=0), [1.0, 0, 0], rtol=0, atol=1e-12)  # momentum
        assert sim.v[1, 2] == pytest.approx(-sim.v[2, 2], abs=1e-3), sim.v  # symmetric, as the balls are
        ratios[e] = _kinetic_energy(sim) / e0
    for e in (0.5, 0.9, 1.0):
        assert ratios[0.0] < ratios[e] <= ratios[0.0] + e**2 * (1.0 - ratios[0.0]) + 1e-3, ratios
    assert ratios[1.0] == pytest.approx(1.0, abs=1e-3)  # elastic: the energy kept


@SERIAL_OR_PARALLEL
@pytest.mark.parametrize("wall_deg", [30, 60])
def test_a_ball_dropped_into_a_v_of_planes_bounces_straight_back_at_e_times_its_speed(serial, wall_deg):
    # a ball falling along the middle of a V of two planes inclined ±wall_deg meets both at once:
    # by symmetry it must come straight back at e times its speed. The planes' rebounds −e·v_n0 met
    # in turn (Newton's law) sent it off sideways with 1.55 times its energy (walls at 30°, e = 1)
    # or 0.35 times (60°). Now the restitution pass meets a ball's impact planes again, in rounds,
    # until each gives back e times its approach (surfaces.joint_plane_bounce): it comes back
    # straight, whatever the sweeps, which Poisson's restitution (e times each compression) would
    # give too; to the rounds' convergence and the f32 rounding of the impulses they keep (F32)
    s, c = np.sin(np.radians(wall_deg)), np.cos(np.radians(wall_deg))
    for e in (0.5, 1.0):
        for sweeps, tol in ((4, F32), (16, F32)):
            sc = scene(f"contact.e={e}", "contact.v_bounce=0", f"contact.iterations={sweeps}")
            sc = dataclasses.replace(sc, planes=(Plane((0, 0, 0), (s, c, 0)), Plane((0, 0, 0), (-s, c, 0))))
            sim = tg.Simulation(sc, x=[[0.0, sc.ball.radius / c + 0.0123, 0.0]], v=[[0.0, -2.0, 0.0]])
            sim.solver = CollisionSolver(sim.model, serial=serial)
            sim.run(t=0.05)  # (the bounce after 12 ms or so)
            np.testing.assert_allclose(sim.v[0], [0.0, 2.0 * e, 0.0], rtol=0, atol=tol * 2.0 * e)


@SERIAL_OR_PARALLEL
@pytest.mark.parametrize("e", [0.5, 1.0])
def test_a_ball_meeting_a_wedge_of_planes_at_once_leaves_each_at_e_times_its_approach(serial, e):
    # a lopsided wedge (walls at 20° and 55°), the ball aimed off its middle and along its crease,
    # placed so that it reaches both walls at the same moment: each sends it off at e times its
    # approach (v'·n_k = −e·v0·n_k), so the velocity in the walls' plane turns back scaled by e and
    # the part along the crease (n1 × n2 = z) is kept; frictionless, e = 1 keeps the energy. Met once
    # each in turn (Newton's law), the second wall's rebound undid part of the first's
    n1 = np.array([np.sin(np.radians(20)), np.cos(np.radians(20)), 0.0])
    n2 = np.array([-np.sin(np.radians(55)), np.cos(np.radians(55)), 0.0])
    v0 = np.array([0.3, -2.0, 0.5])
    sc = scene(f"contact.e={e}", "contact.v_bounce=0")
    R, t_hit = sc.ball.radius, 0.01225  # (between two steps of 0.5 ms)
    # the centre whose gap to each wall, x·n_k − R, closes at t_hit: x·n_k = R − t_hit·v0·n_k
    xy = np.linalg.solve(np.array([n1[:2], n2[:2]]), [R - t_hit * v0 @ n1, R - t_hit * v0 @ n2])
    sc = dataclasses.replace(sc, planes=(Plane((0, 0, 0), tuple(n1)), Plane((0, 0, 0), tuple(n2))))
    sim = tg.Simulation(sc, x=[[xy[0], xy[1], 0.0]], v=[v0])
    sim.solver = CollisionSolver(sim.model, serial=serial)
    sim.run(t=0.03)
    expected = np.array([-e * v0[0], -e * v0[1], v0[2]])
    np.testing.assert_allclose(sim.v[0], expected, rtol=0, atol=F32 * np.linalg.norm(v0))


def test_a_fast_ball_dropped_onto_a_plastic_pile_does_not_bounce_back():
    # A ball at 70 m/s onto a settled pile with e = 0: every impact is plastic, so the ball must not
    # come back out. Its speculative contacts reach 7 cm (h·v) into the pile, a dozen balls at once;
    # with each of them taking the whole jolt, the ball left the pile upwards at 61 m/s within a step
    # and the system kept all its kinetic energy. Kinetic energy may only fall (gravity's work over
    # the few millimetres the balls move is below 0.1 % of it). (Taking one impact per sweep, the
    # ball ploughs about a diameter into the pile in its first step and the position projection
    # pushes it back up; it ends rolling on the surface.)
    pile, x = pile_scene(2048)
    top = x[:, 1].max()
    x = np.vstack([x, [[x[:, 0].mean(), top + 0.1, x[:, 2].mean()]]])  # above the gap between four balls
    v = np.zeros_like(x)
    v[-1] = [0.0, -70.0, 0.0]
    sim = tg.Simulation(pile, x=x, v=v, track=False)
    e0 = _kinetic_energy(sim)
    for _ in range(30):
        sim.step(1)
        assert _kinetic_energy(sim) < e0
        assert sim.v[-1, 1] < 0.05 * 70.0
    assert _kinetic_energy(sim) < 0.05 * e0


def test_lists_that_would_exhaust_memory_stop_the_run_and_name_the_ball(monkeypatch):
    # The neighbour table is as wide as the longest upper list. Balls at 2,000 m/s (2 m per 1 ms
    # step) above a pile have every ball of it within reach: more of them than apart.APART_MAX (a few
    # are listed apart, and own none of their pairs), so every ball's row would widen to as many
    # entries as there are such balls, and every pair be kept: with a million balls that is hundreds
    # of gigabytes. The solver must stop with a SimulationError that names a ball and its speed
    # before it allocates tables larger than half the memory available; here "available" is made
    # small, and the same run without that limit steps on.
    import ti_golf.solvers.solver as solver_module

    pile, x = pile_scene(400)
    fast = apart.APART_MAX + 8
    top = [x[:, 0].mean(), x[:, 1].max() + 0.1, x[:, 2].mean()]
    k = np.arange(fast)  # (in the 0.2 m bin: rows of five touching balls, 25 to a layer)
    layer = top + np.stack([0.04 * (k % 5 - 2), 0.05 * (k // 25), 0.04 * ((k // 5) % 5 - 2)], axis=1)
    x = np.vstack([x, layer])
    v = np.zeros_like(x)
    v[400:] = [0.0, -2000.0, 0.0]
    narrow = solver_module.table_bytes(len(x), 8, 8 * len(x), True)  # lists of eight, not the 400 in reach
    monkeypatch.setattr(solver_module, "available_memory", lambda: 2 * narrow)
    sim = tg.Simulation(pile, x=x, v=v, track=False)
    sim.solver = CollisionSolver(sim.model, serial=False)
    with pytest.raises(tg.SimulationError, match=r"Ball 400 reaches farthest .*speed 2000 m/s") as err:
        sim.step(1)
    assert err.value.balls == [400]
    monkeypatch.setattr(solver_module, "available_memory", lambda: None)  # memory unknown: no limit
    sim.step(1)
    assert sim.solver.capacity >= fast


def test_balls_all_alike_share_one_radius_and_one_mass():
    # the model keeps one radius and one mass when every ball has the same (8 bytes per ball each
    # in f64; docs, performance: "Where the f64 bytes go"), and one per ball when they vary; the kernels read
    # both through types.of_ball, and a storage reorder gathers only the per-ball ones
    pile, x = pile_scene(50)
    alike = tg.Simulation(pile, x=x, track=False)
    assert alike.model.radius.shape == (1,) and alike.model.mass.shape == (1,)
    assert alike.model.per_ball() == []
    r = np.full(len(x), 0.02)
    r[7] = 0.019
    mixed = tg.Simulation(pile, x=x, radius=r, track=False)
    assert mixed.model.radius.shape == (50,) and mixed.model.mass.shape == (1,)
    assert mixed.model.per_ball() == ["radius"]
    np.testing.assert_array_equal(mixed.model.radius.to_numpy(), r)


@pytest.mark.parametrize("method", ["jacobi", "gauss_seidel"])
def test_the_memory_guard_counts_the_bytes_the_pair_tables_take(method):
    # table_bytes is the memory guard's estimate (above) and the performance page's byte count: it must
    # match the tables the solver allocates, whatever they keep (per upper-list entry a neighbour;
    # per pair its link in the other ball's lower list, its resting impulse and its row of the
    # sweep's table, the inverse distance and gap, and under Jacobi the impulse too, in the float
    # type; under Gauss–Seidel that row in f32, with room for the friction a rebuild stashes, and
    # its friction impulse, one table that a rebuild carries it into from the stash).
    import ti_golf.solvers.solver as solver_module

    x, _ = _random_sets()["clustered"]
    sc = scene("world.gravity=[0,-9.81,0]", "world.ground=true", "contact.mu=0.3", f"contact.solver={method}")
    sim = tg.Simulation(sc, x=x[:400] * 0.3 + [0, 0.2, 0], radius=np.full(400, 0.02), track=False)
    sim.solver = CollisionSolver(sim.model, serial=False)
    sim.step(1)
    sim.solver.invalidate()
    sim.step(1)  # a rebuild
    s = sim.solver
    assert s.rebuilds == 2 and s.impulse.shape[1] == (3 if method == "gauss_seidel" else 5)
    assert s.impulse.to_numpy().dtype == (np.float32 if method == "gauss_seidel" else np.float64)
    tables = (s.upper, s.lower, s.lam, s.impulse) + ((s.friction,) if s.gauss_seidel else ())
    allocated = sum(a.to_numpy().nbytes for a in tables)
    assert s.capacity >= 3 and s.pair_capacity >= len(x[:400])
    assert allocated == solver_module.table_bytes(400, s.capacity, s.pair_capacity, s.gauss_seidel)


def test_a_build_past_the_vulkan_loop_cap_stops_the_run_and_names_the_ball():
    # Taichi's Vulkan backend stops a thread's loops after grid.LOOP_CAP iterations without a word.
    # There the cells are sized for the biggest ball, and around a boulder in a large pile they hold
    # more balls than that: listing one ball's neighbours would stop short and lose pairs. The grid
    # bounds each thread's iterations (candidates, the 18 bucket ranges and the sorted insertions'
    # shifts), and the solver stops the run with a SimulationError naming the ball that sizes the
    # cells. Here the cap is set low: the boulder's thread passes it (it tests all 401 balls on a
    # CPU, and on a GPU every thread does), the lattice's threads (about 30 candidates) do not.
    pile, x = pile_scene(400)
    x = np.vstack([x, [[x[:, 0].mean(), x[:, 1].max() + 0.3, x[:, 2].mean()]]])
    r = np.full(len(x), 0.02)
    r[-1] = 0.2
    sim = tg.Simulation(pile, x=x, radius=r, track=False)
    sim.solver = CollisionSolver(sim.model, serial=False)
    assert sim.solver.loop_cap == (grid.LOOP_CAP if tg.init().arch == "vulkan" else None)
    sim.solver.loop_cap = 300
    with pytest.raises(
        tg.SimulationError, match=r"Vulkan backend stops .* Ball 400 reaches farthest \(radius 0.2 m"
    ) as err:
        sim.step(1)
    assert err.value.balls == [400]
    alone = tg.Simulation(pile, x=x[:-1], track=False)
    alone.solver = CollisionSolver(alone.model, serial=False)
    alone.solver.loop_cap = 300
    alone.step(2)
    assert alone.solver.rebuilds >= 1


def test_the_break_shot_adds_no_kinetic_energy():
    # The cue ball reaches the rack of 15 touching balls after about 165 ms; the break is a cascade
    # of simultaneous impacts (e = 0.92, friction on the table): it may only lose kinetic energy
    # (translation and spin). With every impact's whole jolt at once, it left the 16 balls with 5.8
    # times the energy the cue ball brought. With e = 1, no friction and no rolling resistance the
    # binary impacts keep it (to 1e-3: the rack's resting contacts and its position projection).
    sim = tg.Simulation.from_scene("break_shot")
    sim.step(300)  # 150 ms: the cue ball rolls towards the rack
    e0 = _kinetic_energy(sim)
    sim.step(40)
    assert (np.linalg.norm(sim.v, axis=1) > 0.05).sum() >= 14  # the break happened: the rack flies apart
    assert _kinetic_energy(sim) < e0
    elastic = tg.Simulation.from_scene("break_shot", ["contact.e=1", "contact.mu=0", "contact.mu_roll=0"])
    elastic.step(300)
    e0 = _kinetic_energy(elastic)
    elastic.step(40)
    assert _kinetic_energy(elastic) == pytest.approx(e0, rel=1e-3)


@SERIAL_OR_PARALLEL
def test_a_fast_ball_meets_a_wall_it_reaches_within_the_step(serial):
    # A step skips the planes of a ball too far from all of them to reach one at its speed
    # (collide.plane_clearance). Ball 0 is 10 mm from the wall of a three-plane box and flies at it
    # at 30 m/s: it gets there within the 0.5 ms step (15 mm of flight). The wall jolts it by
    # −(1 + e)·v_n (B.11, m_red = 1) and the step is split at the time of impact, 2/3 of the way:
    # it ends 10 − (1/3)·0.5 ms·15 m/s = 2.5 mm from the wall. Ball 1, 20 mm away, flies on.
    sc = dataclasses.replace(
        scene("contact.e=0.5", "contact.v_bounce=0"),
        planes=(Plane((0.5, 0, 0), (-1, 0, 0)), Plane((0, -5, 0), (0, 1, 0)), Plane((0, 0, -5), (0, 0, 1))),
    )
    wall = 0.5 - sc.ball.radius  # where a centre touches the wall
    sim = tg.Simulation(sc, x=[[wall - 0.010, 1.0, 0.0], [wall - 0.020, 2.0, 0.0]], v=[[30.0, 0, 0], [30.0, 0, 0]])
    sim.solver = CollisionSolver(sim.model, serial=serial)
    sim.step(1)
    np.testing.assert_allclose(sim.v, [[-15.0, 0, 0], [30.0, 0, 0]], rtol=0, atol=1e-12)
    np.testing.assert_allclose(sim.x[:, 0] - wall, [-0.0025, -0.005], rtol=0, atol=1e-12)


@SERIAL_OR_PARALLEL
def test_a_ball_knocked_into_a_wall_from_beyond_the_lists_reach_still_meets_it(serial, monkeypatch):
    # The lists' build gives a row of surface impulses only to the balls that may reach a plane
    # before the next build (surfaces.list_surfaces: within the skin, 2 mm here, or 2h·v_max, the
    # farthest the fastest ball, or one it knocks on, flies in a step); the serial solver gives
    # every ball one. Here the build is made to foresee the skin alone, as if no ball were moving
    # (v_max = 0): ball 1 rests 2.5 mm from the wall and ball 0 is 46 mm from it, no row for
    # either. Ball 0 hits ball 1 at 30 m/s (e = 1, μ = 0, equal masses: B.9 passes on all of it);
    # in the same 0.5 ms step ball 1 would fly 15 mm, far into the wall, which sends it back at
    # 30 m/s (B.11), and the next sweep passes that back to ball 0. The wall must act within the
    # step without a row, exactly as with one: ball 0 leaves at −30 m/s, ball 1 stays 2.5 mm from
    # the wall.
    import ti_golf.solvers.solver as solver_module

    real = solver_module.list_surface_rows
    monkeypatch.setattr(solver_module, "list_surface_rows", lambda s, state, carry, v_max: real(s, state, carry, 0.0))
    sc = dataclasses.replace(
        scene("contact.e=1", "contact.mu=0", "contact.mu_roll=0", "contact.v_bounce=0", "contact.solver=jacobi"),
        planes=(Plane((0.5, 0, 0), (-1, 0, 0)), Plane((0, -5, 0), (0, 1, 0)), Plane((0, 0, -5), (0, 0, 1))),
    )
    r = sc.ball.radius
    wall = 0.5 - r  # where a centre touches the wall
    sim = tg.Simulation(
        sc, x=[[wall - 0.0035 - 2 * r, 1.0, 0.0], [wall - 0.0025, 1.0, 0.0]], v=[[30.0, 0, 0], [0, 0, 0]]
    )
    sim.solver = CollisionSolver(sim.model, serial=serial)
    sim.step(1)
    assert sim.model.dt == 0.0005 and sim.solver.skin == pytest.approx(0.002)
    rows = np.diff(sim.solver.surface_start.to_numpy())
    assert rows.tolist() == ([1, 1] if serial else [0, 0])
    np.testing.assert_allclose(sim.v, [[-30.0, 0, 0], [0, 0, 0]], rtol=0, atol=1e-12)
    np.testing.assert_allclose(sim.x[1, 0] - wall, -0.0025, rtol=0, atol=1e-12)


def test_only_the_balls_within_reach_of_a_surface_keep_a_row_of_surface_impulses():
    # A lattice pile at rest in a bin: the balls of its outer layers touch the floor or a wall,
    # every other ball is at least a diameter from all five planes. Only the first have a row of
    # surface impulses (surfaces.list_surfaces: a plane within the skin; at rest 2h·|v| is 0), and
    # the tables hold those rows (a quarter more room at most, see surface_rows.ROW_ROOM) rather
    # than one per ball; a rebuild gives the same rows, with the resting impulses carried over.
    sc, x = pile_scene(2000)
    sim = tg.Simulation(sc, x=x, track=False)
    sim.solver = CollisionSolver(sim.model, serial=False, reorder=False)
    sim.step(5)
    s = sim.solver
    gaps = np.stack([(x - p.point) @ np.asarray(p.normal) for p in sc.planes], axis=1) - 0.02
    near = gaps.min(axis=1) < s.skin
    assert 600 < near.sum() < 800
    start = s.surface_start.to_numpy()
    np.testing.assert_array_equal(np.diff(start) > 0, near)
    assert near.sum() <= s.surface_impulse.shape[0] <= near.sum() * 5 // 4 + 1 and s.surface_impulse.shape[1] == 5
    bottom = gaps[:, 0] < 1e-9  # the bottom layer, on the floor (plane 0), which holds it up
    floor = s.surface_impulse.to_numpy()[start[:-1][near], 0, 0]  # λ on the floor (the rows of the balls near a plane)
    assert np.all(floor[bottom[near]] > 0) and np.all(floor[~bottom[near]] == 0)
    s.invalidate()
    sim.step(1)
    start = s.surface_start.to_numpy()
    np.testing.assert_array_equal(np.diff(start) > 0, near)
    assert np.all(s.surface_impulse.to_numpy()[start[:-1][bottom], 0, 0] > 0)  # (every bottom ball has a row)


@SERIAL_OR_PARALLEL
def test_deepest_overlap_names_the_pair_on_the_current_positions(serial):
    # overlap Δx = r_a + r_b − |x_a − x_b| (B.18), also as a fraction of the smaller radius. Balls 0
    # and 1 (r = 2 and 3 cm, 4.5 cm apart) overlap by 5 mm, 25 % of 2 cm; balls 2 and 3 by 0.5 mm,
    # 2.5 %; ball 4 is alone
    x = [[0.0, 1.0, 0.0], [0.045, 1.0, 0.0], [0.2, 1.0, 0.0], [0.2, 1.0, 0.0395], [5.0, 1.0, 0.0]]
    sim = tg.Simulation(scene(), x=x, radius=[0.02, 0.03, 0.02, 0.02, 0.02])
    sim.solver = CollisionSolver(sim.model, serial=serial)
    d = sim.deepest_overlap()  # before any step: measured on lists built for these positions
    assert (d.i, d.j) == (0, 1)
    assert d.depth == pytest.approx(0.005, rel=1e-12) and d.fraction == pytest.approx(0.25, rel=1e-12)
    sim.step(2)
    sim.x = [*x[:4], [0.2, 1.0, -0.028]]  # ball 4 moved into ball 2 between steps: 12 mm, 60 %
    d = sim.deepest_overlap()
    assert (d.i, d.j) == (2, 4) and d.fraction == pytest.approx(0.6, rel=1e-12)
    sim.x = [[10.0 * k, 1.0, 0.0] for k in range(5)]
    assert sim.deepest_overlap() is None


def _deepest_by_every_pair(x, r):
    """(i, j, depth [m]) of the pair that overlaps most as a fraction of the smaller radius, over
    every pair of balls (an O(n²) search independent of the neighbour lists), or None."""
    i, j = np.triu_indices(len(x), 1)
    depth = r[i] + r[j] - np.linalg.norm(x[i] - x[j], axis=1)
    k = int(np.argmax(depth / np.minimum(r[i], r[j])))
    return (int(i[k]), int(j[k]), float(depth[k])) if depth[k] > 0 else None


@SERIAL_OR_PARALLEL
@pytest.mark.parametrize("solver", ["jacobi", "gauss_seidel"])
def test_deepest_overlap_after_steps_measures_the_pairs_the_lists_may_miss(serial, solver, monkeypatch):
    # a 3×3×3 lattice of balls (r = 2 cm, 1 cm apart) moving together at 15 m/s, 7.5 mm a 0.5 ms
    # step, and one ball 0.5 mm into a corner ball: after three steps new lists are due (each ball
    # has used 37.5 mm, its move plus 2h·|v|: more than the 2 mm skin, and more than a search
    # through the grid covers, 0.99 of a cell less the radius), but no two balls have closed on
    # each other, so the lists still hold every overlapping pair and measuring builds none
    lattice = 0.05 * np.stack(np.meshgrid(*[np.arange(3)] * 3, indexing="ij"), -1).reshape(-1, 3)
    x = np.vstack([lattice, lattice[26] + [0.0395, 0.0, 0.0]]) + [0.0, 2.0, 0.0]
    sim = tg.Simulation(scene(f"contact.solver={solver}"), x=x, v=np.tile([0.0, -15.0, 0.0], (len(x), 1)))
    sim.solver = solver_ = CollisionSolver(sim.model, serial=serial)
    sim.step(3)
    assert solver_.lists_due and (3 + 2) * 15.0 * sim.model.dt > stale.SEARCHED * solver_.cell - 0.02
    builds = solver_.rebuilds
    d = sim.deepest_overlap()
    assert solver_.rebuilds == builds
    assert (d.i, d.j, d.depth) == _deepest_by_every_pair(sim.x, sim.model.radius_np)
    assert (d.i, d.j) == (26, 27)
    # ball 0 shifted 15 mm, into ball 9, as a step could move it (no edit between steps that would
    # ask for new lists): now a pair may be missing, ball 0's with any ball, and those are measured
    # without a build; with room for none of them, the lists are built
    x = sim.x
    x[0] = x[9] - [0.035, 0.0, 0.0]
    sim.state.write("x", x)
    d = sim.deepest_overlap()
    assert solver_.rebuilds == builds
    assert (d.i, d.j, d.depth) == _deepest_by_every_pair(x, sim.model.radius_np) and (d.i, d.j) == (0, 9)
    monkeypatch.setattr(stepping, "MOVED_PAIRS_MAX", len(x) - 1)
    d = sim.deepest_overlap()
    assert solver_.rebuilds == builds + 1
    assert (d.i, d.j, d.depth) == _deepest_by_every_pair(x, sim.model.radius_np)


@pytest.mark.slow
@SERIAL_OR_PARALLEL
@pytest.mark.parametrize("solver", ["jacobi", "gauss_seidel"])
def test_measuring_overlaps_does_not_change_the_run(serial, solver):
    # deepest_overlap builds the lists when they are stale; the next step must then be the step it
    # would have been (same lists, same carried impulses, friction's included): compared bit for bit
    # on a gas under gravity, the serial steps relisting in their kernel

    def run(measure):
        sim = _gas(
            scene(
                "contact.e=0.6",
                "contact.mu=0.4",
                "world.gravity=[0,-9.81,0]",
                "world.ground=true",
                f"contact.solver={solver}",
            ),
            n=200,
        )
        sim.solver = CollisionSolver(sim.model, serial=serial)
        for _ in range(20):
            if measure:
                sim.deepest_overlap()
            sim.step(10)
        return sim.x, sim.v, sim.w

    for a, b in zip(run(False), run(True)):
        np.testing.assert_array_equal(a, b)


@pytest.mark.slow
@pytest.mark.skipif(not ON_CPU, reason="serial stepping runs on the CPU only")
@pytest.mark.parametrize("solver", ["jacobi", "gauss_seidel"])
def test_serial_launches_between_builds_step_as_the_parallel_step(solver):
    # beyond RELIST_MAX_BALLS the serial launches stop where the lists must be rebuilt, which the
    # grid's kernels then do as for the parallel step; the Gauss–Seidel ones sweep the blocks of
    # columns colour after colour in one thread. Both are the parallel step bit for bit, while a
    # pour lands (every step a rebuild) on a boulder, which is listed apart (its pairs with balls
    # beyond the next column: the far pairs of colour.far_pairs)
    n = RELIST_MAX_BALLS + 200
    sc, _ = pit_scene(n, [f"contact.solver={solver}"])
    poured = tg.Simulation(sc)
    x, r = poured.x, np.full(n, float(poured.model.radius_np.max()))
    x[0], r[0] = (x[:, 0].mean(), 0.1, x[:, 2].mean()), 0.05  # a boulder on the floor, under the pour
    runs = []
    for serial in (True, False):
        sim = tg.Simulation(sc, x=x, v=poured.v, radius=r)
        sim.solver = CollisionSolver(sim.model, serial=serial)
        assert not sim.solver.relists
        far = 0
        for _ in range(6):
            sim.run(t=0.05)
            far = max(far, sim.solver.far_owners)
        runs.append((sim.x, sim.v, sim.w, sim.solver.rebuilds, sim.solver.still_steps, far))
    (xs, vs, ws, rebuilds, still, far), parallel = runs
    for a, b in zip((xs, vs, ws), parallel[:3]):
        np.testing.assert_array_equal(a, b)
    assert rebuilds == parallel[3] > 100 and still == parallel[4]
    if solver == "gauss_seidel":
        assert far == parallel[5] > 0


def test_runs_are_deterministic():
    # the parallel step, whose threads may take the balls in any order (a serial one takes them in one)
    def run():
        sim = _gas(scene("contact.e=0.6", "contact.mu=0.4", "world.gravity=[0,-9.81,0]", "world.ground=true"), n=800)
        sim.solver = CollisionSolver(sim.model, serial=False)
        sim.run(t=0.3)
        return sim.x, sim.v, sim.w

    a, b = run(), run()
    for u, v in zip(a, b):
        np.testing.assert_array_equal(u, v)


def _pivot_scene(mu_roll: float, h: float, gravity: list[float] | None = None, e: float | None = None):
    """A scene in vacuum for the Gauss–Seidel sweeps' resistance to pivoting, semi-implicit at step ``h``."""
    world = {"integrator": "semi_implicit", "dt": h} | ({} if gravity is None else {"gravity": gravity})
    contact = {"mu": 0.4, "mu_roll": mu_roll, "solver": "gauss_seidel"} | ({} if e is None else {"e": e})
    return tg.load_scene(data={"air": {"rho": 0.0}, "world": world, "contact": contact})


@SERIAL_OR_PARALLEL
def test_a_ball_spinning_on_a_ball_slows_at_five_halves_mu_roll_g_over_r(serial):
    # reference: two touching balls resist pivoting on each other as a ball on the ground does, with
    # the torque μ_roll·N·R (N = mg, the top ball's weight): the top ball of a column of two, spun
    # about the vertical, slows at dω_y/dt = −(5/2)·μ_roll·g/R until it stops. The contact's
    # resting impulse is m·g·h every step, so the semi-implicit steps follow the line to round-off
    # and to the rounding of that impulse, kept in f32 between steps (2^-24 of each step's torque,
    # so of the spin lost); the bottom ball, held by the ground's larger resistance
    # (μ_roll·2mg·R), does not turn, and neither ball moves.
    mu_r, w0, h, R = 0.05, 30.0, 0.001, 0.02
    sc = _pivot_scene(mu_r, h)
    x0 = np.array([[0.0, R, 0.0], [0.0, 3.0 * R, 0.0]])
    sim = tg.Simulation(sc, x=x0, w=[[0.0, 0.0, 0.0], [0.0, w0, 0.0]], radius=R)
    sim.solver = CollisionSolver(sim.model, serial=serial)
    rate = 2.5 * mu_r * 9.81 / R
    sim.step(1)  # the first step meets the ground (the resting impulses start then)
    for _ in range(3):
        sim.step(100)
        lost = rate * sim.t
        np.testing.assert_allclose(sim.w[1, 1], w0 - lost, rtol=1e-12, atol=2.0**-24 * lost)
        np.testing.assert_array_equal(sim.w[0], 0.0)
    np.testing.assert_array_equal(sim.x, x0)
    sim.run(t=w0 / rate)
    np.testing.assert_array_equal(sim.w, 0.0)
    assert sim.counts()["at_rest"] == 2


@SERIAL_OR_PARALLEL
@pytest.mark.parametrize("closed", [0.5, 0.999, 1.001])
def test_a_plastic_pair_closing_its_gap_within_a_step_ends_touching(serial, closed):
    # reference: a perfectly plastic impact (B.9 with e = 0) of two equal balls leaves them
    # touching, both at the mean of their velocities. Here they start apart by a fraction
    # ``closed`` of what they close in one step, so the contact is met within the first step (the
    # second for 1.001): the sweeps close the gap exactly, and the next step stops the approach. The gap left is round-off
    # of positions near 1 m (1e-12 m); it was up to h·|v_a − v_b| (0.3–0.6 mm here) while the
    # restitution pass stopped such a pair before it touched.
    R, h, v_a, v_b = 0.02, 0.001, 0.5, -0.1
    gap = closed * (v_a - v_b) * h
    sc = _pivot_scene(0.0, h, gravity=[0.0, 0.0, 0.0], e=0.0)
    sim = tg.Simulation(sc, x=[[0.0, 1.0, 0.0], [2.0 * R + gap, 1.0, 0.0]], v=[[v_a, 0, 0], [v_b, 0, 0]], radius=R)
    sim.solver = CollisionSolver(sim.model, serial=serial)
    sim.step(10)
    np.testing.assert_allclose(sim.v[:, 0], 0.5 * (v_a + v_b), rtol=1e-12)
    assert sim.x[1, 0] - sim.x[0, 0] - 2.0 * R == pytest.approx(0.0, abs=1e-12)


@SERIAL_OR_PARALLEL
def test_two_balls_meeting_head_on_lose_relative_spin_and_keep_their_total_spin(serial):
    # reference: two equal balls (no gravity) meet head-on at v, plastically (e = 0), each spinning
    # about the line of their centres. Their contact takes the normal impulse λ = m_red·v with
    # m_red = m/2, and resists pivoting with opposite angular impulses ±μ_roll·λ·R about the normal
    # (the relative spin is never stopped here), so with I = ⅖mR² the relative spin falls by
    # 2·μ_roll·(m/2)·v·R/I = (5/2)·μ_roll·v/R, to the rounding of λ kept in f32 between steps (2^-24
    # of it), and the total spin, their angular momentum about the line, is kept to round-off
    mu_r, R, v, h = 0.05, 0.02, 0.05, 0.001
    sc = _pivot_scene(mu_r, h, gravity=[0.0, 0.0, 0.0], e=0.0)
    w0 = np.array([[10.0, 0.0, 0.0], [-4.0, 0.0, 0.0]])
    sim = tg.Simulation(
        sc, x=[[0.0, 1.0, 0.0], [2.0 * R + 0.5 * v * h, 1.0, 0.0]], v=[[v, 0, 0], [0, 0, 0]], w=w0, radius=R
    )
    sim.solver = CollisionSolver(sim.model, serial=serial)
    sim.step(10)
    np.testing.assert_allclose(sim.v[:, 0], 0.5 * v, rtol=1e-12)  # B.9 with e = 0
    relative = sim.w[0, 0] - sim.w[1, 0]
    lost = 2.5 * mu_r * v / R
    assert relative == pytest.approx((w0[0, 0] - w0[1, 0]) - lost, rel=1e-12, abs=2.0**-24 * lost)
    assert sim.w[:, 0].sum() == pytest.approx(w0[:, 0].sum(), abs=1e-12)
    np.testing.assert_array_equal(sim.w[:, 1:], 0.0)
