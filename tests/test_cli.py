"""The command line end to end: each subcommand in a fresh process, its output checked for content.

Every ``run_cli`` call starts Python and compiles kernels (a few seconds), so each command runs
once in a module-scoped fixture and several tests read its output.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import background
import numpy as np
import pytest
from conftest import (
    MATPLOTLIB_BLUE,
    NO_VULKAN_BACKEND,
    ON_VULKAN,
    ROOT,
    SCENES,
    cli,
    colour_pixels,
    png_rgb,
    run_cli,
    sigint_as_in_a_terminal,
)

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

import ti_golf
from ti_golf.bench.collide import pile_scene
from ti_golf.cli import main
from ti_golf.scene.balls import launch_position
from ti_golf.scene.schema import SCHEMA, TOP_LEVEL
from ti_golf.solvers.solver import REORDER_MIN_BALLS
from ti_golf.solvers.stepping import RELIST_MAX_BALLS, SERIAL_MAX_BALLS

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def viridis(x: float):
    """matplotlib's viridis colour map at ``x`` in [0, 1] (RGBA)."""
    import matplotlib

    return matplotlib.colormaps["viridis"](x)


def ok(proc: subprocess.CompletedProcess) -> subprocess.CompletedProcess:
    assert proc.returncode == 0, (proc.returncode, proc.stdout[-2000:], proc.stderr[-2000:])
    assert "Traceback" not in proc.stderr
    return proc


def read_csv(path: Path) -> tuple[list[str], list[dict[str, float]]]:
    with open(path, newline="") as fh:
        reader = csv.DictReader(fh)
        rows = [{k: float(v) for k, v in row.items()} for row in reader]
        return list(reader.fieldnames or []), rows


# ----------------------------------------------------------------------------------------------
# scenes, keys, --help, unknown subcommand
# ----------------------------------------------------------------------------------------------
def test_version_prints_the_pyproject_version():
    proc = ok(run_cli("--version"))
    version = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["version"]
    assert proc.stdout == f"ti-golf {version}\n" and ti_golf.__version__ == version


def test_scenes_lists_every_scene_with_its_description():
    proc = ok(run_cli("scenes"))
    lines = [ln for ln in proc.stdout.splitlines() if ln.strip()]
    files = sorted(SCENES.glob("*.toml"))
    assert len(lines) == len(files), proc.stdout
    for f in files:
        description = tomllib.loads(f.read_text(encoding="utf-8"))["description"]
        assert description.strip()
        assert any(re.fullmatch(rf"{re.escape(f.stem)}\s+{re.escape(description)}", ln.rstrip()) for ln in lines), (
            f.stem,
            proc.stdout,
        )


def test_scenes_names_the_key_of_a_scene_it_cannot_load(tmp_path):
    (tmp_path / "good.toml").write_text('description = "fine"\n[launch]\nspeed = 10\n')
    (tmp_path / "bad.toml").write_text("[contact]\nmu_rol = 0.1\n")
    proc = ok(run_cli("scenes", env={"TI_GOLF_SCENES": str(tmp_path)}))
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("bad   (invalid: key 'contact.mu_rol' is unknown (did you mean 'mu_roll'?)"), lines
    assert lines[1].split() == ["good", "fine"]


def _keys_rows(stdout: str) -> dict[str, list[str]]:
    """The rows of the `keys` Markdown table by key name, cells split on unescaped pipes."""
    rows: dict[str, list[str]] = {}
    for ln in stdout.splitlines():
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", ln.strip().strip("|"))]
        m = re.fullmatch(r"`([\w.]+)`", cells[0]) if cells else None
        if m:
            assert m.group(1) not in rows, f"key {m.group(1)} printed twice"
            rows[m.group(1)] = cells
    return rows


@pytest.fixture(scope="module")
def keys_output():
    return ok(run_cli("keys")).stdout


def test_keys_prints_every_schema_key_with_its_unit(keys_output):
    rows = _keys_rows(keys_output)
    expected = {f"{s}.{k}": key for s, keys in SCHEMA.items() for k, key in keys.items()}
    expected.update(TOP_LEVEL)
    assert set(rows) == set(expected), set(rows) ^ set(expected)
    for dotted, key in expected.items():
        assert rows[dotted][1] == key.unit, (dotted, rows[dotted])
        if isinstance(key.default, float):
            assert rows[dotted][2] == f"`{key.default}`", (dotted, rows[dotted])
    # spot checks against the SI units the scenes are written in
    assert rows["air.C_D"][1] == "-"
    assert rows["contact.k_p"][1] == "-" and rows["contact.k_p"][3] == "[0, 1]"
    assert rows["world.dt"][1] == "s" and rows["world.dt"][3] == "(0, 1]"
    assert rows["air.wind"][3] == "each in [-1000, 1000]"
    assert rows["ball.mass"][1] == "kg"
    assert rows["air.wind"][1] == "m/s" and rows["air.wind"][2] == "`[0, 0, 0]`"
    assert rows["air.gamma"][3] == "1 or 2"


def test_keys_is_a_well_formed_markdown_table(keys_output):
    rows = _keys_rows(keys_output)
    bad = {k: len(cells) for k, cells in rows.items() if len(cells) != 5}
    assert not bad, f"rows with other than 5 cells: {bad}"
    for section, keys in SCHEMA.items():
        for name, key in keys.items():
            if key.allowed:
                assert rows[f"{section}.{name}"][3].replace("\\|", "|") == key.allowed, (section, name)


@pytest.mark.slow
def test_help_and_unknown_subcommand():
    proc = ok(run_cli("--help"))
    for command in (
        "scenes",
        "keys",
        "sweep",
        "shot",
        "dispersion",
        "run",
        "table",
        "tour",
        "fit-aero",
        "bench",
        "render",
        "play",
    ):
        assert command in proc.stdout
    proc = run_cli("frobnicate")
    assert proc.returncode == 2
    assert "frobnicate" in proc.stderr and "invalid choice" in proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("size", ["0x0", "16x9000", "wide"])
def test_a_bad_picture_size_is_a_usage_error(size, tmp_path):
    # before any simulation, in argparse (no process starts Taichi): one usage line, exit code 2
    for command in (
        ["run", "break_shot", "--steps", "2", "--frames-every", "1", "--frames", str(tmp_path), "--size", size],
        ["render", "break_shot", "--out", str(tmp_path / "p.png"), "--size", size],
    ):
        proc = cli_main_process(command)
        assert proc.returncode == 2, proc.stderr
        assert "--size" in proc.stderr and "Traceback" not in proc.stderr
        assert proc.stderr.strip().splitlines()[-1].startswith("ti-golf: error: argument --size:")


