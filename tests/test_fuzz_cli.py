"""Fuzzed command lines: every generated ``ti-golf`` command runs or exits with code 2 in one line.

Property-based (hypothesis): each command's options get numbers, garbage, empty, negative,
non-finite and huge values, and output paths that exist or not. The simulations behind the
commands are cut short (two steps of a run, two launch conditions per list of a sweep, the
benchmarks and pictures not run), so that a case takes milliseconds while the options' checks,
the scene loading and the outputs run for real. A case must return 0, or 2 with its last line of
standard error a ``ti-golf: error:`` line; a traceback, any other code or a multi-line error is a
defect. Derandomised and bounded, as ``test_fuzz.py``.
"""

from __future__ import annotations

import contextlib
import io
from unittest import mock

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from PIL import Image

from ti_golf.cli import main
from ti_golf.golf.dispersion import dispersion as real_dispersion
from ti_golf.golf.sweep import sweep as real_sweep
from ti_golf.sim.simulation import Simulation

FUZZ = settings(
    max_examples=120, derandomize=True, deadline=None, database=None, suppress_health_check=list(HealthCheck)
)

WORDS = st.sampled_from(
    [
        "0",
        "-1",
        "1",
        "2",
        "0.5",
        "1e999",
        "-1e999",
        "nan",
        "inf",
        "",
        " ",
        "abc",
        "1x1",
        "0x0",
        "16x16",
        "640x360",
        "9000x10",
        "3:1:1",
        "1:2:0",
        "1:2:0.5",
        "5,6",
        "1,,2",
        "[1]",
        "rest",
        "landed",
        "iso",
        "top",
        "cpu",
        "f32",
        "f128",
        "1000000000000",
    ]
)
VALUES = st.one_of(WORDS, st.text(max_size=8))

OPTIONS = {
    "run": ["--t", "--steps", "--until", "--record-every", "--frames-every", "--camera", "--size", "--set"],
    "sweep": ["--angles", "--speeds", "--spins", "--trajectories", "--units", "--set"],
    "shot": ["--speed", "--vla", "--hla", "--spin", "--axis", "--units", "--set"],
    "dispersion": ["--n", "--seed", "--speed", "--sd-speed", "--sd-axis", "--units", "--flight-dt", "--set"],
    "render": ["--t", "--steps", "--until", "--camera", "--size", "--color-by", "--fov", "--backend", "--set"],
    "bench collide": ["--n", "--steps", "--iterations", "--boulder"],
    "bench pit": ["--n", "--t", "--every", "--set"],
    "bench sweep": ["--n", "--dt", "--repeats"],
    "bench render": ["--n", "--frames"],
    "bench lab": ["--seconds", "--size", "--set"],
    "bench reductions": ["--n", "--repeats"],
    "bench startup": ["--cache", "--scenes", "--repeats", "--kernels", "--top"],
    "lab": ["--out", "--speed", "--size", "--set"],
}
SCENES = {
    "run": "break_shot",
    "sweep": "lab_vacuum",
    "render": "break_shot",
    "shot": "tour_shot",
    "dispersion": "tour_shot",
    "lab": "lab_magnus",
    "bench lab": "break_shot",
}


def short_run(
    self, t=None, steps=None, until=None, record_every=0, progress=None, every=0, on_every=None, recording=None
):
    return Simulation._real_run(
        self,
        steps=2,
        until=until,
        record_every=min(record_every, 1),
        progress=progress,
        every=min(every, 1),
        on_every=on_every,
        recording=recording,
    )


def short_sweep(scene, angles=None, speeds=None, spins=None, overrides=None, trajectories=0, to_rest=False):
    def cut(values):
        return None if values is None else values[:2]

    return real_sweep(scene, cut(angles), cut(speeds), cut(spins), overrides, min(trajectories, 2), to_rest)


def short_dispersion(scene, mean, sd, n=10_000, seed=0, **kwargs):
    return real_dispersion(scene, mean, sd, min(n, 8), seed, **kwargs)


