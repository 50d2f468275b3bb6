"""Parameter studies (ti-golf study) on a real Dask cluster, every process on 127.0.0.1: a small
study end to end, figures equal to `ti-golf run` alone, a scheduler and two workers started by
hand, a worker killed mid-task, a resumed study, a failing task, and the study file's checks."""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, cli, run_cli, sigint_as_in_a_terminal

from ti_golf.errors import ConfigError
from ti_golf.study.figures import pile_height, repose_angle
from ti_golf.study.spec import load_study, study_json_schema

distributed = pytest.importorskip("distributed", reason="the cluster extra: pip install 'ti-golf[cluster]'")
pytest.importorskip("pyarrow", reason="the cluster extra: pip install 'ti-golf[cluster]'")

FLIGHT_STUDY = """
description = "carry against launch speed and drag"
scene = "lab_turbulent"

[task]
kind = "run"
until = "landed"

[grid]
"launch.speed" = [40.0, 60.0]
"air.C_D" = "0.2:0.3:0.1"
"""

PILE_SCENE = """
description = "150 balls dropped in a heap"
[world]
dt = 0.001
[contact]
solver = "gauss_seidel"
mu = 0.4
[[planes]]
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
[[blocks]]
kind = "random"
number = 150
box_min = [-0.15, 0.05, -0.15]
box_max = [0.15, 0.5, 0.15]
seed = 3
"""

PILE_STUDY = """
scene = "heap.toml"
seeds = [1, 2]

[task]
kind = "run"
steps = 300
figures = ["pile_height", "repose_angle", "deepest_overlap", "p99_speed"]

[grid]
"contact.mu" = [0.2, 0.6]
"""


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


def figures_of(row: dict) -> str:
    """A row's figures (every column but the bookkeeping that differs run to run), as JSON text:
    equal bit for bit, NaN equal to NaN."""
    kept = {k: v for k, v in row.items() if k not in ("wall_s", "sim_wall_s", "host", "worker", "run_path")}
    return json.dumps(kept, sort_keys=True)


@pytest.fixture(scope="module")
def flight_study(tmp_path_factory):
    """The flight study run once on a local cluster of two workers."""
    from ti_golf.study import run_study

    folder = tmp_path_factory.mktemp("flight")
    spec = write(folder, "flight.toml", FLIGHT_STUDY)
    result = run_study(spec, out=folder / "out", workers=2, log=lambda line: None)
    return spec, result


# -- the study file ------------------------------------------------------------------------------
BAD = [
    ('scene = "lab_turbulent"\nwrkers = 2\n', "wrkers", "is not a study key"),
    ('scene = "lab_turbulent"\nset = ["air.altitude"]\n', "set: air.altitude", "must be KEY=VALUE"),  # (named --set)
    ('scene = "lab_turbulent"\n[task]\nkind = "walk"\n', "task.kind", "must be one of"),
    ('scene = "lab_turbulent"\n[task]\nkind = "run"\nshots = 10\n', "task.shots", "read only when task.kind"),
    ('scene = "lab_turbulent"\n[grid]\n"air.CD" = [0.1]\n', "grid.air.CD", "is not a scene key"),
    ('scene = "lab_turbulent"\n[grid]\n"contact.e" = [0.5, 2.0]\n', "grid.contact.e", "must be in [0, 1]"),
    (
        'scene = "lab_turbulent"\n[grid]\n"air.C_D" = [0.1]\n[random.uniform]\n"air.C_D" = [0, 1]\n',
        "random",
        "give one of",
    ),
    ('scene = "lab_turbulent"\n[task]\nkind = "tour"\nfigures = ["pile_height"]\n', "task.figures", "not a figure of"),
    ('scene = "lab_turbulent"\n[task]\nfigures = ["carri"]\n', "task.figures", "names no figure"),
    ('scene = "lab_turbulent"\nseeds = [1]\n[task]\nkind = "sweep"\n', "seeds", "draws nothing at random"),
    ('scene = "no_such_scene"\n', "scene", "no scene file"),
    (
        'scene = "lab_turbulent"\n[random]\nsamples = 0\n[random.uniform]\n"air.C_D" = [0, 1]\n',
        "random.samples",
        "must be in",
    ),
    ('scene = "lab_turbulent"\n[random.uniform]\n"air.C_D" = [1, 0]\n', "random.uniform.air.C_D", "low <= high"),
    (  # (the same task, run three times)
        'scene = "lab_turbulent"\n[random]\nsamples = 3\n[random.uniform]\n"air.C_D" = [0.2, 0.2]\n',
        "random.uniform",
        "draws the same task every time",
    ),
    ('scene = "lab_turbulent"\n[[points]]\n"air.model" = "magic"\n', "points[0].air.model", "must be one of"),
    ('scene = "lab_turbulent"\n[grid]\n"air.C_D" = [0.2, 0.3, 0.2]\n', "grid.air.C_D", "holds the value 0.2 twice"),
    ('scene = "lab_vacuum"\n[task]\nkind = "run"\nballs = 100\n', "task.balls", "'lab_vacuum' has 0"),
    (  # (it passed, and every task failed)
        'scene = "heap"\n[task]\nkind = "run"\nballs = 500\n',
        "task.balls",
        "asks for 500 balls: the random block of 'heap', scaled to them, holds at most 448",
    ),
    ('scene = "lab_turbulent"\n[grid]\n"air.C_D" = "0:80:0.0001"\n', "grid", "gives 800,001 tasks"),  # (it hung)
    ('scene = "lab_turbulent"\n[task]\nfigures = []\n', "task.figures", "names no figure"),
    (
        'scene = "lab_turbulent"\n[[points]]\n"air.C_D" = 0.2\n[[points]]\n"air.C_D" = 0.2\n',
        "points[1]",
        "is points[0] again",
    ),
    ('scene = "lab_vacuum"\nseeds = [1, 2]\n[task]\nkind = "run"\n', "seeds", "'lab_vacuum' has none"),
    (
        'scene = "lab_turbulent"\nset = ["air.C_D=0.25"]\n[grid]\n"air.C_D" = [0.2, 0.3]\n',
        "set: air.C_D",
        "is varied by the study's [grid]: a value set for every task would have no effect",
    ),
    (
        'scene = "lab_turbulent"\nset = ["air.C_D=0.25", "air.C_D=0.3"]\n',
        "set: air.C_D",
        "is given twice: give it once",
    ),
    # keys the task's kind does not read (each was taken, and every task ran the same)
    (
        'scene = "tour_shot"\nset = ["game.wind_max=3"]\n[task]\nkind = "tour"\n',
        "set: game.wind_max",
        "is not read by a task of task.kind = 'tour' (`ti-golf play` reads it)",
    ),
    (
        'scene = "tour_shot"\n[task]\nkind = "tour"\n[grid]\n"launch.speed" = [60, 70]\n',
        "grid.launch.speed",
        "varying it changes nothing (the tour table's rows give each ball's speed",
    ),
    ('scene = "tour_shot"\n[task]\nkind = "shot"\n[grid]\n"world.t_end" = [1, 2]\n', "grid.world.t_end", "'shot'"),
    (
        'scene = "tour_shot"\n[task]\nkind = "sweep"\n[[points]]\n"air.rho" = 1.2\n[[points]]\n"world.collisions" = false\n',
        "points[1].world.collisions",
        "is not read by a task of task.kind = 'sweep': varying it changes nothing (each shot flies",
    ),
    (
        'scene = "heap"\n[task]\nkind = "run"\nt = 0.1\n[random]\nsamples = 2\n[random.uniform]\n"world.t_end" = [1, 2]\n',
        "random.uniform.world.t_end",
        "(the run's own length (task.t or task.steps) replaces it)",
    ),
    ('scene = "heap"\nset = ["world.t_max=9"]\n', "set: world.t_max", "is not read by a task of task.kind = 'run'"),
    # what a task needs of its scene (each passed, and every task failed)
    ('scene = "break_shot"\n[task]\nkind = "sweep"\n', "scene", "flies the scene's [launch]: 'break_shot' has none"),
    ('scene = "heap"\n[task]\nkind = "run"\nuntil = "landed"\n', "task.until", "'landed' has no effect on 'heap'"),
    (
        'scene = "lab_vacuum"\n[task]\nkind = "run"\nuntil = "landed"\n[grid]\n"launch.angle_deg" = [0, 45]\n',
        "task.until",
        "no ball",
    ),
]