def cli_main_process(args):
    """``ti_golf.cli.main(args)`` as a process would see it: exit code and standard error."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        try:
            code = main(args)
        except SystemExit as exc:
            code = exc.code
    return subprocess.CompletedProcess(args, code, "", err.getvalue())


# ----------------------------------------------------------------------------------------------
# sweep
# ----------------------------------------------------------------------------------------------
SWEEP_COLUMNS = [
    "angle_deg",
    "speed_mps",
    "carry_m",
    "landing_x_m",
    "landing_z_m",
    "apex_height_m",
    "flight_time_s",
    "landing_angle_deg",
    "landing_speed_mps",
]


@pytest.fixture(scope="module")
def turbulent_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    csv_path, png_path = out / "turbulent.csv", out / "turbulent.png"
    proc = ok(
        run_cli("sweep", "lab_turbulent", "--angles", "36:37.4:0.02", "--out", str(csv_path), "--plot", str(png_path))
    )
    header, rows = read_csv(csv_path)
    return proc, header, rows, png_path


def test_sweep_csv_columns_and_rows(turbulent_sweep):
    _, header, rows, _ = turbulent_sweep
    assert set(SWEEP_COLUMNS) <= set(header), header
    assert len(rows) == 71  # 36, 36.02, ..., 37.4
    angles = [r["angle_deg"] for r in rows]
    assert angles[0] == pytest.approx(36.0) and angles[-1] == pytest.approx(37.4)
    assert np.allclose(np.diff(angles), 0.02)
    for r in rows:
        assert all(math.isfinite(r[c]) for c in SWEEP_COLUMNS), r
        assert r["speed_mps"] == 80.0  # the scene's launch speed
        assert r["landing_z_m"] == pytest.approx(0.0, abs=1e-9)  # no wind, no spin: stays in the x-y plane
        assert r["carry_m"] == pytest.approx(r["landing_x_m"], rel=1e-9)
        assert r["apex_height_m"] > 0 and r["flight_time_s"] > 0
        # turbulent drag: the ball comes down steeper and slower than it went up
        assert r["landing_angle_deg"] > r["angle_deg"] and r["landing_speed_mps"] < r["speed_mps"]


def test_sweep_csv_ends_its_lines_as_every_table_written(turbulent_sweep):
    # the dispersion's table (numpy) ends its lines with LF; the sweep's, the round's and the
    # study's (Python's csv module) ended them with CRLF
    csv_path = turbulent_sweep[3].with_suffix(".csv")
    assert b"\r" not in csv_path.read_bytes()
    assert "best angle is the" not in turbulent_sweep[0].stdout  # 36.66 deg lies inside 36 to 37.4


def test_sweep_says_when_its_best_angle_is_an_end_of_the_angles_and_speaks_the_units_asked(capsys):
    assert main(["sweep", "lab_vacuum", "--angles", "30:40:5"]) == 0
    out = capsys.readouterr().out
    assert "lab_vacuum: 3 launch conditions" in out
    assert "the best angle is the highest swept: the longest carry may lie beyond it" in out
    assert main(["sweep", "lab_vacuum", "--angles", "50:60:5"]) == 0
    assert "the best angle is the lowest swept" in capsys.readouterr().out
    assert main(["sweep", "lab_vacuum", "--angles", "45", "--speeds", "44.704"]) == 0
    out = capsys.readouterr().out
    assert "lab_vacuum: 1 launch condition, 1 landed" in out and "best angle is the" not in out
    assert main(["sweep", "tour_shot", "--angles", "16", "--speeds", "44.704", "--units", "imperial"]) == 0
    header, row = capsys.readouterr().out.splitlines()[-2:]
    assert header.split()[:6] == ["angle", "[deg]", "speed", "[mph]", "spin", "[rpm]"]
    assert row.split()[:2] == ["16", "100"]  # 44.704 m/s is 100 mph


def test_sweep_csv_has_one_column_per_quantity_each_with_its_unit(turbulent_sweep):
    # one apex (above the launch point), no total or roll without --to-rest (they would be NaN
    # throughout), every column named with its unit, and every column described on the docs' page
    from ti_golf.sim.results import CSV_COLUMNS

    _, header, rows, _ = turbulent_sweep
    assert header == list(CSV_COLUMNS)
    units = ("_deg", "_mps", "_radps", "_m", "_s")
    assert all(name.endswith(units) for name in header), header
    for name in header:
        assert any(math.isfinite(r[name]) for r in rows), f"{name} is NaN throughout"
    page = (ROOT / "docs" / "results.md").read_text(encoding="utf-8")
    for name in (*header, "total_m", "roll_m"):
        assert f"| `{name}` |" in page, f"{name} is not in the table of docs/results.md"


def test_a_sweep_to_rest_says_which_balls_have_no_total(tmp_path, capsys):
    # in vacuo a ball bounces on without end: rolled out, it has no point of rest by world.t_max,
    # and the command says why its total_m and roll_m are NaN; a scene without ground is refused
    out = tmp_path / "s.csv"
    assert main(["sweep", "lab_vacuum", "--angles", "45", "--to-rest", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert "1 of the 1 balls landed were still moving at world.t_max = 60 s: no total or roll" in said
    header, rows = read_csv(out)
    assert header[-2:] == ["total_m", "roll_m"] and math.isnan(rows[0]["total_m"])
    assert main(["sweep", "lab_vacuum", "--to-rest", "--set", "world.ground=false"]) == 2
    assert "--to-rest: lab_vacuum has no ground to come to rest on" in capsys.readouterr().err


def test_sweep_best_carry_matches_report(turbulent_sweep):
    _, _, rows, _ = turbulent_sweep
    best = max(rows, key=lambda r: r["carry_m"])
    # report Appendix A: turbulent max 212.243 m at 36.6° (Mathematica, 0.2° grid)
    assert best["carry_m"] == pytest.approx(212.243, abs=0.05)
    assert abs(best["angle_deg"] - 36.6) <= 0.2  # within the report's grid spacing


def test_sweep_stdout_names_best_angle(turbulent_sweep):
    proc, _, rows, _ = turbulent_sweep
    best = max(rows, key=lambda r: r["carry_m"])
    m = re.search(r"best: angle ([\d.]+) deg.*carry ([\d.]+) m", proc.stdout)
    assert m, proc.stdout
    assert float(m.group(1)) == pytest.approx(best["angle_deg"], abs=1e-4)
    assert float(m.group(2)) == pytest.approx(best["carry_m"], abs=1e-3)
    assert "71 launch conditions" in proc.stdout


@ON_VULKAN
def test_the_sweep_runs_on_a_gpu_backend():
    # Vulkan (in software in CI: mesa's lavapipe) compiles kernels as a GPU does. The sweep kernel
    # was compiled there without Taichi's IR passes, as on the CPU (see runtime.plain_compile), and
    # Taichi's SPIR-V code generator then stopped with "Not supported" and a traceback.
    proc = run_cli("sweep", "lab_turbulent", "--angles", "36.6", "--arch", "vulkan")
    if "running on the CPU" in proc.stderr:  # (runtime.init's note when Taichi finds no Vulkan)
        pytest.skip(NO_VULKAN_BACKEND)
    assert proc.returncode == 0, proc.stderr[-2000:]
    m = re.search(r"best: angle ([\d.]+) deg.*carry ([\d.]+) m", proc.stdout)
    assert m, proc.stdout
    # report Appendix A: 212.243 m at 36.6° (turbulent drag, Mathematica), to its printed digits
    assert float(m.group(2)) == pytest.approx(212.243, abs=5e-4)


def test_sweep_writes_png(turbulent_sweep):
    # left, the trajectories in viridis from the first angle's purple to the last's yellow; right,
    # carry against angle in matplotlib's blue, with the best angle's red star on the curve's top
    *_, png_path = turbulent_sweep
    img = png_rgb(png_path)
    w = img.shape[1]
    left, right = img[:, : int(0.6 * w)], img[:, int(0.62 * w) :]
    for end in (0.0, 1.0):
        assert colour_pixels(left, viridis(end)[:3], tol=0.1).sum() > 30, f"no trajectory in viridis({end})"
    curve, star = colour_pixels(right, MATPLOTLIB_BLUE), colour_pixels(right, (1.0, 0.0, 0.0))
    assert curve.sum() > 200 and star.sum() > 20, (curve.sum(), star.sum())
    rows, cols = np.nonzero(curve)
    top = np.argmin(rows)  # the highest carry drawn
    star_rows, star_cols = np.nonzero(star)
    assert np.min(np.hypot(star_rows - rows[top], star_cols - cols[top])) < 6.0  # the star marks it


@pytest.mark.slow
def test_sweep_speeds_and_spins_grid(tmp_path):
    csv_path = tmp_path / "magnus.csv"
    ok(run_cli("sweep", "lab_magnus", "--speeds", "60,80", "--spins", "0,10", "--out", str(csv_path)))
    _, rows = read_csv(csv_path)
    angles = ti_golf.load_scene("lab_magnus").sweep.angles  # the scene's default [sweep] angles
    assert angles and len(rows) == len(angles) * 2 * 2
    combos = {(r["speed_mps"], r["spin_radps"]) for r in rows}
    assert combos == {(60.0, 0.0), (60.0, 10.0), (80.0, 0.0), (80.0, 10.0)}
    carry = {c: np.array([r["carry_m"] for r in rows if (r["speed_mps"], r["spin_radps"]) == c]) for c in combos}
    for c, values in carry.items():
        assert len(values) == len(angles) and np.all(np.isfinite(values)), c
    # faster balls fly further; backspin (Magnus lift) carries further at these low angles
    assert np.all(carry[(80.0, 0.0)] > carry[(60.0, 0.0)])
    assert np.all(carry[(80.0, 10.0)] > carry[(80.0, 0.0)])
    assert np.all(carry[(60.0, 10.0)] > carry[(60.0, 0.0)])
    # report Table 3.1-1: turbulent flow with Magnus, 80 m/s, omega0 = 10 rad/s -> 244 m (0.5° grid)
    assert abs(carry[(80.0, 10.0)].max() - 244.0) < 1.0


# ----------------------------------------------------------------------------------------------
# run
# ----------------------------------------------------------------------------------------------
def test_run_spin_decay_npz_and_plot(tmp_path):
    npz_path, png_path = tmp_path / "spin.npz", tmp_path / "spin.png"
    proc = ok(
        run_cli(
            "run",
            "lab_spin_decay",
            "--t",
            "2",
            "--record-every",
            "100",
            "--out",
            str(npz_path),
            "--plot",
            str(png_path),
        )
    )
    scene = ti_golf.load_scene("lab_spin_decay")
    dt = scene.world.dt
    assert dt == 0.001
    with np.load(npz_path) as d:
        data = {k: d[k] for k in d.files}
    for name in ("x", "v", "w"):
        assert data[name].shape == (1, 3), (name, data[name].shape)
        assert np.all(np.isfinite(data[name]))
    assert data["t"].shape == ()
    assert abs(float(data["t"]) - 2.0) <= dt
    n_samples = round(2.0 / (dt * 100)) + 1  # the launch sample plus one every 100 steps
    assert data["traj_x"].shape == (n_samples, 1, 3)
    assert data["traj_w"].shape == (n_samples, 1, 3)
    assert np.allclose(np.diff(data["traj_t"]), 100 * dt)
    # the recording starts at the launch and ends at the saved state
    assert np.allclose(data["traj_x"][0, 0], launch_position(scene))
    assert np.allclose(data["traj_w"][0, 0], scene.launch.spin)
    assert np.allclose(data["traj_x"][-1], data["x"]) and np.allclose(data["traj_w"][-1], data["w"])
    # still in the air after 2 s (40 m/s at 40°), moving downrange
    assert data["x"][0, 1] > scene.ball.radius and data["x"][0, 0] > 20.0
    # spin decay (C_omega = 1): |w| shrinks monotonically from the launch value
    spin = np.linalg.norm(data["traj_w"][:, 0], axis=1)
    assert np.linalg.norm(data["w"][0]) < 0.9 * np.linalg.norm(scene.launch.spin)
    assert np.all(np.diff(spin) < 0)
    # the plot: the trajectory above, |ω| against t below, the one ball in matplotlib's blue; the
    # lower curve falls from left to right as the spin decays
    img = png_rgb(png_path)
    half = img.shape[0] // 2
    upper, lower = colour_pixels(img[:half], MATPLOTLIB_BLUE), colour_pixels(img[half:], MATPLOTLIB_BLUE)
    assert upper.sum() > 100 and lower.sum() > 100, (upper.sum(), lower.sum())
    rows, cols = np.nonzero(lower)
    first, last = cols <= np.percentile(cols, 10), cols >= np.percentile(cols, 90)
    assert rows[first].mean() < rows[last].mean() - 20  # drawn higher at the launch than at t = 2 s
    assert "1 flying" in proc.stdout


@pytest.mark.slow
def test_run_reports_the_deepest_overlap(tmp_path):
    # two balls at rest overlapping by Δx = 4 mm (20 % of a radius), no gravity: one step moves each
    # by k_p·m_red·Δx (B.18, m_red = 1/2) apart and leaves (1 − k_p)·Δx = 3.2 mm (16 %) with k_p = 0.2
    # (the Jacobi sweep: B.18 as the report has it; the Gauss–Seidel sweeps, the default, go further)
    scene = tmp_path / "overlap.toml"
    scene.write_text(
        textwrap.dedent("""\
        [ball]
        radius = 0.02
        mass = 0.045
        [air]
        rho = 0.0
        [world]
        dt = 0.001
        gravity = [0.0, 0.0, 0.0]
        ground = false
        [contact]
        k_p = 0.2
        solver = "jacobi"
        [[balls]]
        position = [0.0, 1.0, 0.0]
        [[balls]]
        position = [0.036, 1.0, 0.0]
        """)
    )
    proc = ok(run_cli("run", str(scene), "--steps", "1"))
    m = re.search(r"deepest overlap: ([0-9.]+) % of a radius \(([0-9.]+) mm, balls 0 and 1\)", proc.stdout)
    assert m, proc.stdout
    assert float(m[1]) == pytest.approx(16.0, abs=0.05) and float(m[2]) == pytest.approx(3.2, abs=0.005)
    scene.write_text(scene.read_text().replace("0.036", "0.041"))  # 1 mm apart
    assert "no two balls overlap" in ok(run_cli("run", str(scene), "--steps", "1")).stdout


@pytest.mark.slow
def test_run_reports_the_distance_to_the_hole(tmp_path):
    # a scene with a [hole] ends with each ball's horizontal distance from the cup, as the saved
    # state gives it
    out = tmp_path / "putt.npz"
    proc = ok(run_cli("run", "putting_green", "--t", "3", "--out", str(out)))
    m = re.search(r"ball 0: ([0-9.]+) m from the hole at x = 6 m, z = 0 m", proc.stdout)
    assert m, proc.stdout
    with np.load(out) as d:
        x = d["x"][0]
    assert float(m[1]) == pytest.approx(math.hypot(x[0] - 6.0, x[2]), abs=0.005)
    assert "carry" not in proc.stdout  # a putt is not a flight


# ----------------------------------------------------------------------------------------------
# table
# ----------------------------------------------------------------------------------------------
# report Table 3.1-1 (best angle [deg], distance [m] on a 0.5° grid) and the maxima of Appendix A
REPORT_TABLE = [
    # (table angle, table distance, expected maximum, source of the maximum)
    (45.0, 652, 652.4, "report Appendix A: in vacuo max 652.396 m (= v0²/g)"),
    (44.5, 626, 626.18, "report Appendix A: laminar max 626.179 m at 44.4°"),
    (36.5, 212, 212.24, "report Appendix A: turbulent max 212.243 m at 36.6°"),
    (11.5, 244, 244.5, "report Table 3.1-1 gives 244 m at 11.5° (0.5° grid); 244.5 m is the finer-grid maximum"),
]


@pytest.mark.slow
def test_table_reproduces_report():
    proc = ok(run_cli("table"))
    row_re = re.compile(r"^(?P<label>\S.*?)\s+(?P<ra>[\d.]+)°\s+(?P<rd>\d+) m\s+(?P<a>[\d.]+)°\s+(?P<d>[\d.]+) m\s*$")
    rows = [m for m in (row_re.match(ln) for ln in proc.stdout.splitlines()) if m]
    assert len(rows) == 4, proc.stdout
    for m, (angle, dist, expected, source) in zip(rows, REPORT_TABLE):
        # the report's columns are transcribed correctly
        assert float(m["ra"]) == angle and int(m["rd"]) == dist, m.group(0)
        # the maximum agrees with the report (see REPORT_TABLE for each number's source)
        assert float(m["d"]) == pytest.approx(expected, abs=0.1), (source, m.group(0))
        # the report's best angle is the best of a 0.5° grid: for a single-peaked carry curve the
        # true optimum lies within 0.5° of it
        assert abs(float(m["a"]) - angle) < 0.5, m.group(0)


# ----------------------------------------------------------------------------------------------
# tour and fit-aero: the TrackMan tour averages and the fit of the spin_reynolds air
# ----------------------------------------------------------------------------------------------
TOUR_ROW = re.compile(
    r"^(?P<name>(PGA|LPGA) \S+)\s+(?P<mph>\d+)\s+[\d.]+\s+\d+ \|\s+(?P<carry>\d+)\s+(?P<model_carry>[\d.]+)\s+"
    r"(?P<carry_err>[+-][\d.]+)% \|\s+(?P<apex>\d+)\s+(?P<model_apex>[\d.]+)\s+[+-][\d.]+ \|\s+(?P<land>\d+)\s+"
    r"(?P<model_land>[\d.]+)\s+[+-][\d.]+(?P<mark>  \*)?$"
)


@pytest.mark.slow
def test_tour_prints_the_23_rows_beside_the_table_and_plots_them(tmp_path, capsys):
    png = tmp_path / "tour.png"
    proc = ok(run_cli("tour", "--plot", str(png)))
    rows = [m for m in (TOUR_ROW.match(ln) for ln in proc.stdout.splitlines()) if m]
    from ti_golf.golf.tour import fly_tour
    from ti_golf.golf.trackman import TOUR

    assert [m["name"] for m in rows] == [r.name for r in TOUR], proc.stdout
    # the table's columns are the data module's, and the model's are what the API flies
    flight = fly_tour(ti_golf.load_scene("tour_shot"))
    for m, r, carry, apex, land in zip(rows, TOUR, flight.carry, flight.apex, flight.land):
        assert (int(m["mph"]), int(m["carry"]), int(m["apex"]), int(m["land"])) == (
            r.ball_mph,
            r.carry_yd,
            r.apex_yd,
            r.land_deg,
        )
        assert (float(m["model_carry"]), float(m["model_apex"]), float(m["model_land"])) == pytest.approx(
            (carry, apex, land), abs=0.051
        )
        assert float(m["carry_err"]) == pytest.approx(100 * (carry / r.carry_yd - 1), abs=0.051)
    marked = sum(bool(m["mark"]) for m in rows)
    assert f"{23 - marked} of 23 rows within 3 % carry, 2 yd apex and 2° land angle" in proc.stdout
    # the plot: three panels (carry, apex, land angle errors), a bar for each row, red where the
    # row misses that figure's target: as many red bars in each panel as the rows it misses
    table = np.array([(r.carry_yd, r.apex_yd, r.land_deg) for r in TOUR])
    misses = (
        np.abs(100 * (flight.carry / table[:, 0] - 1)) > 3.0,
        np.abs(flight.apex - table[:, 1]) > 2.0,
        np.abs(flight.land - table[:, 2]) > 2.0,
    )
    img = png_rgb(png)
    red = colour_pixels(img, (0xD6 / 255, 0x27 / 255, 0x28 / 255))
    for k, (panel, missed) in enumerate(zip(np.array_split(red, 3, axis=0), misses)):
        columns = np.concatenate([[0], panel.any(axis=0).astype(int), [0]])
        bars = int(np.count_nonzero(np.diff(columns) == 1))  # runs of columns holding red
        assert bars == int(missed.sum()), f"panel {k}: {bars} red bars, {int(missed.sum())} rows missed"
    # --rows picks a tour; a scene key the air model does not read is refused
    lpga = ok(run_cli("tour", "--rows", "lpga", "--set", 'air.model="spin_ratio"', "--set", "air.C_omega=0.03"))
    assert [m["name"] for m in map(TOUR_ROW.match, lpga.stdout.splitlines()) if m] == [r.name for r in TOUR[12:]]
    assert main(["tour", "--set", 'air.model="lab"', "--set", "air.viscosity=2e-5"]) == 2
    err = capsys.readouterr().err
    assert "air.viscosity" in err and "spin_reynolds" in err, err


@pytest.mark.slow
def test_fit_aero_finds_the_bundled_coefficients_from_its_start():
    # the documented, repeatable fit: from Ferguson's coefficients it finds the defaults that
    # tour_shot flies (schema.SPIN_REYNOLDS_*), to the 4 decimals printed, within published ranges
    from ti_golf.scene.schema import SPIN_REYNOLDS_C_D, SPIN_REYNOLDS_C_L, SPIN_REYNOLDS_CRISIS

    proc = ok(run_cli("fit-aero"))
    out = proc.stdout
    assert "converged after" in out and "OUTSIDE" not in out, out
    assert f"C_D_S = [{', '.join(f'{c:.4f}' for c in SPIN_REYNOLDS_C_D)}]" in out, out
    assert f"C_L_S = [{', '.join(f'{c:.4f}' for c in SPIN_REYNOLDS_C_L)}]" in out, out
    assert f"C_D_crisis = {SPIN_REYNOLDS_CRISIS[0]:.4f}" in out and f"Re_crisis = {SPIN_REYNOLDS_CRISIS[1]:.4g}" in out
    assert len([ln for ln in out.splitlines() if TOUR_ROW.match(ln)]) == 23


def test_fit_aero_refuses_an_air_model_it_would_replace(capsys):
    # it fits spin_reynolds whatever --set air.model said, and said nothing
    assert main(["fit-aero", "--set", "air.model=lab"]) == 2
    assert "key 'air.model' has no effect with fit-aero" in capsys.readouterr().err


def test_a_run_takes_numpys_scalars_for_its_time():
    # run(t=np.int64(1)) was refused as not a number of seconds, while step() and set() took them
    sim = ti_golf.Simulation("lab_vacuum")
    sim.run(t=np.float64(0.05))
    sim.run(t=np.int64(0))
    assert sim.step_count == 5
    sim.run(t=np.float32(0.5))  # (0.5 exactly in f32)
    assert sim.step_count == 55


def test_fit_aero_without_scipy_says_what_it_needs(capsys, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "scipy.optimize", None)  # import scipy.optimize raises ImportError
    assert main(["fit-aero"]) == 2
    err = capsys.readouterr().err
    assert "needs scipy" in err and "ti-golf[fit]" in err and len(err.strip().splitlines()) == 1, err


# ----------------------------------------------------------------------------------------------
# bench
# ----------------------------------------------------------------------------------------------
@pytest.mark.slow  # a benchmark's process: 2,000 trajectories timed
def test_bench_sweep_json():
    proc = ok(run_cli("bench", "sweep", "--n", "2000", "--repeats", "1", "--json"))
    last = proc.stdout.strip().splitlines()[-1]
    result = json.loads(last)
    assert result["n"] == 2000 and result["landed_fraction"] == 1.0
    # the rate is the launches over the timed seconds (JSON keeps 6 significant digits)
    assert result["trajectories_per_s"] == pytest.approx(2000 / result["seconds"], rel=1e-4)
    # RK4 at h = 0.1 s against DOP853 at rtol 1e-12: an O(h⁴) error of about 1e-6 of the carry,
    # neither zero (the engine compared with itself) nor above the 1e-5 target
    assert 1e-9 < result["max_rel_carry_error"] < 1e-5
    baselines = result["baselines"]
    assert set(baselines) == set(result["speedup"]) == {"numpy_rk4_vectorised", "scipy_solve_ivp_dop853"}
    for name, rate in baselines.items():
        assert result["speedup"][name] == pytest.approx(result["trajectories_per_s"] / rate, rel=1e-3), name
    # one adaptive DOP853 solve per launch is far slower per launch than numpy stepping them all at once
    assert baselines["scipy_solve_ivp_dop853"] < 0.2 * baselines["numpy_rk4_vectorised"]


def test_bench_reductions_times_both_ways_and_checks_them_against_numpy():
    # in this process: the two reductions of a build, both ways their threads meet, beside a loop
    # that reduces nothing; the CLI's JSON names the way this backend takes
    from ti_golf.bench.reductions import bench_reductions
    from ti_golf.solvers.sort import fold_in_array

    lines = []
    result = bench_reductions(n=3001, repeats=2, log=lines.append)
    assert result["n"] == 3001 and result["repeats"] == 2
    assert result["chosen"] == ("in_array" if fold_in_array() else "own_variables")
    for way in ("own_variables", "in_array"):
        figures = result[way]
        assert figures["agree_with_numpy"], way
        assert figures["cell_bounds_ms"] > 0 and figures["apart_balls_ms"] > 0
    assert result["baselines"]["one_cell_a_ball_ms"] > 0
    assert result["probes"]["agree_with_numpy"] and result["probes"]["i32_sum_ms"] > 0
    assert any("(the default here)" in line for line in lines)
    json.loads(json.dumps(result))
    assert main(["bench", "reductions", "--repeats", "0"]) == 2  # (refused before anything runs)


@pytest.mark.slow
def test_bench_pit_pours_the_scene_and_reports_the_piles_quality():
    # the bundled pour scaled down (the bin narrowed so the pile is as deep), in this process
    from ti_golf.bench.pit import PIT_BALLS, _measure_stretch, _scaled_simulation, bench_pit, pit_scene

    full, side = pit_scene()
    assert full.blocks[0].number == PIT_BALLS and side == pytest.approx(2.0)
    small, small_side = pit_scene(1000)
    assert small_side == pytest.approx(2.0 * (1000 / PIT_BALLS) ** 0.5)
    lo, hi = small.blocks[0].box_min, small.blocks[0].box_max
    assert 0 < lo[0] < hi[0] < small_side and lo[1] == full.blocks[0].box_min[1]  # as high, narrower
    assert pit_scene(1000, ["contact.e=0.8"])[0].contact.e == 0.8 != small.contact.e  # --set reaches the scene
    lines = []
    result = bench_pit(n=1000, t=0.05, overrides=["contact.mu=0.5"], log=lines.append, every=0.02)
    assert result["n"] == 1000 and result["steps"] == 50 and result["t_s"] == pytest.approx(0.05)
    # --every: stretches of 20, 20 and 10 steps, whose wall times make up the pour's
    timeline = result["timeline"]
    assert [row["t_s"] for row in timeline] == pytest.approx([0.02, 0.04, 0.05])
    assert sum(row["wall_s"] for row in timeline) == pytest.approx(result["wall_s"], rel=1e-12)
    # each stretch's rebuilds are the solver's: the same pour replayed stretch by stretch, its pile
    # measured after each as the benchmark measures it, rebuilds as often (the run is repeatable)
    replay, rebuilds = _scaled_simulation(pit_scene(1000, ["contact.mu=0.5"])[0], 1000), []
    for steps in (20, 20, 10):
        before = replay.solver.rebuilds
        replay.step(steps)
        _measure_stretch(replay, small_side)
        rebuilds.append(replay.solver.rebuilds - before)
    assert [row["rebuilds"] for row in timeline] == rebuilds and min(rebuilds) > 0 and max(rebuilds) <= 21
    assert result["steps_asleep"] == 0 and [row["steps_asleep"] for row in timeline] == [0, 0, 0]  # none skipped
    assert {k: timeline[-1][k] for k in ("deepest_overlap", "p99_speed_mps", "asleep_fraction")} == {
        k: result[k] for k in ("deepest_overlap", "p99_speed_mps", "asleep_fraction")
    }
    assert result["set"] == ["contact.mu=0.5"]
    # the rates are the pour's: 1,000 balls × 50 steps, 0.05 simulated seconds, over its wall time
    assert result["wall_s"] > 0 and result["compile_s"] > 0
    assert result["ball_steps_per_s"] == pytest.approx(1000 * 50 / result["wall_s"], rel=1e-9)
    assert result["sim_s_per_wall_s"] == pytest.approx(0.05 / result["wall_s"], rel=1e-6)
    # (its memory figure is checked in a process of its own: test_bench_pit_memory_is_the_piles_arrays)
    # the tables' room beside what they hold: the pairs of the last build fit in the pair tables
    # and in the neighbour table's rows, a ball's row as wide as the longest list
    assert 0 < result["pairs_listed"] <= result["pair_table_room"]
    assert result["neighbour_table_width"] >= 1
    assert result["pairs_listed"] <= 1000 * result["neighbour_table_width"]
    assert result["outside_bin"] == 0
    # still falling at 0.05 s: dropped at 1 ± 0.3 m/s per component, plus g·t
    assert 1.0 < result["p99_speed_mps"] < 1.0 + 0.3 * 3**0.5 + 9.81 * 0.05 + 1e-9
    assert 0.0 <= result["asleep_fraction"] <= 1.0 and 0.0 <= result["deepest_overlap"] < 1.0
    # a step does far more than one bare gather over the same balls (forces, lists, sweeps, projections)
    gather = result["baselines"]["bare_gather_balls_per_s"]
    assert result["step_cost_in_bare_gathers"] == pytest.approx(gather / result["ball_steps_per_s"], rel=1e-9)
    assert result["step_cost_in_bare_gathers"] > 1.0
    assert any("deepest overlap" in line for line in lines)
    # the loop probe's figures; a share of the sweeps' loops only with the parallel sweeps (1,000 balls: serial)
    assert result["loop_s"] >= 0.0 and result["ball_loop_s"] >= 0.0 and "sweep_loops_share" not in result
    json.loads(json.dumps(result))


def test_bench_pits_loop_probe_runs_the_loops_it_says():
    # the probe behind loop_s and ball_loop_s: loops over no item run no thread, loops over the
    # balls a thread a ball (a ball whose rest timer reads negative raises the flag it tests)
    from ti_golf.bench.pit import _loops, _scaled_simulation, loop_costs, pit_scene

    sim = _scaled_simulation(pit_scene(300)[0], 300)
    sim.step(1)
    solver = sim.solver
    lists, scratch = solver.packs.lists(solver), solver.packs.scratch(solver)
    for every_ball, raised in ((False, 0), (True, 1)):
        solver.flag[1] = 0
        solver.calm[299] = -2.0  # (the last ball: a loop over every ball reaches it)
        _loops(lists, scratch, 2, every_ball)
        assert solver.flag[1] == raised, every_ball
    solver.forget_quiet()  # (the rest timers as a step leaves them)
    costs = loop_costs(lists, scratch)
    assert set(costs) == {"loop_s", "ball_loop_s"} and all(0.0 <= c < 0.1 for c in costs.values())


@pytest.mark.slow
@ON_VULKAN
def test_bench_pit_runs_on_vulkan():
    # the loop probe behind loop_s started its loops at a bound read on the device, which Taichi's
    # SPIR-V code generator refuses: the pour ran, then a traceback lost its figures
    proc = run_cli("bench", "pit", "--n", "100", "--t", "0.01", "--arch", "vulkan", "--json")
    if "running on the CPU" in proc.stderr:  # (runtime.init's note when Taichi finds no Vulkan)
        pytest.skip(NO_VULKAN_BACKEND)
    assert proc.returncode == 0, proc.stderr[-2000:]
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["arch"] == "vulkan" and result["steps"] == 10 and result["ball_loop_s"] >= 0.0


@pytest.mark.slow
def test_an_interrupted_bench_pit_reports_the_pour_so_far(monkeypatch, capsys):
    # Ctrl-C or SIGTERM 30 steps into a 50-step pour: Simulation.run ends after the whole step it
    # reached and raises KeyboardInterrupt (stood in for here); the benchmark still prints its
    # figures for those 30 steps, its last stretch ending there, and the command exits with 130
    # without asking for another step
    from ti_golf.bench import pit

    asked_after = []

    class InterruptedAfter30Steps(pit.Simulation):
        def run(self, *, steps: int, **kwargs) -> None:
            if self.n != 300:  # the warm-up pour
                return super().run(steps=steps, **kwargs)
            left = 30 - self.state.steps
            if left <= 0:
                asked_after.append(steps)
            super().run(steps=min(steps, left), **kwargs)
            if steps > left:
                raise KeyboardInterrupt

    monkeypatch.setattr(pit, "Simulation", InterruptedAfter30Steps)
    assert main(["bench", "pit", "--n", "300", "--t", "0.05", "--every", "0.02", "--json"]) == 130
    out, err = capsys.readouterr()
    result = json.loads(out.strip().splitlines()[-1])
    assert result["interrupted"] is True and result["steps"] == 30 and result["t_s"] == pytest.approx(0.03)
    assert asked_after == []  # the pour ended at the interrupted stretch's row
    assert [row["t_s"] for row in result["timeline"]] == pytest.approx([0.02, 0.03])
    # (the JSON's figures carry 6 digits)
    assert sum(row["wall_s"] for row in result["timeline"]) == pytest.approx(result["wall_s"], rel=1e-5)
    assert result["ball_steps_per_s"] == pytest.approx(300 * 30 / result["wall_s"], rel=1e-5)
    assert "interrupted at t = 0.03 s" in out
    assert err.strip().splitlines()[-1] == (
        "ti-golf: interrupted at t = 0.03 s; the figures of the pour so far are printed above"
    )


@pytest.mark.slow
def test_bench_pit_interrupted_while_it_measures_the_pile_keeps_that_stretch(monkeypatch, capsys):
    # SIGTERM while the pile is measured at the end of the first stretch (t = 0.02 s): the signal
    # waits for the stretch's row, then the pour ends there, with its figures printed, code 130
    from ti_golf.bench import pit

    measure, calls = pit.pile_quality, []

    def signalled_measure(*args, **kwargs):
        if not calls:
            os.kill(os.getpid(), signal.SIGTERM)  # arrives while the pile is first measured
        calls.append(1)
        return measure(*args, **kwargs)

    monkeypatch.setattr(pit, "pile_quality", signalled_measure)
    assert main(["bench", "pit", "--n", "300", "--t", "0.05", "--every", "0.02", "--json"]) == 130
    out, err = capsys.readouterr()
    result = json.loads(out.strip().splitlines()[-1])
    assert result["interrupted"] is True and result["steps"] == 20
    assert [row["t_s"] for row in result["timeline"]] == pytest.approx([0.02])
    assert err.strip().splitlines()[-1].startswith("ti-golf: interrupted at t = 0.02 s;")


@pytest.mark.slow
def test_a_second_ctrl_c_while_bench_pit_takes_its_figures_still_gets_them_printed(monkeypatch, capsys):
    # Ctrl-C ended the pour after its first stretch; a second one while the figures were taken
    # (here as the pair tables are read) raised out of the benchmark and lost them all
    from ti_golf.bench import pit

    tables, calls = pit.pair_tables, []

    def signalled_tables(sim):
        if not calls:
            os.kill(os.getpid(), signal.SIGINT)
        calls.append(1)
        return tables(sim)

    def interrupted_at_the_first_row(sim, side):
        os.kill(os.getpid(), signal.SIGINT)  # (held while the row is measured: the pour ends there)
        return quality(sim, side)

    quality = pit._measure_stretch
    monkeypatch.setattr(pit, "_measure_stretch", interrupted_at_the_first_row)
    monkeypatch.setattr(pit, "pair_tables", signalled_tables)
    assert main(["bench", "pit", "--n", "300", "--t", "0.05", "--every", "0.02", "--json"]) == 130
    out, err = capsys.readouterr()
    result = json.loads(out.strip().splitlines()[-1])
    assert calls == [1] and result["interrupted"] is True and result["steps"] == 20
    assert "baselines" in result and result["deepest_overlap"] >= 0.0
    assert "taking the figures of the pour so far" in err


PARALLEL_PIT = SERIAL_MAX_BALLS + 1
"""Balls of the benchmarks' piles that take the parallel step: more than ``SERIAL_MAX_BALLS``."""