def fake_render(sim, path, **kwargs) -> str:
    """A 16x16 picture in place of a render (the frames of a GIF must exist)."""
    Image.new("RGB", (16, 16)).save(path)
    return "ggui"


def run_cli(argv: list[str]) -> tuple[int, str]:
    """``main(argv)`` with the simulations cut short: its exit code and standard error."""
    err = io.StringIO()
    with contextlib.ExitStack() as stack:
        stack.enter_context(contextlib.redirect_stderr(err))
        stack.enter_context(contextlib.redirect_stdout(io.StringIO()))
        stack.enter_context(mock.patch.object(Simulation, "_real_run", Simulation.run, create=True))
        stack.enter_context(mock.patch.object(Simulation, "run", short_run))
        stack.enter_context(mock.patch("ti_golf.cli.sweep.sweep", short_sweep))
        stack.enter_context(mock.patch("ti_golf.cli.dispersion.dispersion", short_dispersion))
        stack.enter_context(mock.patch("ti_golf.render.render", fake_render))  # (run imports it to draw)
        stack.enter_context(mock.patch("ti_golf.cli.render.render", lambda *a, **k: "ggui"))
        stack.enter_context(mock.patch("ti_golf.cli.lab.check_display", lambda **k: None))  # no window opens:
        stack.enter_context(mock.patch("ti_golf.cli.lab.LabWindow.run", lambda self: None))  # it closes at once
        stack.enter_context(mock.patch("ti_golf.cli.lab.LabWindow.__init__", lambda self, *a, **k: None))
        for name in ("bench_collide", "bench_pit", "bench_sweep", "bench_render", "bench_reductions"):
            stack.enter_context(mock.patch(f"ti_golf.cli.bench.{name}", lambda **k: {"benchmark": "fuzz"}))
        stack.enter_context(mock.patch("ti_golf.cli.bench.bench_lab", lambda *a, **k: {"benchmark": "fuzz"}))
        stack.enter_context(mock.patch("ti_golf.lab.window.check_display", lambda **k: None))
        stack.enter_context(  # (no processes started: the options are what is fuzzed)
            mock.patch("ti_golf.cli.bench.bench_startup", lambda *a, **k: {"passed": 0, "failed": 0, "load_average": 0})
        )
        stack.enter_context(mock.patch("ti_golf.cli.bench.start_profile", lambda *a, **k: {}))
        stack.enter_context(mock.patch("ti_golf.cli.bench.profile_lines", lambda *a, **k: []))
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse's usage errors
            code = exc.code if isinstance(exc.code, int) else 2
    return code, err.getvalue()


def assert_runs_or_refuses(argv: list[str]) -> None:
    code, err = run_cli(argv)
    assert code in (0, 2), (argv, code, err)
    assert "Traceback" not in err, (argv, err)
    if code == 2:
        last = err.strip().splitlines()[-1]
        assert last.startswith("ti-golf: error:"), (argv, err)


def command_lines(command: str):
    words = command.split()
    scene = [SCENES[command]] if command in SCENES else []
    pairs = st.lists(st.tuples(st.sampled_from(OPTIONS[command]), VALUES), max_size=3)
    return pairs.map(lambda ps: words + scene + [w for p in ps for w in p])


@pytest.mark.slow
@FUZZ
@given(argv=st.sampled_from(sorted(OPTIONS)).flatmap(command_lines))
@example(argv=["run", "break_shot", "--frames-every", "1", "--size", "0x0"])
@example(argv=["render", "break_shot", "--fov", "nan"])
@example(argv=["sweep", "lab_vacuum", "--trajectories", "-5"])
def test_fuzzed_command_lines_run_or_are_refused(argv, tmp_path_factory):
    out = tmp_path_factory.mktemp("out")
    extra = {
        "run": ["--out", str(out / "r.npz"), "--frames", str(out / "f")],
        "sweep": ["--out", str(out / "s.csv"), "--plot", str(out / "s.png")],
        "dispersion": ["--out", str(out / "d.npz"), "--plot", str(out / "d.png")],
        "render": ["--out", str(out / "p.png")],
    }.get(argv[0], [])
    assert_runs_or_refuses(argv + extra)


