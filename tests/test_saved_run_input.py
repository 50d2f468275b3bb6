"""A saved run is input too: every damaged, cut short or edited run file is refused before anything
runs, in one line naming the file and the entry at fault, with exit code 2 (``ti-golf run
--resume``, through ``Simulation.load``); an undamaged one still continues bit for bit.

Each case edits a copy of one small real run (four balls, two of them tracked, one flying; the
collision solver parallel and storing the balls in grid order, so that every kind of entry is
there: the balls, the flight records, the storage order, the balls at t0 and the solver's lists).
"""

from __future__ import annotations

import io
import zipfile

import numpy as np
import pytest
from conftest import assert_same_state, read_saved_run, run_cli, write_saved_run

import ti_golf as tg
from ti_golf.cli import main
from ti_golf.solvers import CollisionSolver

R = 0.02


def make_run() -> tg.Simulation:
    """Three balls resting side by side, touching, and a fourth in flight above them, the first
    and the flying one tracked; the solver parallel, storing the balls in grid order."""
    scene = tg.load_scene("lab_vacuum", ["world.collisions=true", "world.dt=0.001"])
    x = [[0.0, R, 0.0], [2 * R, R, 0.0], [4 * R, R, 0.0], [0.0, 0.5, 0.3]]
    v = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 2.0, 0.0]]
    sim = tg.Simulation(scene, x=x, v=v, track=[True, False, False, True])
    sim.solver = CollisionSolver(sim.model, serial=False, reorder=True)
    return sim


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    """The path of the run saved after 20 steps."""
    path = tmp_path_factory.mktemp("saved") / "base.npz"
    sim = make_run()
    sim.run(steps=20)
    sim.save(path)
    return path


def refused(path, capsys) -> str:
    """``ti-golf run --resume PATH``: exit code 2 and one line of standard error, no traceback;
    returns the error after ``ti-golf: error: PATH: ``."""
    capsys.readouterr()
    assert main(["run", "--resume", str(path), "--t", "0.01"]) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    prefix = f"ti-golf: error: {path}: "
    assert lines[0].startswith(prefix), lines[0]
    return lines[0][len(prefix) :]


def edited(base, tmp_path, edit) -> str:
    """A copy of the run at ``base`` with ``edit(data, meta)`` made to its arrays and description."""
    data, meta = read_saved_run(base)
    edit(data, meta)
    path = tmp_path / "edited.npz"
    write_saved_run(path, data, meta)
    return path


def test_the_undamaged_run_continues_bit_for_bit(base):
    whole = make_run()
    whole.run(steps=30)
    resumed = tg.Simulation.load(base)
    assert resumed.state.order is not None and resumed.solver.record().arrays.keys() >= {"upper", "col_ids"}
    resumed.run(steps=10)
    assert_same_state(whole, resumed)


REQUIRED = [
    "x",
    "v",
    "w",
    "t",
    "status",
    "radius",
    "mass",
    "rest_time",
    "landed",
    "apex",
    "t_land",
    "land_x",
    "land_v",
    "launch_x",
    "solver.upper",
    "solver.first",
    "solver.lam",
    "solver.lower",
    "solver.lower_first",
    "solver.sorted_ids",
    "solver.start",
    "solver.surface_start",
    "solver.surface_impulse",
    "solver.friction",
]


@pytest.mark.parametrize("name", REQUIRED)
def test_a_missing_array_is_named(base, tmp_path, capsys, name):
    path = edited(base, tmp_path, lambda data, meta: data.pop(name))
    message = refused(path, capsys)
    assert message.startswith(f"entry '{name}': missing"), message


def _set(name, value):
    def edit(data, meta):
        data[name] = value(data[name]) if callable(value) else value

    return edit


def _poke(name, index, value):
    def edit(data, meta):
        a = data[name].copy()
        a[index] = value
        data[name] = a

    return edit