background.declare("bench-pit-memory", lambda _: (cli("bench", "pit", "--n", "1000", "--t", "0.05", "--json"), {}))


@pytest.mark.parametrize("n", [16, 17, 100, 101, 150, 562, 563])
def test_the_pit_scaled_to_any_count_in_its_range_holds_its_balls(n):
    # the bin scaled to 16 balls was narrower than a ball, and its box held no 100 to 150 balls
    # (a whole number of sites across); now at least MIN_SIDE wide, and raised until it holds them
    from ti_golf.bench.pit import MIN_SIDE, pit_scene
    from ti_golf.scene.balls import build_balls

    scene, side = pit_scene(n)
    assert side >= MIN_SIDE - 1e-12 and len(build_balls(scene).x) == n
    assert side == pytest.approx(max(MIN_SIDE, 2.0 * (n / 100_000) ** 0.5))  # (as deep a pile, when wide enough)


@pytest.mark.background("bench-pit-memory")
def test_bench_pit_memory_is_the_piles_arrays(background_runs):
    # In a process of its own: a pytest worker's memory after other tests' piles (Taichi's pools,
    # pages freed or not) moved this figure by thousands of bytes a ball. The warm-up compiled the
    # pour's kernels, as it steps, so what the pour adds is its arrays and the pools they come
    # from: a few hundred bytes a ball at 100,000 balls (docs: about 400), a few thousand at
    # 1,000 balls, whose fixed costs (the grid's cells, the kernels' launch records) weigh more.
    proc = ok(background_runs.result("bench-pit-memory")[0])
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["n"] == 1000 and result["steps"] == 50 and not result["interrupted"]
    assert result["peak_rss_bytes"] >= result["bytes_per_ball_above_baseline"] * 1000
    assert 100 < result["bytes_per_ball_above_baseline"] < 5000


