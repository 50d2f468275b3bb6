"""The collision solver's saved record: written as a versioned record of named numbers and arrays,
read back (and as the solver's attributes were saved whole before it, version 1) to continue bit
for bit, and refused in one line when its version is unknown."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import SERIAL_OR_PARALLEL, assert_same_state

import ti_golf as tg
from ti_golf.cli import main
from ti_golf.solvers import CollisionSolver, GaussSeidelSolver, JacobiSolver, record


def _pile(solver: str) -> tg.Scene:
    """Two layers of 3 × 3 balls on the ground and a ball rolling into them (no air)."""
    r = 0.02
    balls = [{"position": [2 * r * i, r + 2 * r * k, 2 * r * j]} for i in range(3) for j in range(3) for k in range(2)]
    balls.append({"position": [-0.1, r, 2 * r], "velocity": [1.0, 0.0, 0.0]})
    data = {"air": {"rho": 0.0}, "world": {"dt": 0.001}, "contact": {"solver": solver, "e": 0.5, "mu": 0.4}}
    return tg.load_scene(None, data={**data, "balls": balls})


def _read(path) -> tuple[dict, dict]:
    with np.load(path) as d:
        data = {k: d[k] for k in d.files}
    return data, json.loads(str(data["run"]))


def _write(path, data: dict, meta: dict) -> None:
    data["run"] = np.array(json.dumps(meta))
    np.savez(path, **data)


@pytest.mark.parametrize("solver", ["jacobi", "gauss_seidel"])
def test_the_scene_names_the_kind_of_solver(solver):
    sim = tg.Simulation(_pile(solver))
    kind = {"jacobi": JacobiSolver, "gauss_seidel": GaussSeidelSolver}[solver]
    assert type(sim.solver) is kind and type(CollisionSolver(sim.model)) is kind
    assert sim.solver.gauss_seidel == (solver == "gauss_seidel")


@SERIAL_OR_PARALLEL
@pytest.mark.parametrize("solver", ["jacobi", "gauss_seidel"])
def test_a_saved_record_reads_back_as_it_was_written(solver, serial, tmp_path):
    sim = tg.Simulation(_pile(solver))
    sim.solver = CollisionSolver(sim.model, serial=serial, reorder=not serial)
    sim.run(t=0.05)
    sim.save(tmp_path / "r.npz")
    data, meta = _read(tmp_path / "r.npz")
    saved = meta["solver"]
    assert saved["version"] == record.VERSION
    assert set(saved["values"]) == {*sim.solver.SAVED_VALUES, "hash"}  # the names the solver declares, no others
    names = {k[len("solver.") :] for k in data if k.startswith("solver.")}
    assert names <= set(sim.solver.SAVED_ARRAYS) and {"upper", "first", "lam", "lower"} <= names
    assert ("col_ids" in names) == (solver == "gauss_seidel" and not serial)
    arrays = {name: data[f"solver.{name}"] for name in names}
    back = record.from_file(arrays, saved, sim.state.n, serial, sim.solver.gauss_seidel)
    now = sim.solver.record()
    assert back.values == json.loads(json.dumps(now.values)) and back.scratch == now.scratch
    assert back.elements == now.elements and back.arrays.keys() == now.arrays.keys()
    for name, a in now.arrays.items():
        np.testing.assert_array_equal(back.arrays[name], a, err_msg=name)
        assert back.arrays[name].dtype == a.dtype


def _as_version_1(path) -> None:
    """Rewrite the solver of the run saved at ``path`` as version 1 held it (what the solver's
    attributes were, saved whole): no version, the private numbers under their attributes' names,
    the column tables of a Jacobi solver as ``None``, and which attributes held one array."""
    data, meta = _read(path)
    solver = meta["solver"]
    del solver["version"]
    values = solver["values"]
    for name in ("r_max", "valid", "rebuild", "hash"):
        values[f"_{name}"] = values.pop(name)
    if "col_start" not in solver["elements"]:
        values["col_start"] = values["col_chunk"] = None
    solver["same"] = {}
    _write(path, data, meta)


@SERIAL_OR_PARALLEL
@pytest.mark.parametrize("solver", ["jacobi", "gauss_seidel"])
def test_a_run_saved_before_the_record_was_versioned_continues_bit_for_bit(solver, serial, tmp_path):
    def make():
        sim = tg.Simulation(_pile(solver))
        sim.solver = CollisionSolver(sim.model, serial=serial, reorder=not serial)
        return sim

    whole = make()
    whole.run(t=0.12)
    first = make()
    first.run(t=0.05)
    first.save(tmp_path / "v1.npz")
    _as_version_1(tmp_path / "v1.npz")
    resumed = tg.Simulation.load(tmp_path / "v1.npz")
    assert resumed.solver.rebuilds == first.solver.rebuilds and resumed.solver._valid
    resumed.run(t=0.07)
    assert np.abs(whole.x[:-1] - first.x[:-1]).max() > 1e-4  # the rolling ball met the pile after the save
    assert_same_state(whole, resumed)


def test_a_record_of_an_unknown_version_is_refused_in_one_line(tmp_path, capsys):
    sim = tg.Simulation.from_scene("break_shot")
    sim.run(t=0.01)
    path = tmp_path / "future.npz"
    sim.save(path)
    data, meta = _read(path)
    meta["solver"]["version"] = 99
    _write(path, data, meta)
    with pytest.raises(tg.ConfigError, match=r"future\.npz: .*record version 99; this ti-golf reads versions 1 to 2"):
        tg.Simulation.load(path)
    assert main(["run", "--resume", str(path), "--t", "0.01"]) == 2
    err = capsys.readouterr().err.strip()
    assert "record version 99" in err and len(err.splitlines()) == 1