@pytest.mark.parametrize("text,key,reason", BAD, ids=[b[1] for b in BAD])
def test_a_bad_study_file_is_one_error_naming_the_file_and_the_key(tmp_path, text, key, reason):
    path = write(tmp_path, "bad.toml", text)
    with pytest.raises(ConfigError) as err:
        load_study(path)
    assert err.value.source == str(path) and err.value.key == key, str(err.value)
    assert reason in err.value.reason and "\n" not in str(err.value)


def test_a_study_of_flights_refuses_a_scene_with_other_balls(tmp_path):
    # a sweep, shot, dispersion or tour task flies each launch alone: the scene's [[balls]] would
    # have no effect (the study passed, and every task failed)
    scene = (ROOT / "scenes" / "tour_shot.toml").read_text() + "\n[[balls]]\nposition = [5.0, 1.0, 0.0]\n"
    write(tmp_path, "wall.toml", scene)
    for kind in ("sweep", "shot", "dispersion", "tour"):
        path = write(tmp_path, "bad.toml", f'scene = "wall.toml"\n[task]\nkind = "{kind}"\n')
        with pytest.raises(ConfigError) as err:
            load_study(path)
        assert err.value.key == "scene" and f"task.kind = '{kind}': wall's balls[0] has no effect" in err.value.reason
    path = write(tmp_path, "good.toml", 'scene = "wall.toml"\n[task]\nkind = "run"\nt = 0.1\n')
    assert load_study(path).tasks


def test_a_study_varies_a_key_of_the_scene_s_array_tables_by_index(tmp_path):
    # blocks[0].number was "not a scene key", though --set and the errors name it so
    path = write(
        tmp_path, "n.toml", 'scene = "heap"\n[task]\nkind = "run"\nt = 0.01\n[grid]\n"blocks[0].number" = [500, 1000]\n'
    )
    spec = load_study(path)
    assert spec.keys == ("blocks[0].number",) and len({t.id for t in spec.tasks}) == 2
    bad = write(tmp_path, "b.toml", 'scene = "heap"\n[task]\nkind = "run"\n[grid]\n"blocks[1].number" = [500, 1000]\n')
    with pytest.raises(ConfigError, match=r"names table 1 of \[\[blocks\]\], and the scene has 1"):
        load_study(bad)


def test_the_command_reports_a_bad_study_in_one_line_with_exit_code_2(tmp_path):
    path = write(tmp_path, "bad.toml", 'scene = "lab_turbulent"\n[grid]\n"contact.e" = [2.0]\n')
    done = run_cli("study", str(path), "--out", str(tmp_path / "out"))
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0 and "bad.toml: key 'grid.contact.e' must be in [0, 1]" in done.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("out", ["missing/out", ""])
def test_the_study_folder_is_made_but_not_its_parents_nor_an_empty_name(tmp_path, monkeypatch, capsys, out):
    # --out made every missing folder above the study's (a typo in a path became a tree of folders,
    # where run --frames refuses a missing parent), and --out "" wrote the study into the current folder
    from ti_golf.cli.main import main

    path = write(tmp_path, "s.toml", FLIGHT_STUDY)
    monkeypatch.chdir(tmp_path)
    assert main(["study", str(path), "--out", out]) == 2
    err = capsys.readouterr().err
    said = "cannot make 'missing/out': folder" if out else "needs a folder name (got an empty path)"
    assert f"--out: {said}" in err and err.count("\n") == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