background.declare(
    "bench-pit-profile",
    lambda _: (
        cli("bench", "pit", "--n", str(PARALLEL_PIT), "--t", "0.005", "--every", "0.003", "--profile", "--json"),
        {},
    ),
)


@pytest.mark.background("bench-pit-profile")
def test_bench_pit_profile_counts_every_launch_of_the_step(background_runs):
    # Taichi's kernel profiler on: each kernel's seconds and launches, in all and per stretch. The
    # step's launches are the solver's: per step 2 of collision_step (the free flight with the
    # warm start, and the last part), one Gauss–Seidel sweep per phase of colour.step_phases and
    # colour.PROJECTIONS projection passes; one or two listings per rebuild the steps made (more
    # balls than SERIAL_MAX_BALLS: the parallel step; a build lists again once it has widened the
    # table that a list overflowed, CollisionSolver._list_balls)
    from ti_golf.solvers.colour import PROJECTIONS, step_phases

    proc = ok(background_runs.result("bench-pit-profile")[0])
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    steps, kernels = result["steps"], result["kernels"]
    assert result["n"] == PARALLEL_PIT and steps == 5
    assert kernels["collision_step"]["launches"] == 2 * steps
    assert kernels["gauss_seidel_sweep"]["launches"] == len(step_phases(4)) * steps
    assert kernels["project_sweep"]["launches"] == PROJECTIONS * steps
    assert 1 <= kernels["list_neighbours"]["launches"] <= 2 * sum(row["rebuilds"] for row in result["timeline"])
    total = result["kernel_profiler"]["kernel_s"]
    assert total == pytest.approx(sum(k["s"] for k in kernels.values()), rel=1e-4)
    assert 0.0 < total < result["wall_s"] and result["kernel_profiler"]["host_s"] == pytest.approx(
        result["wall_s"] - total, rel=1e-4, abs=1e-6
    )
    # the stretches (3 steps, then 2) add up to the whole
    assert [round(row["t_s"], 6) for row in result["timeline"]] == [0.003, 0.005]
    assert sum(row["kernel_s"] for row in result["timeline"]) == pytest.approx(total, rel=1e-4)
    for name in ("gauss_seidel_sweep", "list_neighbours"):
        by_stretch = sum(row["kernels"].get(name, 0.0) for row in result["timeline"])
        assert by_stretch == pytest.approx(kernels[name]["s"], rel=1e-4), name
    assert "s in kernels" in proc.stdout and "the host" in proc.stdout


_BENCH_COLLIDE = {
    "awake": (PARALLEL_PIT, ()),
    "asleep-8-sweeps": (PARALLEL_PIT, ("--asleep", "--iterations", "8")),
    "serial": (64, ()),
    "serial-between-builds": (RELIST_MAX_BALLS + 1, ()),
}
"""The collide bench's runs: the parallel step (more balls than SERIAL_MAX_BALLS), awake and asleep, and the
serial ones, relisting in the kernel and built between launches (RELIST_MAX_BALLS)."""
for _name, (_n, _flags) in _BENCH_COLLIDE.items():
    background.declare(
        f"bench-collide-{_name}",
        lambda _, n=_n, flags=_flags: (cli("bench", "collide", "--n", str(n), "--steps", "3", "--json", *flags), {}),
    )


@pytest.mark.parametrize(
    "n, flags",
    [
        pytest.param(*args, id=name, marks=pytest.mark.background(f"bench-collide-{name}"))
        for name, args in _BENCH_COLLIDE.items()
    ],
)
def test_bench_collide_json(n, flags, background_runs, request):
    proc = ok(background_runs.result(f"bench-collide-{request.node.callspec.id}")[0])
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["n"] == n and result["steps"] == 3 and result["asleep"] == bool(flags)
    assert result["iterations"] == (8 if flags else 4)
    # the rates are the timed steps': n balls a step over the milliseconds a step took
    assert result["ball_steps_per_s"] == pytest.approx(n * 1e3 / result["ms_per_step"], rel=1e-4)
    assert result["peak_rss_bytes"] >= result["bytes_per_ball_above_baseline"] * n
    # the warm-up compiled the timed step's kernels: their compiling (some 35 MB for the serial steps
    # between builds) is not counted as the pile's memory (a few hundred bytes a ball, a few MB in all)
    assert result["bytes_per_ball_above_baseline"] * n < 16 * 2**20
    _, x = pile_scene(n)  # a cubic lattice of touching balls: its face neighbours are its contacts
    d = np.linalg.norm(x[:, None] - x[None], axis=-1)
    lattice_contacts = np.count_nonzero((d > 0) & (d < 2 * 0.02 * 1.001)) / n
    assert result["contacts_per_ball"] == pytest.approx(lattice_contacts, rel=0.02)  # the pile still stands
    assert 0.0 <= result["deepest_overlap"] < 0.05  # and keeps the bound (5 % of a radius)
    # each yardstick's cost is its rate over the step's (the bench's figures of merit)
    for name, key in (
        ("bare_gather", "step_cost_in_bare_gathers"),
        ("one_pass_contacts", "step_cost_in_one_pass_contacts"),
    ):
        rate = result["baselines"][f"{name}_balls_per_s"]
        assert result[key] == pytest.approx(rate / result["ball_steps_per_s"], rel=1e-3), key
    # an awake parallel step does more than one pass of the bare contact law (four sweeps, lists, forces)
    if not flags and not result["serial"]:
        assert result["step_cost_in_one_pass_contacts"] > 1.0
    assert ("asleep_speedup" in result) == bool(flags)  # with its awake baseline timed in the same run
    # few balls are stepped serially, with one parallel launch per step timed in the same run
    assert result["serial"] == (n <= SERIAL_MAX_BALLS) and ("serial_speedup" in result) == result["serial"]
    if result["serial"]:  # its speed-up is the parallel step's time over its own (3 steps: too few to rank them)
        assert result["serial_speedup"] == pytest.approx(
            result["baselines"]["parallel_ms_per_step"] / result["ms_per_step"], rel=1e-3
        )


def test_bench_json_rounds_the_floats_in_lists_and_tuples_too():
    # to_json promised floats to 6 significant digits but left those in lists (the pit's timeline,
    # the start-up's commands) at full length
    from ti_golf.bench.common import to_json

    values = [math.pi, -math.e * 1e-9, 1.0 / 3.0 * 1e7]
    result = {
        "x": values[0],
        "timeline": [{"t_s": v, "kernels": {"k": [v]}} for v in values],
        "commands": [("run", v) for v in values],
    }
    out = json.loads(to_json(result))
    found = [out["x"]]
    for row in out["timeline"]:
        found += [row["t_s"], *row["kernels"]["k"]]
    found += [v for _, v in out["commands"]]
    expected = [values[0]] + [v for v in values for _ in range(2)] + values
    for got, v in zip(found, expected, strict=True):
        assert got == round(v, 5 - math.floor(math.log10(abs(v)))), (got, v)  # 6 significant digits