@pytest.mark.parametrize("path", ["missing/dir/x.png", "", ".", "/proc/x.png"])
@pytest.mark.parametrize(
    "argv",
    [
        ["run", "break_shot", "--out"],
        ["run", "break_shot", "--plot"],
        ["run", "break_shot", "--gif"],
        ["sweep", "lab_vacuum", "--out"],
        ["sweep", "lab_vacuum", "--plot"],
        ["dispersion", "tour_shot", "--out"],
        ["dispersion", "tour_shot", "--plot"],
        ["render", "break_shot", "--out"],
        ["schema", "--out"],
        ["table", "--plot"],
        ["tour", "--plot"],
        ["play", "putting_green", "--out"],
        ["play", "putting_green", "--plot"],
    ],
    ids=lambda a: " ".join(a),
)
def test_unwritable_outputs_are_refused_before_anything_runs(argv, path):
    # a folder that does not exist, an empty path, a folder as the path, and a folder the file
    # system will not write in (as root, permission bits say yes): exit 2 naming the option
    code, err = run_cli(argv + [path])
    assert code == 2, (argv, path, err)
    last = err.strip().splitlines()[-1]
    assert last.startswith(f"ti-golf: error: {argv[-1]}") and "Traceback" not in err, err


def test_an_output_inside_a_file_is_refused_saying_it_is_a_file(tmp_path):
    # it said "folder ... does not exist" of a file that does
    (tmp_path / "x.png").write_bytes(b"")
    code, err = run_cli(["render", "break_shot", "--out", str(tmp_path / "x.png" / "a.png")])
    assert code == 2 and err.strip().endswith(f"'{tmp_path / 'x.png'}' is a file, not a folder"), err


@pytest.mark.parametrize(
    "argv, allowed",
    [
        (["run", "break_shot", "--out", "run.csv"], ".npz"),
        (["run", "break_shot", "--gif", "run.mp4"], ".gif"),
        (["sweep", "lab_vacuum", "--out", "s.parquet"], ".csv"),
        (["dispersion", "tour_shot", "--out", "d.txt"], ".csv or .npz"),
        (["render", "break_shot", "--out", "p.jpg"], ".png"),
        (["schema", "--out", "s.yaml"], ".json"),
        (["play", "putting_green", "--out", "round.npz"], ".csv"),
        (["run", "break_shot", "--plot", "trajectory"], ".png or .svg or .pdf or .eps"),  # (it wrote trajectory.png)
    ],
    ids=lambda a: " ".join(a) if isinstance(a, list) else a,
)
def test_an_output_named_for_another_format_is_refused(argv, allowed, tmp_path):
    # an output is written in one format: a name that says another (run --out x.csv wrote x.csv.npz,
    # play --out r.npz wrote CSV text) is refused before anything runs, naming the option
    argv = argv[:-1] + [str(tmp_path / argv[-1])]
    code, err = run_cli(argv)
    assert code == 2, (argv, err)
    assert err.strip().splitlines()[-1] == f"ti-golf: error: {argv[-2]}: must end in {allowed} (got {argv[-1]!r})"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "argv, usage, last",
    [
        (["sweep", "lab_vacuum", "--plto", "x.png"], "usage: ti-golf sweep", "--plto x.png (did you mean '--plot'?)"),
        (["run", "tour_shot", "--unitl", "rest"], "usage: ti-golf run", "--unitl rest (did you mean '--until'?)"),
        (["bench", "pit", "--evry=1"], "usage: ti-golf bench pit", "--evry=1 (did you mean '--every'?)"),
        (["run", "tour_shot", "--bogus"], "usage: ti-golf run", "--bogus"),
        (["keys", "extra"], "usage: ti-golf keys", "extra"),
    ],
)
def test_a_mistyped_option_gets_its_commands_usage_and_the_likely_option(argv, usage, last):
    code, err = run_cli(argv)
    assert code == 2
    assert err.startswith(usage) and err.strip().splitlines()[-1] == f"ti-golf: error: unrecognized arguments: {last}"