def test_without_dask_the_command_says_how_to_install_it_and_exits_2(tmp_path, monkeypatch, capsys):
    from ti_golf.cli.main import main

    path = write(tmp_path, "s.toml", FLIGHT_STUDY)
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    assert main(["study", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "pip install 'ti-golf[cluster]'" in err and err.count("\n") == 1


def test_a_grid_is_every_combination_and_random_samples_follow_their_seed(tmp_path):
    spec = load_study(write(tmp_path, "g.toml", FLIGHT_STUDY))
    assert [t.point for t in spec.tasks] == [
        {"launch.speed": s, "air.C_D": c} for s in (40.0, 60.0) for c in (0.2, 0.3)
    ]
    assert spec.tasks[0].changes == ("launch.speed=40.0", "air.C_D=0.2")
    text = 'scene = "lab_turbulent"\n[random]\nsamples = 5\nseed = 4\n[random.uniform]\n"air.C_D" = [0.1, 0.4]\n'
    a, b = (load_study(write(tmp_path, f"r{i}.toml", text)) for i in (1, 2))
    drawn = [t.point["air.C_D"] for t in a.tasks]
    assert drawn == [t.point["air.C_D"] for t in b.tasks] and len(set(drawn)) == 5
    assert all(0.1 <= c <= 0.4 for c in drawn)


def test_the_study_schema_declares_every_key_the_loader_reads():
    from ti_golf.study.spec import RANDOM_KEYS, STUDY_KEYS, TASK_KEYS

    schema = study_json_schema()
    props = schema["properties"]
    assert set(props) == {*STUDY_KEYS, "task", "grid", "points", "random"}
    assert set(props["task"]["properties"]) == set(TASK_KEYS)
    assert set(props["random"]["properties"]) == {*RANDOM_KEYS, "uniform"}
    assert props["task"]["properties"]["kind"]["enum"] == ["run", "sweep", "shot", "dispersion", "tour", "pit"]


@pytest.mark.parametrize("name", ["bag_weather", "repose"])
def test_the_bundled_studies_load(name):
    spec = load_study(name)
    assert spec.tasks and len({t.id for t in spec.tasks}) == len(spec.tasks)


# -- the pile's figures --------------------------------------------------------------------------
def test_the_angle_of_repose_of_a_cone_of_balls_is_its_slope():
    rng = np.random.default_rng(0)
    r = 0.02
    for slope_deg in (20.0, 30.0):
        rho = np.sqrt(rng.uniform(0, 1.0, 20000))  # uniform over a disc of radius 1 m
        phi = rng.uniform(0, 2 * np.pi, rho.size)
        top = (1.0 - rho) * math.tan(math.radians(slope_deg))
        y = rng.uniform(r, np.maximum(top, r))  # balls fill the cone below its surface
        x = np.stack([rho * np.cos(phi) + 3.0, y, rho * np.sin(phi) - 1.0], axis=1)
        radius = np.full(rho.size, r)
        in_play = np.ones(rho.size, bool)
        assert repose_angle(x, radius, in_play) == pytest.approx(slope_deg, abs=1.5)
        # a skirt of single balls that rolled up to 2.5 m away on the floor leaves the flank's slope
        out = np.sqrt(rng.uniform(1.0, 6.25, 3000))
        psi = rng.uniform(0, 2 * np.pi, out.size)
        skirt = np.stack([out * np.cos(psi) + 3.0, np.full(out.size, r), out * np.sin(psi) - 1.0], axis=1)
        both = np.concatenate([x, skirt])
        assert repose_angle(both, np.full(len(both), r), np.ones(len(both), bool)) == pytest.approx(slope_deg, abs=1.5)
        assert pile_height(x, radius, in_play) == pytest.approx(y.max() + r - (y.min() - r))


# -- on a cluster --------------------------------------------------------------------------------
def test_a_small_study_runs_on_a_local_cluster_into_one_table(flight_study):
    from ti_golf.study.results import read_table

    spec, result = flight_study
    assert result.failed == 0 and result.ran == 4 and result.skipped == 0
    table = read_table(result.folder)
    assert table["status"] == ["ok"] * 4
    assert table["launch.speed"] == [40.0, 40.0, 60.0, 60.0] and table["air.C_D"] == [0.2, 0.3, 0.2, 0.3]
    carry = table["carry_m"]
    assert carry[0] > carry[1] and carry[2] > carry[3] and carry[2] > carry[0]  # more drag, shorter; faster, longer
    assert all(h for h in table["host"]) and all(w.startswith("tcp://127.0.0.1:") for w in table["worker"])
    assert all((result.folder / p).is_file() for p in table["run_path"])
    with open(result.folder / "results.csv") as fh:  # the CSV holds the same bits
        header, *rows = [line.rstrip("\n").split(",") for line in fh]
    col = header.index("carry_m")
    assert [float(row[col]) for row in rows] == carry


def test_a_tasks_figures_equal_those_of_its_scene_run_alone(flight_study, tmp_path):
    from ti_golf.sim.simulation import Simulation
    from ti_golf.study.results import read_table
    from ti_golf.study.tasks import run_figures

    spec, result = flight_study
    table = read_table(result.folder)
    i = 3
    changes = load_study(spec).tasks[i].changes
    alone = tmp_path / "alone.npz"
    sets = [a for c in changes for a in ("--set", c)]
    done = run_cli("run", "lab_turbulent", *sets, "--until", "landed", "--out", str(alone))
    assert done.returncode == 0, done.stderr
    figures = run_figures(Simulation.load(alone))
    for name, column in (("carry", "carry_m"), ("apex", "apex_m"), ("landing_angle", "landing_angle_deg")):
        assert figures[name] == table[column][i], name  # bit for bit
    with np.load(alone) as a, np.load(result.folder / table["run_path"][i]) as b:
        for name in ("x", "v", "w", "t"):
            np.testing.assert_array_equal(a[name], b[name], err_msg=name)


@pytest.mark.slow
def test_a_pile_study_with_seeds_equals_its_runs_alone(tmp_path):
    from ti_golf.sim.simulation import Simulation
    from ti_golf.study import run_study
    from ti_golf.study.tasks import run_figures

    write(tmp_path, "heap.toml", PILE_SCENE)
    spec = write(tmp_path, "pile.toml", PILE_STUDY)
    result = run_study(spec, out=tmp_path / "out", workers=2, log=lambda line: None)
    assert result.failed == 0 and len(result.rows) == 4
    assert [row["seed"] for row in result.rows] == [1, 2, 1, 2]
    for row in result.rows:
        assert 0 < row["pile_height_m"] < 0.4 and row["deepest_overlap"] < 0.5
        sim = Simulation.load(result.folder / row["run_path"])  # the saved run gives the row's figures again
        again = run_figures(sim)
        assert again["pile_height"] == row["pile_height_m"] and again["p99_speed"] == row["p99_speed_mps"]
    assert result.rows[0]["pile_height_m"] != result.rows[1]["pile_height_m"]  # another seed, another pour
    # the base scene's seed, run alone with `ti-golf run --set`, is a study without seeds
    (tmp_path / "pile.toml").write_text(PILE_STUDY.replace("seeds = [1, 2]\n", ""))
    plain = run_study(spec, out=tmp_path / "plain", workers=1, log=lambda line: None)
    alone = tmp_path / "alone.npz"
    done = run_cli("run", str(tmp_path / "heap.toml"), "--set", "contact.mu=0.6", "--steps", "300", "--out", str(alone))
    assert done.returncode == 0, done.stderr
    figures = run_figures(Simulation.load(alone))
    row = plain.rows[1]
    assert row["contact.mu"] == 0.6
    for name, column in (
        ("pile_height", "pile_height_m"),
        ("repose_angle", "repose_angle_deg"),
        ("deepest_overlap", "deepest_overlap"),
        ("p99_speed", "p99_speed_mps"),
    ):
        assert figures[name] == row[column] or (math.isnan(figures[name]) and math.isnan(row[column])), name


def test_every_process_of_the_local_cluster_listens_on_127_0_0_1_only():
    psutil = pytest.importorskip("psutil")
    from ti_golf.study.cluster import study_client

    def listening(proc):
        return [c.laddr for c in proc.net_connections(kind="inet") if c.status == psutil.CONN_LISTEN]

    me = psutil.Process()
    before = set(listening(me))
    with study_client(workers=2) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        addresses = [a for a in listening(me) if a not in before]
        for child in me.children(recursive=True):
            addresses += listening(child)
    assert len(addresses) >= 3  # the scheduler, and each worker (and its nanny)
    assert {a.ip for a in addresses} == {"127.0.0.1"}, addresses


def test_a_failing_task_records_its_error_and_the_others_go_on(tmp_path):
    text = (
        'scene = "lab_magnus"\n[task]\nkind = "run"\nuntil = "landed"\nfigures = ["carry"]\n'
        '[[points]]\n"launch.speed" = 40.0\n[[points]]\n"launch.speed" = 45.0\n"air.C_M" = 100.0\n'
        '[[points]]\n"launch.speed" = 50.0\n'
    )  # (a Magnus law 4,000 times the report's turns the ball faster than a step: it goes non-finite)
    path = write(tmp_path, "fails.toml", text)
    done = run_cli("study", str(path), "--out", str(tmp_path / "out"), "--workers", "2")
    assert done.returncode == 1, done.stderr
    from ti_golf.study.results import read_table

    table = read_table(tmp_path / "out")
    assert table["status"] == ["ok", "failed", "ok"]
    assert "went non-finite" in table["error"][1] and table["error"][0] == ""
    assert math.isfinite(table["carry_m"][0]) and math.isfinite(table["carry_m"][2])
    assert "1 failed" in done.stdout
    # every task failed: the plot is left out (it said "--figure: the table has no column ''", exit 2)
    text = 'scene = "lab_magnus"\n[task]\nkind = "run"\nuntil = "landed"\n'
    path = write(tmp_path, "all_fail.toml", text + '[grid]\n"air.C_M" = [99.0, 100.0]\n')
    done = run_cli(
        "study", str(path), "--out", str(tmp_path / "out2"), "--workers", "1", "--plot", str(tmp_path / "p.png")
    )
    assert done.returncode == 1 and "no plot: no task of all_fail finished ok" in done.stdout, done.stderr
    assert not (tmp_path / "p.png").exists()


def test_a_resumed_study_runs_only_the_tasks_not_finished(flight_study, tmp_path):
    from ti_golf.study import run_study
    from ti_golf.study.results import Manifest

    spec, result = flight_study
    folder = tmp_path / "out"
    shutil.copytree(result.folder, folder)
    lines = (folder / "manifest.jsonl").read_text().splitlines()
    dropped = json.loads(lines[1])["id"]
    (folder / "manifest.jsonl").write_text("\n".join(lines[:1] + lines[2:]) + "\n" + lines[1][:20])  # a torn last line
    again = run_study(spec, out=folder, workers=1, log=lambda line: None)
    assert (again.ran, again.skipped, again.failed) == (1, 3, 0)
    assert [r["task_id"] for r in again.rows] == [r["task_id"] for r in result.rows]
    assert [figures_of(r) for r in again.rows] == [figures_of(r) for r in result.rows]
    assert any(r["task_id"] == dropped for r in again.rows)
    # the row run again starts a line of its own after the torn one: read again, all four are there
    assert sorted(Manifest(folder).rows) == sorted(r["task_id"] for r in result.rows)


def test_a_folder_that_holds_another_studys_rows_says_so_and_lists_this_studys(flight_study, tmp_path):
    from ti_golf.study import run_study

    spec, result = flight_study
    folder = tmp_path / "out"
    shutil.copytree(result.folder, folder)
    with open(folder / "manifest.jsonl", "a") as fh:
        fh.write(json.dumps({**GOOD_ROW, "id": "0ther0ther0ther0"}) + "\n")
    lines = []
    again = run_study(spec, out=folder, workers=1, log=lines.append)
    assert (again.ran, again.skipped) == (0, 4)
    assert any(f"also holds 1 task row that {again.spec.name} does not have" in line for line in lines), lines
    assert [r["task_id"] for r in again.rows] == [r["task_id"] for r in result.rows]


def test_a_finished_task_whose_saved_run_is_gone_or_broken_runs_again(tmp_path):
    # its row in results.csv named a file that was missing or cut short, and running the study
    # again skipped the task
    from ti_golf.study.results import MANIFEST, RUNS, Manifest

    (tmp_path / RUNS).mkdir()
    np.savez(tmp_path / RUNS / "a1.npz", x=np.zeros((1, 3)))
    whole = (tmp_path / RUNS / "a1.npz").read_bytes()
    (tmp_path / RUNS / "b2.npz").write_bytes(whole[:100])
    rows = [
        {**GOOD_ROW, "id": "a1", "run_path": f"{RUNS}/a1.npz"},
        {**GOOD_ROW, "id": "b2", "run_path": f"{RUNS}/b2.npz"},
        {**GOOD_ROW, "id": "c3", "run_path": f"{RUNS}/c3.npz"},
        {**GOOD_ROW, "id": "d4", "run_path": ""},  # (a task that saves no run)
    ]
    (tmp_path / MANIFEST).write_text("".join(json.dumps(r) + "\n" for r in rows))
    manifest = Manifest(tmp_path)
    assert [manifest.finished(i) for i in ("a1", "b2", "c3", "d4")] == [True, False, False, True]


@pytest.mark.slow
def test_a_worker_killed_mid_task_is_replaced_and_the_row_equals_an_undisturbed_one(
    flight_study, tmp_path, monkeypatch
):
    from ti_golf.study import run_study
    from ti_golf.study.tasks import KILL_ONCE_ENV

    spec, result = flight_study
    marker = tmp_path / "killed"
    monkeypatch.setenv(KILL_ONCE_ENV, str(marker))  # the workers inherit it: the first task to run kills its worker
    disturbed = run_study(spec, out=tmp_path / "out", workers=2, log=lambda line: None)
    assert marker.exists()  # a worker did die mid-task
    assert disturbed.failed == 0
    assert [figures_of(r) for r in disturbed.rows] == [figures_of(r) for r in result.rows]


def dask_command(*args: str) -> list[str]:
    return [str(Path(sys.executable).parent / "dask"), *args]


@pytest.mark.slow
def test_a_scheduler_and_two_workers_started_by_hand_share_the_tasks(flight_study, tmp_path):
    from ti_golf.study import run_study

    spec, result = flight_study
    scheduler_file = tmp_path / "scheduler.json"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    procs = [
        subprocess.Popen(
            dask_command(
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                str(scheduler_file),
            ),
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    ]
    try:
        deadline = time.monotonic() + 60
        while not scheduler_file.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        for name in ("node-a", "node-b"):
            procs.append(
                subprocess.Popen(
                    dask_command(
                        "worker",
                        "--scheduler-file",
                        str(scheduler_file),
                        "--host",
                        "127.0.0.1",
                        "--nthreads",
                        "1",
                        "--no-dashboard",
                        "--name",
                        name,
                    ),
                    env=env,
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                )
            )
        from distributed import Client

        with Client(scheduler_file=str(scheduler_file), timeout="60s") as client:
            client.wait_for_workers(2, timeout=120)
        by_hand = run_study(spec, out=tmp_path / "out", address=str(scheduler_file), log=lambda line: None)
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            p.wait(timeout=60)
    assert by_hand.failed == 0
    assert len({r["worker"] for r in by_hand.rows}) == 2  # tasks landed on both workers
    assert all(r["worker"].startswith("tcp://127.0.0.1:") for r in by_hand.rows)
    assert [figures_of(r) for r in by_hand.rows] == [figures_of(r) for r in result.rows]


@pytest.mark.slow
def test_ctrl_c_keeps_the_finished_rows_and_a_rerun_completes_the_study(tmp_path):
    # 18 tasks of a tenth of the time step, so that the signal after the second finds most to do
    text = FLIGHT_STUDY.replace('"air.C_D" = "0.2:0.3:0.1"', '"air.C_D" = "0.1:0.5:0.05"')
    text = text.replace('scene = "lab_turbulent"', 'scene = "lab_turbulent"\nset = ["world.dt=0.0001"]')
    path = write(tmp_path, "long.toml", text)
    out = tmp_path / "out"
    proc = subprocess.Popen(
        cli("study", str(path), "--out", str(out), "--workers", "1"),
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=sigint_as_in_a_terminal,
    )
    manifest = out / "manifest.jsonl"
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and not (manifest.exists() and manifest.read_text().count("\n") >= 2):
        time.sleep(0.2)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "run the study again to finish it" in err
    from ti_golf.study.results import read_table

    kept = read_table(out)
    assert 2 <= len(kept["task_id"]) < 18 and set(kept["status"]) == {"ok"}
    done = run_cli("study", str(path), "--out", str(out), "--workers", "2")
    assert done.returncode == 0, done.stderr
    table = read_table(out)
    assert len(table["task_id"]) == 18 and set(table["status"]) == {"ok"}
    assert f"{len(kept['task_id'])} finished before" in done.stdout


def test_the_benchmarks_tasks_are_equal_runs_of_one_scene():
    # `ti-golf bench study` compares Dask with running the same tasks without it: its tasks must
    # be equal (the same scene, steps and precision; only the ids differ, so that Dask runs each)
    # and each run must give the same figures, here run in this process as a worker would
    from ti_golf.study.benchmark import BENCH_SCENE, bench_tasks
    from ti_golf.study.worker import run_task

    tasks = bench_tasks(3, 700)  # 7 s of lab_turbulent's 10 ms steps: the ball lands at 6.8 s
    assert len({t["id"] for t in tasks}) == 3
    assert all({**t, "id": ""} == {**tasks[0], "id": ""} for t in tasks) and tasks[0]["scene"] == BENCH_SCENE
    rows = [run_task(t, None) for t in tasks]
    assert [r["status"] for r in rows] == ["ok"] * 3, rows
    assert [r["carry_m"] for r in rows] == [rows[0]["carry_m"]] * 3
    assert rows[0]["carry_m"] == pytest.approx(212.243, abs=5e-4)  # the report's Appendix A


def test_tasks_that_ask_for_a_gpu_go_to_the_worker_that_has_one(tmp_path):
    # a local cluster of one CPU worker and one worker with the resource GPU = 1 (here without a
    # GPU: its Taichi falls back to the CPU); every task with task.gpu = true lands on the latter
    from ti_golf.study import run_study
    from ti_golf.study.cluster import study_client

    text = FLIGHT_STUDY.replace('until = "landed"', 'until = "landed"\ngpu = true')
    spec = write(tmp_path, "gpu.toml", text)
    with study_client(workers=1, gpus=1, need_gpu=True) as client:
        workers = client.scheduler_info()["workers"]
        with_gpu = [a for a, w in workers.items() if w.get("resources", {}).get("GPU")]
        assert len(workers) == 2 and len(with_gpu) == 1
        result = run_study(spec, out=tmp_path / "out", address=client.scheduler.address, log=lambda line: None)
    assert result.failed == 0 and len(result.rows) == 4
    assert {row["worker"] for row in result.rows} == set(with_gpu)


GOOD_ROW = {"id": "a1", "carry_m": 150.5, "status": "ok", "error": "", "wall_s": 1.5, "host": "h", "run_path": ""}


def test_a_manifest_row_without_one_of_its_figures_runs_again(tmp_path):
    # a row whose figure was deleted counted as finished: the results table had an empty cell
    from ti_golf.study.results import MANIFEST, Manifest

    row = {**GOOD_ROW, "carry_m[PGA Driver]": 250.0}
    (tmp_path / MANIFEST).write_text(json.dumps(row) + "\n")
    manifest = Manifest(tmp_path)
    assert manifest.finished("a1", ("carry",)) and not manifest.finished("a1", ("carry", "apex"))
    del row["carry_m"], row["carry_m[PGA Driver]"]
    (tmp_path / MANIFEST).write_text(json.dumps(row) + "\n")
    assert not Manifest(tmp_path).finished("a1", ("carry",)) and Manifest(tmp_path).finished("a1")


@pytest.mark.parametrize(
    "line, problem",
    [
        ("[1, 2]", "is not a task's row (an object with a string 'id')"),
        (json.dumps({**GOOD_ROW, "status": "done"}), "task a1: 'status' must be 'ok' or 'failed' (got 'done')"),
        (json.dumps({**GOOD_ROW, "carry_m": "abc"}), "task a1: 'carry_m' must be a number (got 'abc')"),
        (json.dumps({**GOOD_ROW, "wall_s": True}), "task a1: 'wall_s' must be a number (got True)"),
        (json.dumps({**GOOD_ROW, "host": 3}), "task a1: 'host' must be text (got 3)"),
        ("garbage {{{", "is not a task's row (not JSON: Expecting value)"),  # (was skipped as if cut short)
        # (an entry no task writes became a column of the results table)
        (json.dumps({**GOOD_ROW, "bogus": 1}), "task a1: 'bogus' is neither a figure nor the task's bookkeeping"),
    ],
)
def test_a_manifest_edited_into_something_else_is_one_error_naming_its_line(tmp_path, line, problem):
    # a study run again reads its manifest: a row it cannot have written ended in a TypeError or in
    # pyarrow's ArrowTypeError once every task had run; a line cut short is still skipped (run again)
    from ti_golf.study.results import MANIFEST, Manifest

    path = tmp_path / MANIFEST
    path.write_text(json.dumps(GOOD_ROW) + "\n" + line + "\n" + '{"id": "b2", "sta' + "\n")
    with pytest.raises(ConfigError) as info:
        Manifest(tmp_path)
    assert str(info.value) == f"{path}:2: {problem}; remove the line (or the file) to run its tasks again"
    path.write_text(json.dumps(GOOD_ROW) + "\n" + '{"id": "b2", "sta' + "\n")
    assert list(Manifest(tmp_path).rows) == ["a1"]
    path.write_bytes(b"\xff\xfe\n")
    with pytest.raises(ConfigError, match="is not UTF-8 text"):
        Manifest(tmp_path)


@pytest.mark.parametrize(
    "options, env, message",
    [
        (["--address", "zzz"], {}, "--address: no Dask scheduler reached through the address 'zzz' (ValueError: "),
        ([], {"TI_GOLF_SCHEDULER": "zzz"}, "TI_GOLF_SCHEDULER: no Dask scheduler reached through the address 'zzz'"),
        (["--address", "EMPTY.json"], {}, "holds no scheduler's address (JSON with an 'address')"),
        (["--address", "NUMBER.json"], {}, "holds no scheduler's address (JSON with an 'address')"),  # (a TypeError)
        (["--workers", "100000"], {}, "--workers: must be a whole number in [1, "),
        (["--gpus", "1"], {}, "--gpus: has no effect: the tasks of flight ask for no GPU"),  # (it ran, exit 0)
        # (found only after every task had run)
        (
            ["--plot", "f.png", "--figure", "nope"],
            {},
            "--figure: is not a figure of flight (got 'nope'); its figures: ",
        ),
    ],
)
def test_a_bad_scheduler_address_or_worker_count_is_one_error(tmp_path, options, env, message):
    # a malformed address ended in distributed's traceback; 100,000 local workers were started
    spec = write(tmp_path, "flight.toml", FLIGHT_STUDY)
    (tmp_path / "EMPTY.json").write_text("")
    (tmp_path / "NUMBER.json").write_text('{"address": 5}')
    options = [str(tmp_path / o) if o.endswith(".json") else o for o in options]
    proc = run_cli("study", str(spec), "--out", str(tmp_path / "out"), *options, env=env)
    assert proc.returncode == 2, proc.stderr
    last = proc.stderr.strip().splitlines()[-1]
    assert last.startswith("ti-golf: error: ") and message in last, proc.stderr
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "out").exists()  # (refused before any task ran; a bad address left an empty table)


def test_the_command_lines_set_replaces_the_files_and_may_not_set_a_varied_key(tmp_path):
    from ti_golf.study.spec import load_study

    text = 'scene = "lab_turbulent"\nset = ["air.C_D=0.25"]\n[grid]\n"air.rho" = [1.1, 1.2]\n'
    spec = write(tmp_path, "s.toml", text)
    (task,) = {t.changes[:1] for t in load_study(spec, ["air.C_D=0.3"]).tasks}
    assert task == ("air.C_D=0.3",)  # the file's 0.25 replaced, not given twice
    with pytest.raises(ConfigError) as info:
        load_study(spec, ["air.rho=1.0"])
    assert (info.value.source, info.value.key) == ("overrides", "air.rho") and "is varied by the study's [grid]" in str(
        info.value
    )
    # a key the task's kind does not read, given on the command line, is named as given there
    with pytest.raises(ConfigError) as info:
        load_study(spec, ["game.wind_max=2"])
    assert (info.value.source, info.value.key) == ("overrides", "game.wind_max"), str(info.value)
    assert "is not read by a task of task.kind = 'run'" in info.value.reason
    # a [task] key given on the command line is named as given there (the study file was blamed)
    for given, reason in (
        ("task.shots=10", "is read only when"),
        ("task.t=-1", "must be in (0, "),
        ("task.t=1", "not both"),
    ):
        with pytest.raises(ConfigError) as info:
            load_study(spec, [given, "task.steps=5"] if given == "task.t=1" else [given])
        assert info.value.source == "overrides" and reason in info.value.reason, str(info.value)


def test_a_ctrl_c_keeps_the_rows_of_tasks_that_finished_while_it_waited(tmp_path, monkeypatch):
    # the Ctrl-C came while the loop waited for the next task: the tasks that had finished since
    # (their rows not yet read) were cancelled with the rest, and ran again in the next run
    import distributed

    from ti_golf.study import runner
    from ti_golf.study.results import Manifest

    spec = load_study(write(tmp_path, "s.toml", FLIGHT_STUDY))

    class Future:
        def __init__(self, task: dict, finished: bool) -> None:
            self.row = {"id": task["id"], "status": "ok", "error": "", "wall_s": 1.0, "run_path": ""}
            self.status = "finished" if finished else "pending"

        def result(self, timeout=None):
            return dict(self.row)

        def done(self) -> bool:
            return self.status == "finished"

    class Client:
        scheduler = type("Scheduler", (), {"address": "inproc://test"})()
        cancelled: list = []

        def scheduler_info(self):
            return {"workers": {"a": {}}}

        def submit(self, fn, task, run_dir, **kwargs):
            return Future(task, finished=task["id"] != spec.tasks[-1].id)  # all but the last finished

        def cancel(self, futures):
            self.cancelled.extend(futures)

    def first_then_ctrl_c(futures):
        yield next(iter(futures))
        raise KeyboardInterrupt

    monkeypatch.setattr(distributed, "as_completed", first_then_ctrl_c)
    manifest, result = Manifest(tmp_path), runner.StudyResult(spec, tmp_path)
    client = Client()
    with pytest.raises(KeyboardInterrupt):
        runner._run(spec, list(spec.tasks), client, tmp_path, manifest, result, log=lambda line: None)
    kept = [t.id for t in spec.tasks if Manifest(tmp_path).finished(t.id)]
    assert kept == [t.id for t in spec.tasks[:-1]] and result.ran == len(spec.tasks) - 1
    assert len(client.cancelled) == 1  # the one still running


def test_a_manifest_row_with_only_its_id_and_status_is_a_row_of_the_table(tmp_path):
    # it passed the manifest's checks, then the table mixed "" with the other rows' times and
    # pyarrow stopped with a traceback
    from ti_golf.study.results import MANIFEST, Manifest, read_table, table_rows, write_table

    spec = load_study(write(tmp_path, "s.toml", FLIGHT_STUDY))
    first, second = spec.tasks[:2]
    rows = [{**GOOD_ROW, "id": first.id}, {"id": second.id, "status": "ok"}]
    (tmp_path / MANIFEST).write_text("".join(json.dumps(r) + "\n" for r in rows))
    write_table(tmp_path, *table_rows(spec.tasks, Manifest(tmp_path), spec.keys))
    table = read_table(tmp_path)
    assert list(table["task_id"]) == [first.id, second.id]
    assert table["wall_s"] == [GOOD_ROW["wall_s"], None]  # (null: no time was recorded)


def test_figure_of_a_tour_study_is_checked_against_its_columns_per_club():
    # `--figure carry_m` passed the check before the tasks ran, then, after all of them, the plot
    # found no such column: a tour study's columns are per club
    from ti_golf.cli.study import _check_figure

    spec = load_study("bag_weather")
    with pytest.raises(ConfigError, match=re.escape("its figures: carry_m[PGA Driver], carry_m[PGA 3-wood]")):
        _check_figure("carry_m", spec)
    _check_figure("carry_m[PGA Driver]", spec)


def test_a_study_folder_whose_manifest_or_runs_is_the_wrong_kind_is_refused_before_its_tasks(tmp_path):
    # a folder holding a directory named manifest.jsonl, or a file named runs, started the cluster
    # and ran tasks, then failed with "manifest.jsonl: Is a directory" or "runs: File exists"
    from ti_golf.study.results import MANIFEST, RUNS

    spec = write(tmp_path, "flight.toml", FLIGHT_STUDY)
    for name, make, said in ((MANIFEST, Path.mkdir, "is not a file"), (RUNS, Path.touch, "is not a folder")):
        out = tmp_path / f"out_{name}"
        out.mkdir()
        make(out / name)
        proc = run_cli("study", str(spec), "--out", str(out))
        assert proc.returncode == 2 and f"{out / name}: {said}" in proc.stderr, proc.stderr
        assert sorted(p.name for p in out.iterdir()) == [name]


def test_a_run_tasks_carry_has_the_sign_of_a_sweeps_for_a_ball_blown_behind_the_tee():
    # a steep shot into a 30 m/s headwind lands 16.5 m behind the tee: the sweep and shot tasks
    # said -16.5 m, the run task +16.5 m, so the study's carry_m column changed sign with task.kind
    import ti_golf as tg
    from ti_golf.study.tasks import run_figures

    sc = tg.load_scene("lab_turbulent", ["launch.angle_deg=80", "launch.speed=20", "air.wind=[-30,0,0]"])
    swept = tg.sweep(sc, angles_deg=[80.0]).carry[0]
    sim = tg.Simulation(sc)
    sim.run(until="landed", t=10)
    assert swept < -10.0
    assert run_figures(sim)["carry"] == pytest.approx(swept, rel=1e-9)  # (the same flight, to round-off)


def test_a_plot_of_a_study_of_three_varied_keys_is_refused_before_any_task_runs(tmp_path, capsys):
    # --figure and --lines were checked before the run, --plot's count of varied keys only after it
    from ti_golf.cli.main import main

    path = write(tmp_path, "s.toml", FLIGHT_STUDY + '"air.rho" = [1.0, 1.2]\n')
    out = tmp_path / "out"
    assert main(["study", str(path), "--out", str(out), "--plot", str(tmp_path / "p.png")]) == 2
    assert "--plot: draws a figure against one or two varied keys (the study varies 3)" in capsys.readouterr().err
    assert not out.exists()


def test_a_study_folder_that_cannot_be_written_is_refused_before_the_cluster_starts(tmp_path, monkeypatch, capsys):
    # a read-only --out was found only once the Dask cluster was up, in words without --out's name
    from ti_golf.cli.main import main

    monkeypatch.setattr("ti_golf.study.runner.write_problem", lambda folder: "Read-only file system")
    path = write(tmp_path, "s.toml", FLIGHT_STUDY)
    assert main(["study", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"--out: cannot write into '{tmp_path / 'out'}': Read-only file system" in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_a_ctrl_c_while_the_local_cluster_starts_stops_the_study(tmp_path, monkeypatch, capsys):
    # Ctrl-C was ignored while the workers started (so that they inherited it ignored), and one
    # that came then was lost: the study ran to its end and exited 0. Now it waits, blocked, and
    # stops the study as the cluster is up, which is closed
    from ti_golf.cli.main import main
    from ti_golf.study import cluster

    started = []

    def interrupted(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)  # (as the workers start)
        started.append(real(*args, **kwargs))
        return started[-1]

    real = cluster._start_local_cluster
    monkeypatch.setattr(cluster, "_start_local_cluster", interrupted)
    path = write(tmp_path, "s.toml", FLIGHT_STUDY)
    assert main(["study", str(path), "--workers", "1", "--out", str(tmp_path / "out")]) == 130
    assert capsys.readouterr().err.strip().splitlines()[-1] == "ti-golf: interrupted before any task ran"
    assert len(started) == 1 and started[0].status.name == "closed"
    assert not (tmp_path / "out").exists()
    assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, set())  # (unblocked again)


def test_a_tasks_identity_follows_the_heights_its_scene_reads(tmp_path):
    # the id hashed the scene's keys, which name the heights file, not its heights: a study run
    # again after the file was edited skipped its tasks as finished and kept the old figures
    from ti_golf.scene.loader import scenes_dir

    for name in ("lab_friction.toml", "lab_friction.npy"):
        shutil.copy(scenes_dir() / name, tmp_path / name)
    path = write(
        tmp_path, "st.toml", 'scene = "lab_friction.toml"\n[task]\nkind = "run"\nt = 2\n[grid]\n"contact.mu" = [0.4]\n'
    )
    before = load_study(path).tasks[0].id
    assert load_study(path).tasks[0].id == before  # (the same heights: the same task)
    heights = np.load(tmp_path / "lab_friction.npy")
    np.save(tmp_path / "lab_friction.npy", heights / 2)
    assert load_study(path).tasks[0].id != before