@pytest.mark.skipif(not Path("/proc/self/clear_refs").exists(), reason="restarting the peak RSS needs Linux /proc")
def test_the_bench_restarts_the_peak_memory_after_its_warm_up():
    # the collide bench reports the pile's peak resident memory above the process's after the
    # warm-up; compiling the warm-up's kernels from an empty kernel cache peaks at 800 MiB and more,
    # which the lifetime peak would report instead (1,064 bytes per ball at N = 9,000, against 236
    # with the kernels cached), so the peak must restart after it
    import mmap

    from ti_golf.bench import common as bench

    # 96 MiB of memory of its own, touched page by page, then given back to the OS (munmap). Not a
    # numpy array: in a process whose heap holds freed memory (this one, after compiling kernels)
    # malloc serves it from there, already resident, and keeps it after it is freed
    size = 96 * 2**20
    block = mmap.mmap(-1, size)
    for offset in range(0, size, mmap.PAGESIZE):
        block[offset] = 1
    block.close()
    before = bench._peak_rss_bytes()
    assert before >= bench._rss_bytes() + 64 * 2**20
    assert bench._restart_peak_rss()
    after = bench._peak_rss_bytes()
    assert after <= before - 64 * 2**20  # the 96 MiB no longer counts
    assert after >= bench._rss_bytes() - 2**20  # the peak restarts from the current size (a page's lag aside)


background.declare(
    "bench-collide-boulder",
    lambda _: (cli("bench", "collide", "--n", "512", "--steps", "3", "--boulder", "0.1", "--json"), {}),
)


@pytest.mark.background("bench-collide-boulder")
def test_bench_collide_with_a_boulder_times_the_pile_alone_too(background_runs):
    proc = ok(background_runs.result("bench-collide-boulder")[0])
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["boulder_radius"] == 0.1 and result["n"] == 512  # the pile's balls (the boulder comes on top)
    assert result["boulder_slowdown"] == pytest.approx(
        result["ms_per_step"] / result["baselines"]["pile_alone_ms_per_step"], rel=1e-3
    )


def test_bench_lab_refuses_a_screenshot_path_that_ends_in_a_separator(tmp_path, capsys):
    # `--screenshot DIR.png/` names a folder, but Path reads it as DIR.png: the picture was written there
    shot = tmp_path / "shot.png"
    args = ["bench", "lab", "lab_vacuum", "--seconds", "0.1", "--size", "160x90", "--screenshot", f"{shot}{os.sep}"]
    assert main(args) == 2
    assert f"--screenshot: cannot write '{shot}{os.sep}': it ends in a separator" in capsys.readouterr().err
    assert not shot.exists()


def test_bench_collide_names_the_sweeps_of_the_solver_its_pile_uses(capsys):
    # --iterations' help and pile_scene's docstring said "Jacobi sweeps per step" of a pile that the
    # default solver, Gauss-Seidel, steps
    words = {"gauss_seidel": "Gauss–Seidel", "jacobi": "Jacobi"}
    solver = pile_scene(2)[0].contact.solver
    with pytest.raises(SystemExit):
        main(["bench", "collide", "--help"])
    said = " ".join(capsys.readouterr().out.split())
    iterations = said[said.index("--iterations ITERATIONS") :]
    for text in (iterations, " ".join((pile_scene.__doc__ or "").split())):
        assert f"{words[solver]} sweeps per step" in text, text
        assert all(word not in text for name, word in words.items() if name != solver), text


def test_the_performance_pages_collide_options_claim_only_baselines_the_bench_times(capsys):
    # the `--iterations 8` row gave "4 sweeps in the same session" as its same-run baseline, which
    # `bench collide --iterations 8` neither times nor prints: a row's baseline is a yardstick every
    # run times, the parallel step a serial pile is timed against, one its option's help says is
    # "timed too, as baseline", or it says it is a separate run
    page = (ROOT / "docs" / "performance.md").read_text(encoding="utf-8")
    table = page[
        page.index("The same command with an option") : page.index("**What limits it.**", page.index("## Collisions"))
    ]
    with pytest.raises(SystemExit):
        main(["bench", "collide", "--help"])
    said = " ".join(capsys.readouterr().out.split())
    said = said[said.index(" options: ") :]  # (each option's help, after the usage line)
    rows = [
        [c.strip() for c in ln.strip().strip("|").split("|")] for ln in table.splitlines() if ln.startswith("| `--")
    ]
    assert any("--iterations" in row[0] for row in rows)
    for row in rows:
        option = re.match(r"`(--[\w-]+)", row[0]).group(1)
        start = said.find(f" {option} ")
        helped = start >= 0 and "as baseline" in said[start : said.find(" --", start + 1)]
        kinds = ("one pass of the contacts", "bare gather", "one parallel launch a step", "a separate run")
        assert helped or any(kind in row[3] for kind in kinds), row


def test_bench_collide_bounds_the_boulder_by_the_bin_of_its_pile():
    # a boulder wider than the bin of --n balls never reached the pile (the walls inside it), and
    # one below a scene's least ball radius was taken too: refused, naming the range for that --n
    from ti_golf.bench.collide import drop_boulder, widest_boulder
    from ti_golf.scene.checks import RADIUS

    n = 301  # (a top layer partly filled: the boulder falls over the pile's middle, off the bin's)
    widest = widest_boulder(n)
    scene, x = pile_scene(n)
    walls = [p for p in scene.planes if p.normal[1] == 0]
    for radius, fits in ((widest, True), (widest + 1e-3, False)):
        centre = drop_boulder(scene, x, radius)[0][-1]
        room = min(np.dot(centre - np.asarray(p.point), np.asarray(p.normal)) for p in walls)
        assert (room >= radius) == fits, (radius, room)
    for bad in (widest + 1e-3, RADIUS.lo / 2):
        proc = run_cli("bench", "collide", "--n", str(n), "--steps", "1", "--boulder", str(bad))
        assert proc.returncode == 2, (bad, proc.stdout[-500:], proc.stderr)
        assert f"--boulder: must be 0 (no boulder) or a radius in [{RADIUS.lo:g}, {widest:g}] m for --n {n}" in (
            proc.stderr
        )


@ON_VULKAN
def test_bench_render_refuses_a_backend_ggui_does_not_draw_with():
    # on Vulkan GGUI is not drawn (render's "auto" falls back to matplotlib): the bench timed
    # matplotlib against matplotlib and exited 0. --arch offers cpu and cuda, as `bench lab` does,
    # and TI_GOLF_ARCH=vulkan is refused naming --arch
    proc = run_cli("bench", "render", "--arch", "vulkan", "--n", "10", "--frames", "1")
    assert proc.returncode == 2 and "argument --arch: invalid choice: 'vulkan'" in proc.stderr, proc.stderr
    proc = run_cli("bench", "render", "--n", "10", "--frames", "1", env={"TI_GOLF_ARCH": "vulkan"})
    if "running on the CPU" in proc.stderr:  # (runtime.init's note when Taichi finds no Vulkan)
        pytest.skip(NO_VULKAN_BACKEND)
    assert proc.returncode == 2, (proc.stdout[-500:], proc.stderr)
    assert "--arch: times GGUI against matplotlib, and GGUI draws with the CPU or CUDA backend" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_bench_render_reports_the_best_of_its_frames_of_each_renderer_and_the_precision(monkeypatch):
    # the docs said "the best of three frames each": the bench reported the mean of the GGUI
    # frames and one matplotlib frame, and no precision, which every other bench reports. The
    # frames' seconds here come from a clock that each fake frame advances by its own time
    import types

    from ti_golf.bench import common
    from ti_golf.bench import render as bench
    from ti_golf.runtime import ensure_init

    clock = [0.0]
    times = {"ggui": [5.0, 0.3, 0.1, 0.2], "matplotlib": [9.0, 0.7, 0.9, 0.5]}  # (the first: untimed)
    drawn = {"ggui": 0, "matplotlib": 0}

    def fake_render(sim, path, backend="auto", **kwargs):
        clock[0] += times[backend][drawn[backend]]
        drawn[backend] += 1
        return backend

    monkeypatch.setattr(bench, "render", fake_render)
    monkeypatch.setattr(common, "time", types.SimpleNamespace(perf_counter=lambda: clock[0]))
    result = bench.bench_render(n=10, frames=3, log=lambda line: None)
    assert drawn == {"ggui": 4, "matplotlib": 4}  # an untimed first frame, then three timed, each
    assert result["renderer"] == "ggui"
    assert result["seconds_per_frame"] == pytest.approx(min(times["ggui"][1:]))
    assert result["baselines"]["matplotlib_seconds_per_frame"] == pytest.approx(min(times["matplotlib"][1:]))
    assert result["precision"] == ensure_init().precision and result["frames"] == 3


TOUR_DT = tomllib.loads((SCENES / "tour_shot.toml").read_text(encoding="utf-8"))["world"]["dt"]
"""The time step of ``tour_shot``, the scene ``bench dispersion`` flies [s]."""

BAD_BENCH_OPTIONS = [
    (("collide", "--iterations", "0"), "[1, 100]"),
    (("collide", "--steps", "0"), "[1, 1,000,000]"),
    (("collide", "--steps", "999999999999"), "[1, 1,000,000]"),  # (it ran on, deaf to Ctrl-C)
    (("sweep", "--n", "99999999999999"), "[1, 10,000,000]"),  # (numpy's allocation error)
    (("sweep", "--dt", "inf"), "[1e-05, 1] s"),  # (it printed Infinity into the JSON)
    (("sweep", "--repeats", "0"), "[1, 100]"),
    (("render", "--frames", "0"), "[1, 1000]"),
    (("lab", "--seconds", "0"), "(0, 3600] s"),
    (("lab", "--seconds", "nan"), "(0, 3600] s"),
    (("lab", "--screenshot", "lab.jpg"), ".png"),
    (("lab", "no_such_scene"), "file not found"),
    (("lab", "--set", "air.C_D=-1"), "[0, 100]"),
    (("startup", "--scenes", ","), "names no scene"),  # (it timed every scene)
    (("startup", "--repeats", "101", "--cache", "warm", "--scenes", "lab_vacuum"), "[1, 100]"),  # (no bound)
    (("startup", "--repeats", "0"), "[1, 100]"),
    (("startup", "--top", "3", "--cache", "warm"), "has no effect without --kernels"),
    (("startup", "--repeats", "2", "--kernels", "lab_vacuum"), "has no effect with --kernels"),
    (("pit", "--t", "0.02", "--n", "500", "--set", "world.dt=1e-9"), "20,000,000 steps; at most 10,000,000"),
    (("collide", "--n", "1"), "must be in [2, 10,000,000]"),
    (("pit", "--n", "15"), "must be in [16, 10,000,000]"),
    (("dispersion", "--n", "100", "--rest", "200"), "--rest: must be in [0, --n] shots (got 200)"),
    # (a step equal to world.dt was timed once, the second timing dropped; a finer one is no "coarser step")
    (
        ("dispersion", "--flight-dt", str(TOUR_DT), "--n", "100"),
        f"must be coarser than tour_shot's world.dt = {TOUR_DT:g} s",
    ),
    (("dispersion", "--flight-dt", str(TOUR_DT / 2), "--n", "100"), f"in ({TOUR_DT:g}, 0.05] s"),
    (("collide", "--boulder", "-0.1"), "must be 0 (no boulder) or a radius in ["),
    (("collide", "--boulder", "nan"), "must be 0 (no boulder) or a radius in ["),
    # (4,097 to 8,191 balls: stepped in parallel, not reordered; both runs timed the random order)
    (("collide", "--shuffled", "--n", str(REORDER_MIN_BALLS - 1), "--steps", "1"), f"--n >= {REORDER_MIN_BALLS:,}"),
    (("collide", "--shuffled", "--n", str(SERIAL_MAX_BALLS + 1), "--steps", "1"), f"--n >= {REORDER_MIN_BALLS:,}"),
    # (with the boulder, one ball fewer makes the pile the solver reorders)
    (
        ("collide", "--shuffled", "--boulder", "0.1", "--n", str(REORDER_MIN_BALLS - 2), "--steps", "1"),
        f"--n >= {REORDER_MIN_BALLS - 1:,}",
    ),
    (("pit", "--every", "0"), "(0, --t]"),
    (("pit", "--every", "5"), "(0, --t]"),  # longer than the pour (--t 4)
    (("pit", "--every", "nan"), "(0, --t]"),
    (("pit", "--t", "0"), "(0, 60]"),
    (("pit", "--set", "launch.speed=10", "--n", "100", "--t", "0.01"), "makes a launched ball"),  # (101 balls, n 100)
    (("pit", "--set", "world.collisions=false", "--n", "100", "--t", "0.01"), "must be true for the pit"),  # (0 %)
    (("pit", "--every", "0.0001", "--n", "100", "--t", "0.05"), "at least world.dt = 0.001 s"),  # (rows a step apart)
    (
        ("pit", "--n", "100", "--t", "0.01", "--set", "ball.radius=0.1"),
        "100 balls do not fit the pit's bin scaled to them",
    ),  # (named ball_pit.toml; balls wider than the narrowest bin)
]
"""(bench and one bad option, a fragment of the allowed range the error must name)."""