@pytest.mark.parametrize(
    "argv, dest, value",
    [
        (["sweep", "lab_vacuum", "--angles", "-10,45"], "angles", "-10,45"),
        (["sweep", "lab_vacuum", "--angles", "-10:10:5"], "angles", "-10:10:5"),
        (["shot", "tour_shot", "--hla", "-.5"], "hla", -0.5),
        (["run", "lab_vacuum", "--set", "air.wind=[-5,0,0]"], "overrides", ["air.wind=[-5,0,0]"]),
    ],
)
def test_a_value_that_starts_with_a_negative_number_is_a_value(argv, dest, value):
    # argparse took "-10,45" for an unknown option ("expected one argument") and asked for --angles=-10,45
    from ti_golf.cli import build_parser

    assert getattr(build_parser(argv).parse_command_line(argv), dest) == value


@pytest.mark.parametrize(
    "argv, last",
    [
        (["run", "lab_vacuum", "--t", "inf"], "--t: must be in (0, 1e+09] seconds (got inf)"),
        (["run", "lab_vacuum", "--t", "1e300"], "--t: must be in (0, 1e+09] seconds (got 1e+300)"),
        (
            ["run", "lab_vacuum", "--steps", "100000000000000"],
            "--steps: must be at most 1e+11 steps of 0.01 s (1e+09 s; got 100000000000000)",
        ),
        (
            ["render", "lab_vacuum", "--t", "inf", "--out", "r.png"],
            "--t: must be in [0, 1e+09] seconds (got inf)",
        ),
        (  # (a traceback: the run's own ValueError)
            ["render", "lab_vacuum", "--steps", "100000000000000", "--out", "r.png"],
            "--steps: must be at most 1e+11 steps of 0.01 s (1e+09 s; got 100000000000000)",
        ),
        (["bench", "study", "--tasks", "100000000"], "--tasks: must be in [2, 1,000] (got 100000000)"),  # (hung)
        (
            ["bench", "study", "--steps", "100000000000000000"],
            "--steps: must be in [1, 10,000,000] (got 100000000000000000)",
        ),
        (["dispersion", "tour_shot", "--seed", "-1"], "argument --seed: must be a whole number, 0 or more (got -1)"),
        (
            ["run", "lab_vacuum", "--set", "air.rho=1", "--set", "air.rho=2"],
            "--set: key 'air.rho' is given twice: give it once",
        ),
    ],
)
def test_an_infinite_time_or_a_negative_seed_is_one_error(argv, last, tmp_path):
    # --t inf ended in an OverflowError (its steps counted as an integer), a negative seed in numpy's
    # ValueError; --t 1e300 ran on past where a step still moves the time (1e12 s at h = 1 ms)
    argv = [str(tmp_path / a) if a.endswith(".png") else a for a in argv]
    code, err = run_cli(argv)
    assert code == 2 and err.strip().splitlines()[-1] == f"ti-golf: error: {last}", err