CASES = {
    "v of 3 balls": (_set("v", lambda v: v[:3]), "v", "shape (3, 3) but the run has 4 balls (expects (4, 3))"),
    "x of 3 balls": (_set("x", lambda x: x[:3]), "x", "shape (3, 3) but the run has 4 balls (expects (4, 3))"),
    "x of 2 columns": (_set("x", lambda x: x[:, :2]), "x", "shape (4, 2); expects (N, 3)"),
    "no balls": (_set("x", np.zeros((0, 3))), "x", "shape (0, 3); expects (N, 3)"),
    "radius of 5": (_set("radius", np.full(5, R)), "radius", "shape (5,) but the run has 4 balls (expects (4,))"),
    "NaN velocity": (_poke("v", (2, 1), np.nan), "v", "ball 2 holds nan; expects the balls' velocities [m/s], finite"),
    "infinite position": (
        _poke("x", (0, 0), np.inf),
        "x",
        "ball 0 holds inf; expects the balls' positions [m], finite",
    ),
    "NaN spin": (_poke("w", (3, 2), np.nan), "w", "ball 3 holds nan"),
    "negative radius": (
        _poke("radius", 1, -R),
        "radius",
        "ball 1 holds -0.02; expects the balls' radii [m], finite and > 0",
    ),
    "zero mass": (_poke("mass", 0, 0.0), "mass", "ball 0 holds 0.0; expects the balls' masses [kg], finite and > 0"),
    "negative rest timer": (_poke("rest_time", 0, -1.0), "rest_time", "ball 0 holds -1.0"),
    "negative time": (_set("t", np.float64(-5.0)), "t", "is -5.0 s; expects a time in [0, 1e+09] s"),
    "NaN time": (_set("t", np.float64(np.nan)), "t", "is nan s; expects a time in [0, 1e+09] s"),
    "time so late a step no longer moves it": (_set("t", np.float64(1e300)), "t", "is 1e+300 s; expects a time in"),
    "infinite time": (_set("t", np.float64(np.inf)), "t", "is inf s"),
    "two times": (_set("t", np.zeros(2)), "t", "shape (2,); expects one number"),
    "partial as text": (_set("partial", np.array("yes")), "partial", "expects true or false"),
    "a speed no run reaches": (_poke("v", (0, 0), 1e30), "v", "ball 0 holds 1e+30; expects the balls' velocities"),
    "a position whose square overflows": (_poke("x", (3, 0), 1e300), "x", "ball 3 holds 1e+300"),
    "partial for each ball": (_set("partial", np.zeros(4, bool)), "partial", "expects true or false"),
    "text velocities": (_set("v", lambda v: v.astype(str)), "v", "dtype <U"),
    "text time": (_set("t", np.array("5")), "t", "dtype <U1; expects numbers"),
    "float statuses": (_set("status", lambda s: s.astype(float)), "status", "dtype float64; expects whole numbers"),
    "unknown status": (_poke("status", 3, 7), "status", "ball 3 holds 7; expects one of 0 (flying), 1 (rolling)"),
    "unknown flight state": (_poke("landed", 0, 5), "landed", "ball 0 holds 5; expects one of -1 (not tracked)"),
    "nothing tracked": (_set("landed", lambda a: np.full_like(a, -1)), "landed", "tracks no ball"),
    "NaN landing point": (_poke("land_x", (0, 1), np.nan), "land_x", "ball 0 holds nan"),
    "order not an order": (_poke("order", 0, 9), "order", "is not an order of the balls"),
    "balls at t0 of 3": (_set("initial.x", lambda x: x[:3]), "initial.x", "shape (3, 3) but the run has 4 balls"),
    "NaN velocity at t0": (_poke("initial.v", (1, 1), np.nan), "initial.v", "holds nan; expects finite numbers"),
    "steps negative": (lambda d, m: m.update(steps=-3), "run", "'steps' is -3; expects a whole number >= 0"),
    "tracking as text": (lambda d, m: m.update(tracking="yes"), "run", "'tracking' is 'yes'; expects true or false"),
    "no scene": (lambda d, m: m.pop("scene"), "run", "'scene' is missing"),
    # (the advice named '--precision f16', which is no choice)
    "precision f16": (
        lambda d, m: m.update(precision="f16"),
        "run",
        "key 'precision' must be one of f32, f64 (got 'f16')",
    ),
    "a bad scene key": (
        lambda d, m: m["scene"]["world"].update(dt=-1.0),
        "run",
        "its scene: key 'world.dt' must be in (0, 1] s",
    ),
    "upper too wide": (
        _set("solver.upper", lambda a: np.zeros((a.shape[0], a.shape[1] + 1), np.int32)),
        "solver.upper",
        "but the run has 4 balls and the record's capacity is",
    ),
    "upper as floats": (
        _set("solver.upper", lambda a: a.astype(np.float64)),
        "solver.upper",
        "dtype float64; expects int32",
    ),
    "lam too short": (_set("solver.lam", lambda a: a[:-1]), "solver.lam", "but the record's pair_capacity is"),
    "surface rows of 9 columns": (
        _set("solver.surface_impulse", lambda a: np.zeros((a.shape[0], 9, 4), np.float32)),
        "solver.surface_impulse",
        "the scene has 1 surface column(s)",
    ),
    "a ball id past the balls": (
        _poke("solver.upper", (0, 0), 40),
        "solver.upper",
        "holds 40; expects entries in [0, 3]",
    ),
    "a list start past the pairs": (_poke("solver.first", -1, 10**6), "solver.first", "expects starts from 0 to"),
    "NaN carried impulse": (_poke("solver.lam", 0, np.nan), "solver.lam", "holds NaN or infinite values"),
    "a negative drift": (_poke("solver.drift", 1, -1e-3), "solver.drift", "holds -0.001; expects distances >= 0"),
    "drifts of 3 balls": (_set("solver.drift", lambda a: a[:3]), "solver.drift", "but the run has 4 balls"),
    "amendable as text": (
        lambda d, m: m["solver"]["values"].update(amendable="yes"),
        "run",
        "solver value 'amendable' is 'yes'; expects true or false",
    ),
    "a colour past the colours": (
        _poke("solver.col_colour", 0, 9),
        "solver.col_colour",
        "holds 9; expects entries in [0, 3]",
    ),
    "capacity past the balls": (
        lambda d, m: m["solver"]["values"].update(capacity=10**9),
        "run",
        "solver value 'capacity' is 1000000000; expects a whole number in [1, 3]",
    ),
    "scratch too small": (
        lambda d, m: m["solver"]["scratch"]["x_free"].__setitem__(0, [1]),
        "run",
        "solver scratch 'x_free' is [[1], [3], 'float64']; expects [4], [3], float64",
    ),
    "no blocks of columns for the next step": (
        lambda d, m: (d.pop("solver.col_ids"), m["solver"]["values"].update(rebuild=False)),
        "solver.col_ids",
        "missing; the next step sweeps the balls by blocks of grid columns",
    ),
    "serial and reordering": (
        lambda d, m: m["solver"].update(serial=True),
        "run",
        "'solver.serial' and 'solver.reorder' are both true",
    ),
    "no scratch shapes": (
        lambda d, m: m["solver"].update(scratch={}),
        "run",
        "solver scratch 'impulse' is missing; a record of lists that were built gives its shape",
    ),
    "radii a million times the scene's": (
        _set("radius", lambda r: r * 1e6),
        "radius",
        "ball 0 holds 20000 m but the run's scene gives it 0.02 m (4 balls differ)",
    ),
    "an entry a run does not hold": (
        lambda d, m: d.update(junk=np.zeros(3)),
        "junk",
        "is not an entry of a saved run, so it would have no effect",
    ),
    "the solver's record dropped": (
        lambda d, m: m.update(solver=None),
        "run",
        "'solver' is null, but the run's balls collide: its carried impulses are missing",
    ),
    "no grid hash": (
        lambda d, m: m["solver"]["values"].update(hash=None),
        "run",
        "solver value 'hash' is missing or null",
    ),
    "an extra description field": (  # (resumed as if it were not there)
        lambda d, m: m.update(zzz=1),
        "run",
        "'zzz' is not a field of a saved run's description, so it would have no effect",
    ),
    "f32 positions in an f64 run": (  # (resumed, no longer bit for bit)
        _set("x", lambda x: x.astype(np.float32)),
        "x",
        "dtype float32; a run saved in f64 holds float64",
    ),
    "unknown format": (
        lambda d, m: m.update(format=3),
        "run",
        "is a saved run of format 3; this ti-golf reads format 2",
    ),
    "unknown record version": (
        lambda d, m: m["solver"].update(version=99),
        "run",
        "holds a collision solver saved in record version 99",
    ),
}


