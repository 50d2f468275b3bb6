"""The Gauss–Seidel sweeps laid out by contact colours (``contact.layout = "contacts"``,
``ti_golf.solvers.contact_colour``): a valid, repeatable colouring of the listed pairs, and runs
that repeat bit for bit. The piles' figures with this layout are checked in test_piles.py."""

import json
import textwrap
from pathlib import Path

import background
import numpy as np
import pytest
from conftest import NO_VULKAN_BACKEND, ON_VULKAN

import ti_golf as tg
from ti_golf.errors import ConfigError
from ti_golf.solvers.contact_colour import COLOURS, OVERFLOW
from ti_golf.solvers.solver import CollisionSolver


def _scene(number: int, box: float, seed: int, e: float = 0.5):
    """``number`` balls dropped at random into a bin ``box`` [m] wide, with the contact colours."""
    return tg.load_scene(None, data=_scene_data(number, box, seed, e))


def _scene_data(number: int, box: float, seed: int, e: float = 0.5) -> dict:
    """The scene file's data of :func:`_scene`."""
    return {
        "description": "a dense random set",
        "world": {"dt": 0.001},
        "contact": {"solver": "gauss_seidel", "layout": "contacts", "e": e},
        "planes": [
            {"point": [0, 0, 0], "normal": [0, 1, 0]},
            {"point": [0, 0, 0], "normal": [1, 0, 0]},
            {"point": [box, 0, 0], "normal": [-1, 0, 0]},
            {"point": [0, 0, 0], "normal": [0, 0, 1]},
            {"point": [0, 0, box], "normal": [0, 0, -1]},
        ],
        "blocks": [
            {
                "kind": "random",
                "number": number,
                "box_min": [0.02, 0.02, 0.02],
                "box_max": [box - 0.02, 1.2, box - 0.02],
                "seed": seed,
            }
        ],
    }


def _colouring(sim) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(owner, other ball, colour) of each listed pair of ``sim``'s last build, and the pairs laid
    out colour by colour with the colours' starts."""
    solver = sim.solver
    first, upper = solver.first.to_numpy(), solver.upper.to_numpy()
    pairs = int(first[-1])
    owner = np.repeat(np.arange(sim.n), np.diff(first))
    other = upper[owner, np.arange(pairs) - first[owner]]
    tables = solver.colours.tables
    colour = tables["colour"].to_numpy()[:pairs]
    return np.stack([owner, other, colour], axis=1), tables["pairs"].to_numpy()[:pairs], tables["start"].to_numpy()


def _assert_valid(sim) -> None:
    _assert_valid_layout(*_colouring(sim))


def _assert_valid_layout(listed: np.ndarray, laid_out: np.ndarray, start: np.ndarray) -> None:
    assert len(listed) > 0
    # every pair coloured, exactly once in the layout, in the run of its colour
    assert np.all((listed[:, 2] >= 0) & (listed[:, 2] <= OVERFLOW))
    np.testing.assert_array_equal(np.sort(laid_out), np.arange(len(listed)))
    for c in range(COLOURS + 1):
        run = laid_out[start[c] : start[c + 1]]
        assert np.all(listed[run, 2] == c)
        assert np.all(np.diff(run) > 0), c  # in index order, whatever order the threads ran in
        if c < COLOURS:  # no two pairs of a colour share a ball
            balls = listed[run, :2].ravel()
            assert len(np.unique(balls)) == len(balls), c


@pytest.mark.parametrize("seed", [1, 2])
def test_colouring_of_a_dense_random_set_is_valid(seed):
    # 1,000 balls at random in a 0.3 m cube, overlapping one another: a ball holds a dozen pairs
    # or more, some balls more than the colours can take at once (the overflow set)
    x = np.random.default_rng(seed).uniform(0.02, 0.28, (1000, 3))
    sim = tg.Simulation(_scene(10, 0.3, seed), x=x)
    sim.run(steps=1)
    _assert_valid(sim)
    assert sim.solver.colours.sizes()[0] >= 8