def test_bench_startup_refuses_a_backend_the_machine_lacks():
    # its commands, started with TI_GOLF_ARCH=cuda on a machine without CUDA, ran on the CPU and
    # their times were reported as CUDA's ("0 of 0 targets met (cuda, f64 …)")
    from ti_golf.runtime import backend_found

    if backend_found("cuda"):
        pytest.skip("this machine has CUDA")
    proc = run_cli("bench", "startup", "--scenes", "lab_magnus", "--cache", "warm", "--arch", "cuda")
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert "--arch: Taichi finds no cuda backend on this machine" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.parametrize("args, fragment", BAD_BENCH_OPTIONS, ids=[" ".join(a) for a, _ in BAD_BENCH_OPTIONS])
def test_bench_bad_option_exits_2(args, fragment):
    proc = run_cli("bench", *args)
    assert proc.returncode == 2, (proc.stdout, proc.stderr)
    assert args[1] in proc.stderr and fragment in proc.stderr and "Traceback" not in proc.stderr


# ----------------------------------------------------------------------------------------------
# backend selection through the environment
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def bogus_arch():
    return run_cli("sweep", "lab_turbulent", "--angles", "36", env={"TI_GOLF_ARCH": "bogus"})


def test_bogus_arch_env_exits_2_naming_allowed_backends(bogus_arch):
    proc = bogus_arch
    assert proc.returncode == 2, (proc.stdout, proc.stderr)
    assert "Traceback" not in proc.stderr
    assert "bogus" in proc.stderr
    for arch in ("cpu", "cuda", "vulkan", "gpu"):
        assert arch in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert "best:" not in proc.stdout  # nothing was simulated