@pytest.mark.parametrize(
    "argv, last",
    [
        (["run", "lab_vacuum", "--record-every", "1"], "--record-every: has no effect without --out or --plot"),
        (["run", "lab_vacuum", "--camera", "top"], "--camera: has no effect without --frames or --gif"),
        (["run", "lab_vacuum", "--size", "320x200"], "--size: has no effect without --frames or --gif"),
        (["run", "lab_vacuum", "--follow"], "--follow: has no effect without --frames or --gif"),
        (["run", "lab_vacuum", "--frames-every", "2"], "--frames-every: has no effect without --frames or --gif"),
        (["sweep", "lab_vacuum", "--trajectories", "5"], "--trajectories: has no effect without --plot"),
        (["study", "bag_weather", "--figure", "carry_m"], "--figure: has no effect without --plot"),
        (["study", "bag_weather", "--lines"], "--lines: has no effect without --plot"),
        (
            ["bench", "collide", "--n", "100", "--shuffled"],
            "--shuffled: has no effect on 100 balls: the solver stores the balls in the grid's order from",
        ),
        (["sweep", "lab_vacuum", "--to-rest"], "--to-rest: has no effect without --out or --units"),  # (it rolled them)
        # given at their default values: given all the same, and without effect
        (["run", "lab_vacuum", "--camera", "iso"], "--camera: has no effect without --frames or --gif"),
        (["run", "lab_vacuum", "--record-every", "0"], "--record-every: has no effect without --out or --plot"),
        (["sweep", "lab_vacuum", "--trajectories", "21"], "--trajectories: has no effect without --plot"),
        (["lab", "--screenshot", "s.png", "--speed", "1"], "--speed: has no effect without a window"),
        (["bench", "startup", "--kernels", "lab_vacuum", "--repeats", "1"], "--repeats: has no effect with --kernels"),
        # --set keys the command does not read (each was taken, and nothing changed)
        (["run", "golf_hole", "--set", "game.wind_max=1"], "--set: key 'game.wind_max' has no effect on `ti-golf run`"),
        (["run", "lab_vacuum", "--set", "world.t_max=1"], "--set: key 'world.t_max' has no effect on `ti-golf run`"),
        (
            ["lab", "lab_magnus", "--set", "sweep.angles=[3]"],
            "--set: key 'sweep.angles' has no effect on `ti-golf lab`",
        ),
        (
            ["play", "golf_hole", "--set", "launch.speed=10"],
            "--set: key 'launch.speed' has no effect on `ti-golf play`",
        ),
        (
            ["play", "golf_hole", "--set", "air.wind=[5,0,0]"],
            "--set: key 'air.wind' has no effect while game.wind_max > 0",
        ),
        (["run", "lab_vacuum", "--gif", "g.gif", "--camera", "follow", "--follow"], "--follow: has no effect with"),
        # keys the flights, the pour or a run of its own length do not read
        (
            ["sweep", "lab_vacuum", "--set", "game.wind_max=2"],
            "--set: key 'game.wind_max' has no effect on `ti-golf sweep`",
        ),
        (["shot", "tour_shot", "--set", "world.t_end=3"], "--set: key 'world.t_end' has no effect on `ti-golf shot`"),
        (
            ["dispersion", "tour_shot", "--set", 'contact.solver="jacobi"'],
            "--set: key 'contact.solver' has no effect on `ti-golf dispersion` (each shot flies and rolls out alone",
        ),
        (["tour", "--set", "hole.radius=0.2"], "--set: key 'hole.radius' has no effect on `ti-golf tour`"),
        (["bench", "pit", "--set", "world.t_end=3"], "--set: key 'world.t_end' has no effect on `ti-golf bench pit`"),
        (
            ["run", "lab_vacuum", "--steps", "3", "--set", "world.t_end=5"],
            "--set: key 'world.t_end' has no effect with --steps",
        ),
        (
            ["render", "lab_vacuum", "--out", "r.png", "--set", "world.t_end=5"],
            "--set: key 'world.t_end' has no effect with --t or --steps, or",
        ),
        # keys and options that only the roll-out, a simulated time or a random draw reads
        (
            ["sweep", "lab_vacuum", "--set", "contact.e=0.3"],
            "--set: key 'contact.e' has no effect on `ti-golf sweep` (read only when the balls bounce and roll out",
        ),
        (
            ["dispersion", "tour_shot", "--no-roll", "--set", "world.ground=false"],
            "--set: key 'world.ground' has no effect on `ti-golf dispersion --no-roll`",
        ),
        (
            ["dispersion", "tour_shot", "--no-roll", "--flight-dt", "0.01", "--set", "world.dt=0.002"],
            "--set: key 'world.dt' has no effect on `ti-golf dispersion --no-roll` (--flight-dt steps the flights",
        ),
        (
            [
                "dispersion",
                "tour_shot",
                "--seed",
                "0",
                *(f"--sd-{o}=0" for o in ("speed", "vla", "hla", "spin", "axis")),
            ],
            "--seed: has no effect: every standard deviation is 0",
        ),
        (["tour", "--set", "contact.mu=0.2"], "--set: key 'contact.mu' has no effect on `ti-golf tour`"),
        (
            ["fit-aero", "--set", "air.Re_crisis=5e4"],
            "--set: key 'air.Re_crisis' has no effect on `ti-golf fit-aero` (the fit starts from the same",
        ),
        (
            ["render", "lab_vacuum", "--out", "r.png", "--set", "air.rho=1.0"],
            "--set: key 'air.rho' has no effect on `ti-golf render` (a picture of the initial state simulates nothing",
        ),
        (
            ["render", "lab_vacuum", "--out", "r.png", "--precision", "f64"],
            "--precision: has no effect on a picture of the initial state",
        ),
        (
            ["render", "lab_vacuum", "--out", "r.png", "--t", "0", "--until", "rest"],
            "--until: has no effect on a picture of the initial state",
        ),
        (
            ["bench", "startup", "--cache", "cold", "--repeats", "1"],
            "--repeats: has no effect with --cache cold",
        ),
        (["lab", "--t", "0"], "--t: goes with --screenshot"),
        (["study", "repose", "--gpus", "0"], "--gpus: has no effect: the tasks of repose ask for no GPU"),
    ],
)
def test_an_option_without_the_option_it_serves_is_refused(argv, last):
    # a key without effect is an error: each of these ran and quietly did nothing with it
    code, err = run_cli(argv)
    assert code == 2 and err.strip().splitlines()[-1].startswith(f"ti-golf: error: {last}"), err