# The dense random set on Vulkan (the GPU backend CI runs, in software), five steps: its colouring
# made and laid out on that backend, and the sweeps over it.
_VULKAN_COLOURS = textwrap.dedent("""
    import json
    import sys

    import numpy as np
    import ti_golf as tg

    if tg.init().arch != "vulkan":
        sys.exit(77)  # Taichi fell back to another backend: nothing to compare
    scene = tg.load_scene(None, data=json.loads(open(sys.argv[1]).read()))
    x = np.random.default_rng(1).uniform(0.02, 0.28, (1000, 3))
    sim = tg.Simulation(scene, x=x)
    sim.run(steps=1)
    s = sim.solver
    t = s.colours.tables
    arrays = {name: t[name].to_numpy() for name in ("colour", "pairs", "start")}
    first, x_first = s.first.to_numpy(), sim.x
    sim.run(steps=4)
    np.savez(sys.argv[2], first=first, x_first=x_first, x=sim.x, **arrays)
""")


def _vulkan_colours(workdir: Path) -> background.Command:
    (workdir / "vulkan_colours.py").write_text(_VULKAN_COLOURS)
    (workdir / "scene.json").write_text(json.dumps(_scene_data(10, 0.3, 1)))
    script, scene = str(workdir / "vulkan_colours.py"), str(workdir / "scene.json")
    return background.python(script, scene, str(workdir / "run.npz")), {"TI_GOLF_ARCH": "vulkan"}


background.declare("vulkan-colours", _vulkan_colours, timeout=600)


@ON_VULKAN
@pytest.mark.background("vulkan-colours")
def test_a_gpu_backend_colours_and_sweeps_the_pairs_as_the_cpu_does(background_runs):
    # The colouring and its layout are integer work: a GPU backend must make them exactly as the
    # CPU does, and then take the same step up to round-off (SPIR-V lets a driver fuse a multiply
    # and an add). Taichi's Vulkan backend once added up a thread's loop of integer atomics to at
    # most 2: the layout's counts per colour came out a few pairs each, and the sweeps left all
    # but a few dozen of the 12,000 pairs of a 5,000-ball pile out (overlaps of 20 % R).
    # Later steps of this jammed start part by more than round-off wherever a contact's decision
    # sits on the edge (a velocity of 1e-34 m/s or 0): four steps on, the sets of seeds 1 to 5
    # kept 83-100 % of the balls within 1e-6 m and none more than 0.65 mm apart.
    _, workdir = background_runs.succeeded("vulkan-colours", NO_VULKAN_BACKEND)
    gpu = np.load(workdir / "run.npz")
    x = np.random.default_rng(1).uniform(0.02, 0.28, (1000, 3))
    sim = tg.Simulation(_scene(10, 0.3, 1), x=x)
    sim.run(steps=1)
    listed, laid_out, start = _colouring(sim)
    pairs = len(listed)
    np.testing.assert_array_equal(gpu["first"], sim.solver.first.to_numpy())
    np.testing.assert_array_equal(gpu["colour"][:pairs], listed[:, 2])
    _assert_valid_layout(listed, gpu["pairs"][:pairs], gpu["start"])
    d = np.linalg.norm(gpu["x_first"] - sim.x, axis=1)
    assert d.max() < 1e-9, d.max()
    sim.run(steps=4)
    d = np.linalg.norm(gpu["x"] - sim.x, axis=1)
    assert np.mean(d < 1e-6) > 0.5 and d.max() < 2e-3, (np.mean(d < 1e-6), d.max())


@pytest.mark.slow
def test_colouring_of_a_settled_pile_is_valid_and_climbs():
    sim = tg.Simulation(_scene(250, 0.2, 3))
    sim.run(t=0.8)
    _assert_valid(sim)
    listed, _, _ = _colouring(sim)
    # the colours rise up the pile: over the pairs that share a ball and are not in the overflow
    # set, the higher pair mostly takes the later colour (half the time for colours without order;
    # 0.66-0.71 over the piles of seeds 1 to 6, whose settling round-off reshuffles)
    x = sim.solver.x_at_build.to_numpy()
    height = 0.5 * (x[listed[:, 0], 1] + x[listed[:, 1], 1])
    later = total = 0
    by_ball: dict[int, list[int]] = {}
    for p, (a, b, c) in enumerate(listed):
        if c < COLOURS:
            by_ball.setdefault(int(a), []).append(p)
            by_ball.setdefault(int(b), []).append(p)
    for ps in by_ball.values():
        for p in ps:
            for q in ps:
                if height[q] > height[p] + 0.01:
                    total += 1
                    later += int(listed[q, 2] > listed[p, 2])
    assert total > 0 and later > 0.6 * total, (later, total)