@pytest.mark.parametrize("case", CASES, ids=list(CASES))
def test_an_edited_entry_is_named(base, tmp_path, capsys, case):
    edit, entry, what = CASES[case]
    message = refused(edited(base, tmp_path, edit), capsys)
    assert message.startswith(f"entry '{entry}'"), message
    assert what in message, message


def test_a_run_saved_before_builds_kept_lists_reads_every_list_as_made_at_the_last_build(base, tmp_path):
    # a run saved without drifts (before a build could keep a ball's list) made every list at
    # its last build: each ball owes nothing before it, and the next build lists every ball anew
    def older(data, meta):
        data.pop("solver.drift")
        meta["solver"]["elements"].pop("drift")
        meta["solver"]["values"].pop("amendable")

    resumed = tg.Simulation.load(edited(base, tmp_path, older))
    np.testing.assert_array_equal(resumed.solver.drift.to_numpy(), np.zeros(4, np.float32))
    assert not resumed.solver.amendable
    resumed.run(steps=10)
    as_saved = tg.Simulation.load(base)  # (its balls owed nothing either: they go on the same)
    as_saved.run(steps=10)
    np.testing.assert_array_equal(resumed.x, as_saved.x)
    np.testing.assert_array_equal(resumed.v, as_saved.v)


def _cut(content: bytes) -> bytes:
    return content[: len(content) // 2]


def _npy() -> bytes:
    """A .npy file's bytes (one array, not an archive of them)."""
    out = io.BytesIO()
    np.save(out, np.zeros((4, 3)))
    return out.getvalue()


def _flip_in(name: str):
    """Flip a byte in the middle of entry ``name``'s numbers."""

    def flip(content: bytes, path) -> bytes:
        with zipfile.ZipFile(path) as z:
            info = z.getinfo(f"{name}.npy")
        at = info.header_offset + 30 + len(info.filename) + len(info.extra) + info.compress_size - 8
        return content[:at] + bytes([content[at] ^ 0xFF]) + content[at + 1 :]

    return flip


FILES = {
    "cut in half": (
        lambda content, path: _cut(content),
        "is not a run saved by ti-golf (an .npz file): it is not a zip",
    ),
    "garbage": (lambda content, path: bytes(range(256)) * 4, "is not a run saved by ti-golf (an .npz file): it is not"),
    "a .npy file": (lambda content, path: _npy(), "is not a run saved by ti-golf (an .npz file): it is not a zip"),
    "empty": (lambda content, path: b"", "is not a run saved by ti-golf (an .npz file)"),
    "a byte flipped in v": (_flip_in("v"), "entry 'v': cannot be read"),
    "a byte flipped in the run": (_flip_in("run"), "entry 'run': cannot be read"),
}


@pytest.mark.parametrize("case", FILES, ids=list(FILES))
def test_a_damaged_file_is_refused(base, tmp_path, capsys, case):
    damage, what = FILES[case]
    path = tmp_path / "damaged.npz"
    path.write_bytes(damage(base.read_bytes(), base))
    message = refused(path, capsys)
    assert message.startswith(what), message


def test_an_object_array_is_refused_unread(base, tmp_path, capsys):
    # np.load would unpickle it: allow_pickle stays false, and the entry is named
    data, meta = read_saved_run(base)
    data["v"] = np.array([{"a": 1}] * 4, dtype=object)
    path = tmp_path / "pickled.npz"
    write_saved_run(path, data, meta)
    message = refused(path, capsys)
    assert message.startswith("entry 'v': cannot be read (Object arrays cannot be loaded"), message


def test_a_run_entry_that_is_not_json_is_refused(base, tmp_path, capsys):
    data, meta = read_saved_run(base)
    path = tmp_path / "text.npz"
    np.savez(path, **{**data, "run": np.array("{not json")})
    assert refused(path, capsys) == "entry 'run': is not readable (a saved run's description, JSON text)"


def test_the_console_command_refuses_a_cut_file_in_one_line(base, tmp_path):
    # the whole process, as a person runs it: exit code 2 and one line on standard error
    path = tmp_path / "cut.npz"
    path.write_bytes(_cut(base.read_bytes()))
    proc = run_cli("run", "--resume", str(path), "--t", "0.01", timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().splitlines() == [
        f"ti-golf: error: {path}: is not a run saved by ti-golf (an .npz file): it is not a zip archive"
    ]


def test_the_scene_of_a_saved_run_is_checked_as_a_scene_file(base, tmp_path):
    path = edited(base, tmp_path, lambda data, meta: meta["scene"]["air"].update(rho=-1.0))
    with pytest.raises(
        tg.ConfigError, match=r"edited\.npz: entry 'run', its scene: key 'air\.rho' must be in \[0, 1000\] kg"
    ):
        tg.Simulation.load(path)


def test_a_run_whose_scene_makes_other_balls_or_another_ground_is_refused(tmp_path, capsys):
    # the balls and the ground come from the run's scene: 16 balls where it makes 1 went on, and so
    # did a run whose heights file was edited after it was saved (it then ended elsewhere)
    one = tmp_path / "one.npz"
    tg.Simulation(tg.load_scene("lab_vacuum")).save(one)
    data, meta = read_saved_run(one)
    for name, a in list(data.items()):
        if name != "run" and np.ndim(a) >= 1 and a.shape[0] == 1:
            data[name] = np.concatenate([a, a])
    two = tmp_path / "two.npz"
    write_saved_run(two, data, meta)
    assert refused(two, capsys) == "entry 'x': holds 2 balls but the run's scene (entry 'run') makes 1"

    heights = tmp_path / "ground.npy"
    np.save(heights, np.zeros((5, 5)))
    scene = tmp_path / "ground.toml"
    scene.write_text(
        '[world]\nground = false\n[terrain]\nkind = "file"\nfile = "ground.npy"\nsize = [10, 10]\n'
        "[[balls]]\nposition = [5, 0.5, 5]\n"
    )
    run = tmp_path / "run.npz"
    assert main(["run", str(scene), "--t", "0.05", "--out", str(run)]) == 0
    np.save(heights, np.full((5, 5), 0.5))
    message = refused(run, capsys)
    assert (
        message
        == f"entry 'terrain_heights': differ from the heights of the run's terrain (its file {str(heights)!r} changed since)"
    )