def test_a_backend_taichi_does_not_find_is_one_note_and_the_cpu():
    # Taichi's own probe printed raw warnings ("[W ...] libcuda.so lib not found", "Arch=[...] is not
    # supported, falling back to CPU"); a machine without the backend (here made so, GPU or not) now
    # gets one line of ti-golf's
    script = "from ti_golf.cli import main; raise SystemExit(main(['run', 'lab_vacuum', '--steps', '1']))"
    proc = subprocess.run(
        [sys.executable, "-c", f"from ti_golf import runtime; runtime.backend_found = lambda a: False; {script}"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={**os.environ, "TI_GOLF_ARCH": "cuda"},
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert "ti-golf: Taichi finds no cuda backend on this machine; running on the CPU" in lines, proc.stderr
    assert all(line.startswith("ti-golf: ") for line in lines), proc.stderr  # (and the first-compile note)
    assert "1 flying" in proc.stdout


def test_bogus_arch_env_error_names_the_variable(bogus_arch):
    assert "TI_GOLF_ARCH" in bogus_arch.stderr, bogus_arch.stderr


def test_a_bad_cuda_passes_switch_exits_2_naming_the_variable(monkeypatch):
    # TI_GOLF_CUDA_PASSES (runtime.CUDA_PASSES_ENV) takes 1, 0 or nothing: any other value is
    # refused before anything runs, as a bad TI_GOLF_ARCH is
    monkeypatch.setenv("TI_GOLF_CUDA_PASSES", "yes")
    proc = cli_main_process(["sweep", "lab_turbulent", "--angles", "36"])
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip() == "ti-golf: error: TI_GOLF_CUDA_PASSES: must be 1, 0 or empty, not 'yes'"
    monkeypatch.setenv("TI_GOLF_CUDA_PASSES", "1")  # (on the CPU it changes nothing)
    assert cli_main_process(["sweep", "lab_turbulent", "--angles", "36"]).returncode == 0


def test_the_first_run_on_a_machine_is_announced(tmp_path):
    # a new user's first commands pause while Taichi compiles the kernels: the CLI says so while
    # Taichi's kernel cache is empty, and no more once it holds a kernel (here the command then
    # stops at the unknown scene, exit 2, before compiling anything)
    cache = tmp_path / "ticache"
    env = {"TI_OFFLINE_CACHE_FILE_PATH": str(cache)}
    cold = run_cli("run", "no_such_scene", env=env)
    assert cold.returncode == 2 and "no_such_scene" in cold.stderr
    assert "first run on this machine" in cold.stderr and str(cache) in cold.stderr
    cache.mkdir(exist_ok=True)
    (cache / "Tkernel.tic").write_bytes(b"")
    warm = run_cli("run", "no_such_scene", env=env)
    assert warm.returncode == 2 and "no_such_scene" in warm.stderr
    assert "first run" not in warm.stderr


def interrupt_mid_run(args: list[str], sig: int = signal.SIGTERM, until: Path | None = None) -> tuple[int, str]:
    """Start ``ti-golf ARGS`` in a real process, send it ``sig`` once its first progress line shows
    it is simulating, and return its exit code and the rest of its standard error. ``until``: send
    ``sig`` again every 10 ms until that file exists or the process ends (a user pressing Ctrl-C
    again while the run writes what it simulated)."""
    proc = subprocess.Popen(
        cli(*args),
        stderr=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        preexec_fn=sigint_as_in_a_terminal,
    )
    try:
        for line in proc.stderr:  # the first progress line comes a few seconds into the run
            if line.startswith("progress:"):
                break
        proc.send_signal(sig)
        deadline = time.monotonic() + 120
        while until is not None and not until.exists() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
            proc.send_signal(sig)
        rest = proc.stderr.read()
        return proc.wait(timeout=120), rest
    finally:
        proc.kill()


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_an_interrupted_run_keeps_what_it_computed(sig, tmp_path):
    # a real process, stopped mid-run: it saves the state it reached and the recording so far, marked
    # partial, draws the plot of what it recorded (it drew none), says so in one line and exits with code 130
    out, png = tmp_path / "run.npz", tmp_path / "run.png"
    args = ["run", "terrain_3d", "--t", "100", "--out", str(out), "--plot", str(png), "--record-every", "10"]
    code, rest = interrupt_mid_run(args, sig)
    assert code == 130, rest
    last = rest.strip().splitlines()[-1]
    assert last.startswith("ti-golf: interrupted at t = ") and "marked partial" in last, rest
    assert f"kept in {out} and {png}" in last and png.read_bytes().startswith(PNG_SIGNATURE), rest
    assert "Traceback" not in rest
    with np.load(out) as d:
        assert bool(d["partial"]) and 0.0 < float(d["t"]) < 100.0
        assert d["x"].shape == (400, 3) and np.isfinite(d["x"]).all()
        assert d["traj_t"][-1] <= float(d["t"]) and d["traj_x"].shape == (len(d["traj_t"]), 400, 3)


@pytest.mark.slow
def test_a_run_keeps_what_it_computed_when_ctrl_c_comes_again_while_it_writes(tmp_path):
    # the second Ctrl-C (and every one after it) waits until the state is written: before, one that
    # came while the run was saving ended it with nothing saved
    out = tmp_path / "run.npz"
    args = ["run", "terrain_3d", "--t", "100", "--out", str(out), "--record-every", "10"]
    code, rest = interrupt_mid_run(args, signal.SIGINT, until=out)
    assert code == 130, rest
    assert "ti-golf: writing what was simulated first" in rest and "Traceback" not in rest, rest
    # (the last line says what was kept, unless a Ctrl-C came after the state was written and
    # before the first one's words were said)
    assert rest.strip().splitlines()[-1].startswith("ti-golf: interrupted"), rest
    with np.load(out) as d:
        assert bool(d["partial"]) and 0.0 < float(d["t"]) < 100.0 and d["x"].shape == (400, 3)


def interrupted_launch(monkeypatch, module, name: str, signum: int, argv: list[str], capsys) -> list[str]:
    """``main(argv)`` with ``module.name`` (the command's one kernel launch) sent ``signum`` as it
    starts; asserts the exit code 130 and the handlers put back, and returns standard error's lines."""
    real = getattr(module, name)

    def interrupted(*args, **kwargs):
        os.kill(os.getpid(), signum)  # arrives while the launch runs
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, interrupted)
    before = signal.getsignal(signum)
    assert main(argv) == 130
    assert signal.getsignal(signum) == before  # the handlers are put back
    return capsys.readouterr().err.strip().splitlines()


def test_an_interrupted_sweep_keeps_its_results(tmp_path, capsys, monkeypatch):
    # a sweep's flights are one kernel launch, which cannot stop half-way: SIGTERM (or Ctrl-C)
    # during it is held until its results are written, then the command stops with one line and
    # code 130
    from ti_golf.golf import sweep as sweep_module

    out = tmp_path / "s.csv"
    argv = ["sweep", "lab_vacuum", "--angles", "30,45,60", "--out", str(out)]
    err = interrupted_launch(monkeypatch, sweep_module, "fly", signal.SIGTERM, argv, capsys)
    assert err == [
        f"ti-golf: interrupted during the sweep's flights, one kernel launch: they ran to their end; saved in {out}"
    ]
    assert len(out.read_text().splitlines()) == 1 + 3  # header and the three launches


def test_an_interrupted_sweep_to_rest_stops_its_roll_out_and_keeps_what_it_computed(tmp_path, capsys, monkeypatch):
    # a Ctrl-C during --to-rest's roll-out waited for the whole roll-out (19 s after the signal in
    # a sweep of 1,000 launches), then said the sweep was one kernel launch; during the flights it
    # also ran the whole roll-out. Now the flights are kept without a roll-out, or the roll-out
    # stops between its launches, with a line that says which
    import csv

    from ti_golf.golf import rollout
    from ti_golf.golf import sweep as sweep_module

    out = tmp_path / "s.csv"
    argv = ["sweep", "tour_shot", "--angles", "10,12,14", "--to-rest", "--out", str(out)]
    for module, name, said in (
        (
            sweep_module,
            "fly",
            "during the sweep's flights, one kernel launch: they ran to their end, before the roll-out",
        ),
        (rollout.Simulation, "run", "during the roll-out: 0 of the 3 balls landed had come to rest"),
    ):
        err = interrupted_launch(monkeypatch, module, name, signal.SIGINT, argv, capsys)
        assert err == [f"ti-golf: interrupted {said}; saved in {out}"], err
        rows = list(csv.DictReader(out.read_text().splitlines()))
        assert len(rows) == 3 and all(float(r["carry_m"]) > 100 for r in rows), rows[:1]
        assert all(r.get("total_m", "") in ("", "nan") for r in rows), rows[:1]  # (none rested)
        monkeypatch.undo()


def test_an_interrupted_dispersion_without_a_roll_out_keeps_its_shots(tmp_path, capsys, monkeypatch):
    # the shots' flights are one kernel launch: a Ctrl-C during them waited for the launch to end,
    # then threw its shots away (no --out written); they are kept, as a sweep's are
    from ti_golf.golf import sweep

    out = tmp_path / "d.csv"
    argv = ["dispersion", "tour_shot", "--n", "20", "--no-roll", "--out", str(out)]
    err = interrupted_launch(monkeypatch, sweep, "fly", signal.SIGINT, argv, capsys)
    assert err[-1].startswith("ti-golf: interrupted during the shots' flights") and str(out) in err[-1], err
    assert len(out.read_text().splitlines()) >= 1 + 20  # the header (and notes) and the twenty shots


def test_an_interrupted_dispersion_with_a_roll_out_keeps_what_it_computed(tmp_path, capsys, monkeypatch):
    # with a roll-out, a Ctrl-C during the flights (one launch) or the roll-out (steps) threw every
    # shot away; the flights are kept, and the rests reached, with a line that says which
    import csv

    from ti_golf.golf import rollout, sweep

    out = tmp_path / "d.csv"
    argv = ["dispersion", "tour_shot", "--n", "20", "--out", str(out)]
    for module, name, said in (
        (sweep, "fly", "during the shots' flights, which are one kernel launch: they ran to their end, not rolled out"),
        (rollout.Simulation, "run", "during the roll-out: 0 of the 20 landed shots had come to rest"),
    ):
        err = interrupted_launch(monkeypatch, module, name, signal.SIGINT, argv, capsys)
        assert err[-1].startswith(f"ti-golf: interrupted {said}") and str(out) in err[-1], err
        rows = list(csv.DictReader(out.read_text().splitlines()))
        assert len(rows) == 20 and all(float(r["carry_yd"]) > 150 for r in rows), rows[:1]
        assert all(r.get("total_yd", "") in ("", "nan") for r in rows), rows[:1]  # (none rested)
        monkeypatch.undo()


@pytest.mark.slow
@ON_VULKAN
def test_an_interrupted_render_draws_the_state_it_reached(tmp_path):
    out = tmp_path / "p.png"
    code, rest = interrupt_mid_run(["render", "terrain_3d", "--t", "100", "--out", str(out), "--size", "160x120"])
    assert code == 130, rest
    last = rest.strip().splitlines()[-1]
    assert last.startswith("ti-golf: interrupted at t = ") and "picture of that state is saved" in last, rest
    assert out.read_bytes().startswith(PNG_SIGNATURE)


# ----------------------------------------------------------------------------------------------
# a first hour without rough edges
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("command", ["keys", "scenes"])
def test_a_reader_that_leaves_early_ends_the_output_quietly(command):
    # `ti-golf keys | head`: the reader closes the pipe before the command writes; no error, no
    # traceback, and the exit code a shell gives a command stopped by SIGPIPE (which it passes over)
    proc = subprocess.Popen(cli(command), stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT, text=True)
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()
    err = proc.stderr.read()
    assert proc.wait(timeout=120) == 128 + signal.SIGPIPE and err == ""


def test_a_misspelled_bundled_scene_gets_a_did_you_mean(capsys):
    assert main(["run", "newtons_cradel", "--steps", "1"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == (
        "ti-golf: error: newtons_cradel: file not found, nor a bundled scene "
        "(did you mean 'newtons_cradle'? `ti-golf scenes` lists them)"
    )


@pytest.mark.parametrize(
    "args",
    [
        ["lab"],
        ["play", "--gui"],
        ["run", "no_such_scene"],
        ["run", "lab_vacuum", "--set", "air.C_D=-1"],
        ["run", "lab_vacuum", "--t", "-1"],
        ["sweep", "lab_vacuum", "--angles", "a:b:c"],
        ["bench", "pit", "--t", "-1"],
        ["run", "lab_vacuum", "--size", "1x1"],
        ["frobnicate"],
    ],
)
def test_no_error_message_says_ti_golf_twice(args, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    try:
        code = main(args)
    except SystemExit as exc:  # argparse's usage errors
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("ti-golf:") == 1 and "ti-golf: error: " in err, err


IMPORTS_SCRIPT = """
import sys
from ti_golf.cli import main
heavy = ("matplotlib", "PIL", "scipy")
main(["keys"])
main(["scenes"])
print("keys, scenes:", sorted(m for m in ("taichi", *heavy) if m in sys.modules))
main(["run", "lab_vacuum", "--steps", "1"])
print("run:", sorted(m for m in heavy if m in sys.modules))
"""


def test_keys_scenes_and_a_run_without_plots_import_no_plotting_library():
    # the start of a command is paid by every test, study and lab scene: `keys` and `scenes` start
    # no Taichi, and a run that draws nothing imports neither matplotlib, Pillow nor scipy
    proc = subprocess.run([sys.executable, "-c", IMPORTS_SCRIPT], capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "keys, scenes: []" in lines and "run: []" in lines, proc.stdout


def test_a_run_until_rest_that_reaches_its_time_limit_says_so_and_names_the_balls(capsys):
    # lab_vacuum flies for 11.5 s (80 m/s at 45 degrees, no air)
    assert main(["run", "lab_vacuum", "--t", "1", "--until", "landed"]) == 0
    out = capsys.readouterr().out
    assert (
        "stopped at the time limit (--t) before every ball was landed: 1 still in flight (ball 0); "
        "a longer --t runs on" in out
    )
    assert main(["run", "lab_vacuum", "--t", "1", "--until", "rest"]) == 0
    assert "before every ball was at rest or out of bounds: 1 still moving (ball 0)" in capsys.readouterr().out
    assert main(["run", "lab_vacuum", "--t", "12", "--until", "landed"]) == 0
    assert "time limit" not in capsys.readouterr().out  # landed before it


def test_run_prints_the_apex_above_the_launch_point(capsys):
    # in vacuo, RK4 follows the parabola exactly: apex (v0·sin θ)²/2g above the launch point, whose
    # centre sits a radius above the ground (the run printed the centre's height, a radius more);
    # the printed 0.01 m, plus the apex sampled at steps of h = 0.01 s, g·(h/2)²/2 at most
    scene = ti_golf.load_scene("lab_vacuum")
    assert main(["run", "lab_vacuum", "--until", "landed"]) == 0
    printed = float(re.search(r"apex (\S+) m above launch", capsys.readouterr().out).group(1))
    g = -scene.world.gravity[1]
    rise = (scene.launch.speed * math.sin(math.radians(scene.launch.angle_deg))) ** 2 / (2 * g)
    assert printed == pytest.approx(rise, abs=0.005 + g * (scene.world.dt / 2) ** 2 / 2)


def test_a_run_until_rest_that_reaches_the_scenes_length_says_it_counts_from_the_resume(tmp_path, capsys):
    # the default length of a run, world.t_end, counts from where a resumed run starts: at t = 4.5 s a
    # line that named "world.t_end = 4 s" alone read as a contradiction
    first = tmp_path / "a.npz"
    assert main(["run", "lab_vacuum", "--t", "0.5", "--out", str(first)]) == 0
    capsys.readouterr()
    assert main(["run", "--resume", str(first), "--set", "world.t_end=1", "--until", "landed"]) == 0
    out = capsys.readouterr().out
    assert "t = 1.5 s (resumed at t = 0.5 s)" in out
    assert (
        "stopped at the time limit (world.t_end = 1 s, the default length of a run from where it resumed) "
        "before every ball was landed: 1 still in flight (ball 0)" in out
    )


def test_a_render_until_rest_that_reaches_its_time_limit_says_so(tmp_path, capsys):
    png = tmp_path / "p.png"
    args = ["render", "lab_vacuum", "--until", "rest", "--out", str(png), "--size", "64x48", "--backend", "matplotlib"]
    assert main([*args, "--t", "1"]) == 0
    assert (
        "stopped at the time limit (--t) before every ball was at rest or out of bounds: 1 still moving (ball 0)"
        in (capsys.readouterr().out)
    )
    assert png.read_bytes().startswith(PNG_SIGNATURE)


def test_the_progress_of_a_run_until_rest_follows_the_balls_not_the_time_limit():
    # a roll-out runs until every ball rests, with world.t_max as a limit it seldom reaches: its
    # progress counts the balls at rest, so it ends at 100 %, not at a few per cent of t_max
    from ti_golf.golf.rollout import roll_out

    scene = ti_golf.load_scene("tour_shot")
    calls = []
    x = np.array([[0.0, 0.0214, 0.0], [0.0, 0.0214, 1.0], [0.0, 0.0214, 2.0]])
    v = np.array([[3.0, -1.0, 0.0], [1.0, -1.0, 0.0], [6.0, -2.0, 0.0]])
    roll_out(scene, x, v, np.zeros((3, 3)), progress=lambda *a, **k: calls.append((a, k)))
    (t_done, t_max), last = calls[-1]
    assert t_done < 0.5 * t_max  # the balls came to rest long before the limit
    assert last["finished"] == (3, 3, "at rest or out of bounds")
    done = [k["finished"][0] for _, k in calls]
    assert done == sorted(done) and done[0] < 3


def test_progress_shows_the_larger_of_the_time_and_the_balls_finished(capsys):
    from ti_golf.cli._common import Progress

    progress = Progress(after_s=0.0, every_s=0.0)
    progress.tty = False
    progress(1.5, 60.0, finished=(30, 50, "at rest or out of bounds"))
    progress(2.0, 4.0)
    frames = Progress(after_s=0.0, every_s=0.0, unit="frames")
    frames.tty = False
    frames(25, 100)
    lines = capsys.readouterr().err.splitlines()
    assert lines[0].startswith("progress:  60.0% (t = 1.5 of 60 s; 30 of 50 balls at rest or out of bounds, ")
    assert lines[1].startswith("progress:  50.0% (t = 2 of 4 s, ")
    assert lines[2].startswith("progress:  25.0% (25 of 100 frames, ")


RESTING_BALL = """description = "one ball at rest on the ground"
[ball]
radius = 0.02134
[[balls]]
position = [0.0, 0.02134, 0.0]
velocity = [0.0, 0.0, 0.0]
"""


def _gif_frames(path: Path) -> list[np.ndarray]:
    from PIL import Image

    with Image.open(path) as gif:
        frames = []
        for k in range(gif.n_frames):
            gif.seek(k)
            frames.append(np.asarray(gif.convert("RGB"), dtype=float))
    return frames


@pytest.mark.slow  # two renders of 1,500 steps in subprocesses
@ON_VULKAN  # (their frames are drawn with GGUI)
def test_the_gif_report_matches_the_file_and_the_camera_holds_still(tmp_path):
    # break_shot spreads its balls: a camera that refits every frame (--follow) zooms out and
    # every frame's ground moves; the still camera draws the same ground in every frame, and the
    # command reports the frames the GIF file holds
    common = ["run", "break_shot", "--steps", "1500", "--frames-every", "500", "--size", "160x90", "--camera", "top"]
    still, follow = tmp_path / "still.gif", tmp_path / "follow.gif"
    proc = ok(run_cli(*common, "--gif", str(still)))
    frames = _gif_frames(still)
    assert f"wrote {still}: {len(frames)} frames, " in proc.stdout and len(frames) == 4
    moved = [np.abs(f - frames[0]).max(axis=2) > 8 for f in frames[1:]]
    assert max(m.mean() for m in moved) < 0.02  # only the balls changed
    ok(run_cli(*common, "--gif", str(follow), "--follow"))
    refit = _gif_frames(follow)
    assert np.mean(np.abs(refit[-1] - refit[0]).max(axis=2) > 8) > 0.1  # the ground moved


@ON_VULKAN  # (its frames are drawn with GGUI)
def test_a_gif_of_frames_that_do_not_change_reports_the_frames_it_holds(tmp_path):
    # Pillow merges identical neighbouring frames: the report counts what the file holds
    scene = tmp_path / "resting.toml"
    scene.write_text(RESTING_BALL)
    gif = tmp_path / "a.gif"
    proc = ok(run_cli("run", str(scene), "--steps", "30", "--frames-every", "10", "--size", "80x60", "--gif", str(gif)))
    n = len(_gif_frames(gif))
    merged = f"wrote {gif}: {n} frames, 0.08 s at 50 frames/s; {4 - n} unchanged frames merged into the one before"
    assert n < 4 and merged in proc.stdout, proc.stdout


# ----------------------------------------------------------------------------------------------
# start-up: the benchmark, the per-kernel report, the status of a long start
# ----------------------------------------------------------------------------------------------
def test_the_kernel_log_times_each_instances_front_end_and_compilation():
    import taichi as ti
    from taichi.lang.kernel_impl import Kernel

    from ti_golf.kernel_log import KernelLog, cache_hits

    def scaled(a, k):
        for i in a:
            a[i] = k * i

    scaled.__annotations__ = {"a": ti.types.ndarray(), "k": ti.template()}  # (this module's are strings)
    scaled = ti.kernel(scaled)

    a = ti.ndarray(ti.f64, 4)
    before = Kernel.materialize
    log = KernelLog()
    with log.installed():
        scaled(a, 2)
        scaled(a, 2)  # the same instance: prepared once
        scaled(a, 3)  # a new template argument: a second instance
    assert Kernel.materialize is before  # put back
    (entry,) = [k for k in log.table() if k.name.endswith(".scaled")]
    assert entry.instances == 2 and len(set(entry.instance_names)) == 2
    assert all(name.startswith("scaled_c") for name in entry.instance_names)
    assert entry.front_end_s > 0 and entry.compile_s > 0 and entry.first_launch_s > 0 and log.busy is None
    assert log.totals()[3] >= entry.first_launch_s
    # once compiled, the rest of a first launch is the kernel's own work, not its compilation
    from ti_golf.kernel_log import _TimedProgram

    class Program:
        def compile_kernel(self, *args):
            assert log.busy is None  # (the launch wrapper says "compile": not made here)
            return "compiled"

    entry = log.kernels[next(k.name for k in log.table() if k.name.endswith(".scaled"))]
    assert _TimedProgram(Program(), entry, log).compile_kernel() == "compiled"
    assert log.busy is not None and log.busy[:2] == ("first launch", entry.name)
    np.testing.assert_array_equal(a.to_numpy(), [0, 3, 6, 9])
    line = "[D 11/28/26 14:49:03.602 23182] [kernel_compilation_manager.cpp:try_load_cached_kernel@224] "
    assert cache_hits(line + "Create kernel 'scaled_c80_0' from cache (key='T2a43')") == {"scaled_c80_0"}


def test_the_keys_and_module_lengths_of_cached_kernels_are_read_from_the_log_and_the_cache(tmp_path):
    import struct

    from ti_golf.kernel_log import cache_keys, cached_module_lines

    log = "\n".join(
        [
            "[D 11/28/26 14:49:03.602 23182] [kernel_compilation_manager.cpp:try_load_cached_kernel@224] "
            "Create kernel 'scaled_c80_0' from cache (key='T2a43')",
            "[D 11/28/26 14:49:03.700 23182] [kernel_compilation_manager.cpp:compile_and_cache_kernel@242] "
            "Cache kernel 'sweep_c82_1' (key='T9f00')",
            "[D 11/28/26 14:49:03.800 23182] Create KernelCompilationManager with offline_cache_file_path = /x",
        ]
    )
    assert cache_keys(log) == {"scaled_c80_0": "T2a43", "sweep_c82_1": "T9f00"}
    metadata, module = b'{"args":[]}', b"; ModuleID = 'kernel'\ndefine void @f() {\n  ret void\n}\n"
    good = tmp_path / "T2a43.tic"
    good.write_bytes(b"TIC\0\0\0\0\0" + struct.pack("<QQ", len(metadata), len(module)) + metadata + module + b"\n\n")
    assert cached_module_lines(good) == 4  # the module's lines, not the metadata's or the checksum's
    truncated = tmp_path / "T9f00.tic"
    truncated.write_bytes(good.read_bytes()[:40])
    (tmp_path / "other.tic").write_bytes(b"not a cache file")
    assert cached_module_lines(truncated) is None and cached_module_lines(tmp_path / "other.tic") is None
    assert cached_module_lines(tmp_path / "missing.tic") is None


def test_a_long_start_says_what_taichi_is_doing():
    from ti_golf.cli._common import StartupStatus

    class Log:  # a KernelLog in the middle of a long front end
        busy: tuple[str, str, float] | None = ("front end", "ti_golf.solvers.collide.collision_step", 0.0)

        def totals(self):
            return 14, 3.0, 0.5

    log = Log()
    status = StartupStatus(log, after_s=0.0, every_s=5.0)
    log.busy = ("front end", "ti_golf.solvers.collide.collision_step", status.start - 1.0)
    line = status.line()
    assert line is not None and line.startswith(
        "ti-golf: Taichi is reading the kernel collision_step (its front end runs in every new process, "
        "even for cached kernels); 14 kernels ready, "
    )
    assert status.line() is None  # not again before every_s
    status._said = -math.inf
    log.busy = ("compile", "ti_golf.physics.kernels.advance", status.start - 1.0)
    assert "compiling the kernel advance (or loading it from its cache)" in (status.line() or "")
    status._said = -math.inf
    log.busy = ("first launch", "ti_golf.physics.kernels.fly_to_landing", status.start - 1.0)
    assert "making machine code for the kernel fly_to_landing and running it (its first launch)" in (
        status.line() or ""
    )
    log.busy = None
    status._said = -math.inf
    assert status.line() is None  # nothing prepared now: nothing to say


@pytest.mark.slow  # three commands, each timed in processes of its own
def test_bench_startup_times_commands_in_fresh_processes_against_the_targets():
    proc = ok(run_cli("bench", "startup", "--cache", "warm", "--scenes", "lab_vacuum", "--json"))
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    rows = {r["command"]: r for r in result["commands"]}
    assert list(rows) == ["ti-golf run lab_vacuum --steps 1", "ti-golf scenes", "ti-golf keys"]
    assert rows["ti-golf run lab_vacuum --steps 1"]["warm_target_s"] == 1.2  # one ball
    assert rows["ti-golf keys"]["warm_target_s"] == rows["ti-golf scenes"]["warm_target_s"] == 0.5
    for row in rows.values():
        assert row["warm_error"] is None and 0 < row["warm_s"] < 600
        assert row["warm_pass"] == (row["warm_s"] <= row["warm_target_s"])
        assert "cold_s" not in row
    assert result["benchmark"] == "startup"  # (it was "bench", where every other benchmark says "benchmark")
    assert result["passed"] + result["failed"] == 3
    assert isinstance(result["bytecode_stale"], list)  # (make setup compiled them: see the test below)
    assert "ti-golf keys" in proc.stdout.splitlines()[2] and "target 0.5 s" in proc.stdout


def test_bench_startup_names_the_modules_whose_bytecode_python_compiles_at_every_start(tmp_path):
    import compileall
    import os

    from ti_golf.bench.startup import stale_bytecode

    package = tmp_path / "pkg"
    (package / "sub").mkdir(parents=True)
    for name in ("__init__.py", "a.py", "sub/__init__.py", "sub/b.py"):
        (package / name).write_text("X = 1\n")
    assert stale_bytecode(package) == ["pkg/__init__.py", "pkg/a.py", "pkg/sub/__init__.py", "pkg/sub/b.py"]
    assert compileall.compile_dir(str(package), quiet=1)
    assert stale_bytecode(package) == []
    later = (package / "a.py").stat().st_mtime + 10
    os.utime(package / "a.py", (later, later))  # edited after it was compiled
    assert stale_bytecode(package) == ["pkg/a.py"]


@pytest.mark.slow  # a cold compile in a subprocess
def test_bench_startup_kernels_reports_each_kernels_front_end_and_what_was_compiled():
    # from an empty cache every instance is compiled; once the cache holds them, none is
    cold = ok(run_cli("bench", "startup", "--kernels", "lab_vacuum", "--cache", "cold", "--json"))
    report = json.loads(cold.stdout.strip().splitlines()[-1])
    assert report["benchmark"] == "startup_kernels"
    assert report["instances"] > 0 and report["compiled"] == report["instances"]
    names = [k["kernel"] for k in report["kernels"]]
    assert "ti_golf.physics.kernels.advance" in names or "ti_golf.physics.kernels.fly_to_landing" in names, names
    front = [k["front_end_s"] for k in report["kernels"]]
    assert front == sorted(front, reverse=True) and sum(front) == pytest.approx(report["front_end_s"], rel=1e-3)
    first = [k["first_launch_s"] for k in report["kernels"]]
    assert min(first) > 0 and sum(first) == pytest.approx(report["first_launch_s"], rel=1e-3)
    assert sum(first) < report["stages"]["first_step_s"] + report["stages"]["setup_s"]  # (launches in both)
    assert set(report["stages"]) == {"import_s", "init_s", "setup_s", "first_step_s", "total_s"}
    lines = {k["kernel"]: k["module_lines"] for k in report["kernels"]}  # each module, found in the cache
    assert all(n > 0 for n in lines.values()) and sum(lines.values()) == report["module_lines"]
    ok(run_cli("run", "lab_vacuum", "--steps", "1"))  # the default cache now holds them
    warm_run = ok(run_cli("bench", "startup", "--kernels", "lab_vacuum", "--cache", "warm", "--json"))
    warm = json.loads(warm_run.stdout.splitlines()[-1])
    assert warm["compiled"] == 0 and warm["instances"] == report["instances"]
    assert {k["kernel"]: k["module_lines"] for k in warm["kernels"]} == lines  # the same modules, loaded
    assert f"the modules {report['module_lines']:,} lines" in warm_run.stdout


@pytest.mark.parametrize(
    "env, last",
    [
        ({"TI_GOLF_PLAIN_FRONT_END": "zzz"}, "TI_GOLF_PLAIN_FRONT_END: must be 1 (on) or 0 (off), not 'zzz'"),
        ({"TI_GOLF_PLAIN_LAUNCH": "maybe"}, "TI_GOLF_PLAIN_LAUNCH: must be 1 (on) or 0 (off), not 'maybe'"),
        ({"TI_GOLF_SCENES": "/no/such/folder"}, "TI_GOLF_SCENES: must name a folder of scene files"),
    ],
)
def test_a_mistyped_environment_switch_is_one_error_naming_it(env, last):
    # a switch other than 1 or 0 was quietly off, and a missing scenes folder listed no scenes with exit code 0
    proc = run_cli("run", "lab_vacuum", "--steps", "1", env=env)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().splitlines()[-1].startswith(f"ti-golf: error: {last}"), proc.stderr


def test_the_task_threads_variable_is_a_count(monkeypatch):
    from ti_golf.errors import ConfigError, env_count

    monkeypatch.delenv("TI_GOLF_TASK_THREADS", raising=False)
    assert env_count("TI_GOLF_TASK_THREADS") is None
    for bad in ("abc", "0", "-3"):
        monkeypatch.setenv("TI_GOLF_TASK_THREADS", bad)
        with pytest.raises(ConfigError, match=f"TI_GOLF_TASK_THREADS: must be a whole number >= 1, not '{bad}'"):
            env_count("TI_GOLF_TASK_THREADS")
    monkeypatch.setenv("TI_GOLF_TASK_THREADS", "4")
    assert env_count("TI_GOLF_TASK_THREADS") == 4


def test_a_ctrl_c_while_the_commands_modules_are_imported_ends_in_one_line(monkeypatch, capsys):
    # a Ctrl-C in the first few tenths of a second (the parser imports the commands' modules)
    # printed a traceback
    cli_main = sys.modules["ti_golf.cli.main"]  # (the module: ti_golf.cli.main is also its function's name)

    def interrupted(argv):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli_main, "build_parser", interrupted)
    assert cli_main.main(["play", "golf_hole"]) == 130
    assert capsys.readouterr().err == "ti-golf: interrupted\n"


def test_a_full_disk_names_the_output_it_could_not_write(tmp_path):
    # numpy's writes raise ENOSPC naming no file: `ti-golf: error: No space left on device`
    # said nothing of which output it was (the temporary file beside it is removed, as before)
    import errno

    from ti_golf.files import atomic_path

    target = tmp_path / "a.npz"
    with pytest.raises(OSError) as info, atomic_path(target) as tmp:
        tmp.write_bytes(b"half")
        raise OSError(errno.ENOSPC, "No space left on device")
    assert (info.value.errno, info.value.filename) == (errno.ENOSPC, str(target))
    assert list(tmp_path.iterdir()) == []


def test_the_pour_says_100_percent_asleep_only_when_every_ball_is():
    # three balls of 100,000 awake (99.997 %) were printed as "100 % asleep" beside a pile whose
    # steps were never skipped
    from ti_golf.bench.pit import asleep_share

    assert [asleep_share(f) for f in (1.0, 0.99997, 0.989, 0.0)] == ["100 %", "99.997 %", "98.9 %", "0 %"]


def test_bench_collide_steps_and_warms_up_the_pile_with_its_boulder_as_the_solver_does(monkeypatch):
    # the bench decided serial stepping (and which baseline and warm-up to run) from --n alone, while
    # the solver holds the boulder too: at the bound, the pile was said serial and stepped in parallel
    from ti_golf.bench.collide import bench_collide, widest_boulder
    from ti_golf.solvers import stepping

    n = 64
    monkeypatch.setattr(stepping, "SERIAL_MAX_BALLS", n)
    result = bench_collide(n=n, steps=1, boulder=widest_boulder(n) / 2, log=lambda _: None)
    assert result["serial"] is False and "serial_speedup" not in result, result


def test_a_run_saved_under_a_capital_npz_suffix_is_written_and_resumed(tmp_path, capsys):
    # --out took A.NPZ (its check reads the suffix in any case), ran the whole run, then the writer
    # refused the name in a traceback and kept nothing
    out = tmp_path / "A.NPZ"
    assert main(["run", "lab_vacuum", "--t", "0.05", "--out", str(out)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["A.NPZ"]
    assert main(["run", "--resume", str(out), "--t", "0.05"]) == 0
    assert "resumed at t = 0.05 s" in capsys.readouterr().out


@pytest.mark.parametrize("argv", [["--kernels", "lab_vacuum"], ["--scenes", "lab_vacuum", "--cache", "warm"]])
def test_bench_startup_checks_the_backend_variables_it_passes_on(monkeypatch, capsys, argv):
    # bench startup starts no runtime of its own: a TI_GOLF_ARCH that runtime.init refuses reached
    # the timed processes, and came back as a traceback (--kernels) or a report of failed runs, exit 0
    monkeypatch.setenv("TI_GOLF_ARCH", "foo")
    assert main(["bench", "startup", *argv]) == 2
    err = capsys.readouterr().err
    assert "TI_GOLF_ARCH: unknown backend 'foo'" in err and err.count("\n") == 1, err


def test_a_run_until_landed_of_balls_none_of_which_is_tracked_is_refused(capsys, tmp_path):
    # no ball of break_shot is tracked for its landing: the run stopped at its first check, at
    # t = 0.05 s, exit 0, saying nothing (render's run too)
    import ti_golf

    for command in (["run"], ["render", "--out", str(tmp_path / "a.png")]):
        assert main([*command, "break_shot", "--until", "landed", "--t", "1"]) == 2
        assert "--until: landed has no effect on break_shot: no ball of it is tracked" in capsys.readouterr().err
    sim = ti_golf.Simulation.from_scene("break_shot")
    with pytest.raises(ValueError, match="until='landed' has no effect: no ball is tracked"):
        sim.run(t=1.0, until="landed")
    assert sim.t == 0.0