def test_colouring_is_the_same_build_after_build():
    sim = tg.Simulation(_scene(250, 0.2, 4))
    sim.run(steps=1)
    first = _colouring(sim)
    sim.solver.invalidate()
    sim.solver.ensure_lists(sim.state)
    for a, b in zip(first, _colouring(sim)):
        np.testing.assert_array_equal(a, b)


def _colours_by_pair(sim) -> dict[tuple[int, int], int]:
    """Each listed pair's colour, by the ids of its two balls (the storage order may change)."""
    listed, _, _ = _colouring(sim)
    order = sim.state.order
    ids = np.arange(sim.n) if order is None else order
    return {(int(min(ids[a], ids[b])), int(max(ids[a], ids[b]))): int(c) for a, b, c in listed}


@pytest.mark.slow
@pytest.mark.parametrize("reorder", [False, True])
def test_pairs_keep_their_colours_over_rebuilds(reorder):
    # a pour landing: the lists are rebuilt step after step, the balls stored in the grid's order
    # (reorder) or not; a pair listed before a rebuild keeps its colour (unless in the overflow
    # set), only the pairs new to the lists are coloured, and the colouring stays valid
    sim = tg.Simulation(_scene(250, 0.2, 6))
    sim.solver = CollisionSolver(sim.model, serial=False, reorder=reorder)
    sim.run(t=0.35)
    colours = sim.solver.colours
    colours.record = True
    kept, rounds = 0, colours.rounds
    for _ in range(20):
        before = _colours_by_pair(sim)
        sim.solver.invalidate()
        sim.run(steps=1)
        _assert_valid(sim)
        after = _colours_by_pair(sim)
        new = [pair for pair in after if pair not in before or before[pair] == OVERFLOW]
        assert colours.fresh[-1] == len(new)
        for pair, c in after.items():
            if pair not in new:
                assert c == before[pair], pair
                kept += 1
    assert kept > 0 and sum(colours.fresh) < 0.2 * kept
    assert colours.rounds - rounds <= 20 * 8  # a few rounds a rebuild for the few new pairs


@pytest.mark.slow
def test_runs_with_contact_colours_repeat_bit_for_bit():
    # the states, and what a saved run keeps of the solver: the pairs' layout colour by colour too
    runs = []
    for _ in range(2):
        sim = tg.Simulation(_scene(250, 0.2, 5, e=0.8))
        sim.run(t=0.3)
        runs.append((sim.x, sim.v, sim.w, *sim.solver.record().arrays.values()))
    assert len(runs[0]) == len(runs[1]) > 3 + len(sim.solver.colours.TABLES)
    for a, b in zip(*runs, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.slow
def test_a_saved_run_with_contact_colours_continues_bit_for_bit(tmp_path):
    # the colours are carried from build to build, so the order of the sweeps depends on the run's
    # history: a run loaded again must sweep its pairs in the same colours (a run that coloured its
    # pairs afresh at the load ended centimetres apart 0.15 s later)
    whole = tg.Simulation(_scene(250, 0.2, 5, e=0.8))
    whole.run(t=0.2)
    whole.save(tmp_path / "run.npz")
    whole.run(t=0.1)
    again = tg.Simulation.load(tmp_path / "run.npz")
    assert again.solver.colours is not None and again.solver.colours.builds > 0
    again.run(t=0.1)
    for a, b in ((whole.x, again.x), (whole.v, again.v), (whole.w, again.w)):
        np.testing.assert_array_equal(a, b)


def test_layout_is_read_only_with_the_gauss_seidel_sweeps():
    with pytest.raises(ConfigError, match="contact.layout"):
        tg.load_scene(None, data={"description": "x", "contact": {"solver": "jacobi", "layout": "contacts"}})
    with pytest.raises(ConfigError, match="contact.layout"):
        tg.load_scene(None, data={"description": "x", "contact": {"solver": "gauss_seidel", "layout": "rows"}})