def test_a_value_given_with_set_is_blamed_on_set_not_on_the_scene_file():
    # checks made once the scene is built named the bundled scene's file for a value --set gave
    for key, value, command, said in (
        ("hole.position", "[1000000,0]", ["play", "putting_green", "--shots", "none.txt"], "must lie on the terrain"),
        ("world.dt", "1e-9", ["sweep", "lab_vacuum", "--angles", "45"], "allows 6e+10 steps"),
    ):
        code, err = run_cli([*command, "--set", f"{key}={value}"])
        assert code == 2 and err.strip().splitlines()[-1].startswith(f"ti-golf: error: --set: key '{key}' {said}"), err


@pytest.mark.parametrize(
    "argv",
    [["run", "lab_vacuum", "--t", "1"], ["render", "lab_vacuum", "--t", "1", "--out", "r.png"]],
    ids=["run", "render"],
)
def test_a_run_of_more_steps_than_days_hold_is_refused(argv, tmp_path, monkeypatch):
    # run and render passed 1e300 steps of world.dt = 1e-300 s to a kernel: a Taichi TypeError and
    # exit code 1 (the simulation's own check, so not through run_cli's shortened runs)
    monkeypatch.chdir(tmp_path)
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main([*argv, "--set", "world.dt=1e-300"])
    last = err.getvalue().strip().splitlines()[-1]
    assert code == 2 and last.startswith("ti-golf: error: --set: key 'world.dt' = 1e-300 s makes a run of 1 s"), last


def test_the_keys_and_options_refused_without_effect_pass_where_they_act(tmp_path):
    # the same keys and options as above, given where they change the outcome, run
    out = str(tmp_path / "out")
    for argv in (
        ["sweep", "lab_vacuum", "--angles", "40", "--to-rest", "--out", f"{out}.csv", "--set", "contact.e=0.3"],
        ["dispersion", "tour_shot", "--n", "2", "--set", "world.ground=false"],
        ["dispersion", "tour_shot", "--n", "2", "--flight-dt", "0.01", "--set", "world.dt=0.002"],
        ["render", "lab_vacuum", "--out", f"{out}.png", "--steps", "2", "--set", "air.rho=1.0", "--precision", "f64"],
        ["render", "lab_vacuum", "--out", f"{out}.png", "--set", "air.wind=[-3,0,0]"],  # (its arrow is drawn)
    ):
        code, err = run_cli(argv)
        assert code == 0, (argv, err)


def test_a_dispersion_plot_that_cannot_be_drawn_is_said_and_fails(tmp_path):
    # with fewer than three shots landed the plot was left out, with no word and exit code 0
    plot = tmp_path / "d.png"
    code, err = run_cli(["dispersion", "tour_shot", "--n", "4", "--set", "world.t_max=0.5", "--plot", str(plot)])
    assert code == 1 and err.strip() == f"{plot} not written: 0 of the shots landed, and the plot's ellipses need 3"
    assert not plot.exists()


def test_frames_into_a_folder_whose_parent_is_missing_or_a_file_are_refused(tmp_path):
    # --frames made every missing folder on its path, where every other output refuses a missing folder
    (tmp_path / "a_file").write_text("")
    for frames, last in (
        (
            tmp_path / "no" / "sub",
            f"cannot make '{tmp_path / 'no' / 'sub'}': folder '{tmp_path / 'no'}' does not exist",
        ),
        (tmp_path / "a_file", f"'{tmp_path / 'a_file'}' is a file, not a folder"),
    ):
        code, err = run_cli(["run", "lab_vacuum", "--steps", "2", "--frames", str(frames)])
        assert code == 2 and err.strip().splitlines()[-1] == f"ti-golf: error: --frames: {last}", err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file"]


@pytest.mark.parametrize(
    "argv, last",
    [
        (
            ["sweep", "lab_vacuum", "--angles", "10", "--set", "sweep.angles=[20,30]"],
            "'sweep.angles' has no effect with --angles",
        ),
        (
            ["sweep", "lab_vacuum", "--speeds", "50", "--set", "launch.speed=60"],
            "'launch.speed' has no effect with --speeds",
        ),
        (
            ["shot", "tour_shot", "--speed", "100", "--set", "launch.speed=10"],
            "'launch.speed' has no effect with --speed",
        ),
        (["tour", "--set", "launch.speed=10"], "'launch.speed' has no effect with the tour's rows"),
    ],
)
def test_a_set_key_that_an_option_replaces_is_refused(argv, last):
    # the option won and the --set did nothing, silently
    code, err = run_cli(argv)
    assert code == 2 and err.strip().splitlines()[-1].startswith(f"ti-golf: error: --set: key {last}"), err


def test_trails_without_a_time_to_simulate_are_refused(tmp_path):
    # the picture came out as it does without --trails: nothing was simulated, so no path was drawn
    code, err = run_cli(["render", "lab_vacuum", "--out", str(tmp_path / "p.png"), "--trails"])
    assert code == 2 and err.strip().endswith(
        "--trails: has no effect without a time to simulate (--t, --steps or --until)"
    )
    assert not (tmp_path / "p.png").exists()


def test_a_set_for_a_saved_run_drawn_as_it_is_is_refused(tmp_path):
    # a saved run takes only the keys that act on its next steps: drawn without a step, the --set did nothing
    run = tmp_path / "a.npz"
    assert run_cli(["run", "lab_vacuum", "--steps", "2", "--out", str(run)])[0] == 0
    code, err = run_cli(["render", "--resume", str(run), "--set", "air.rho=1", "--out", str(tmp_path / "p.png")])
    assert code == 2 and "--set: has no effect on a saved run drawn as it is" in err, err
