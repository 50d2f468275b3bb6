"""The golf game: the cup's capture rule (closed form), rounds on a course, and ``ti-golf play``.

References: the capture speed v_c(b) = 2·√(R_c² − b²)·√(g/(2r)) of a ball rolling straight across
the cup (:mod:`ti_golf.game.cup`); the simulated roll of the same putt with no cup, for the game's verdicts.
"""

from __future__ import annotations

import dataclasses
import io
import math
import re

import background
import numpy as np
import pytest
from conftest import ON_VULKAN, colour_pixels, png_rgb

import ti_golf as tg
from ti_golf import cli
from ti_golf.errors import ConfigError
from ti_golf.game.cup import capture_speed, drop_time, holed_at
from ti_golf.game.rules import HOLED, OUT, RESTS, GolfGame, Shot
from ti_golf.scene.schema import GameConfig

G = 9.81
R = 0.02134  # golf ball
R_CUP = 0.054  # regulation cup


def green(**game) -> tg.Scene:
    """A flat green 10 m × 6 m (y = 0) with the cup 3 m down +x from the ball, in vacuum."""
    return tg.load_scene(
        data={
            "description": "test green",
            "air": {"rho": 0.0},
            "ball": {"radius": R, "mass": 0.04593},
            "world": {"integrator": "semi_implicit", "dt": 0.001},
            "contact": {"e": 0.3, "mu": 0.4, "mu_roll": 0.05},
            "terrain": {
                "kind": "generated",
                "amplitude": 0.0,
                "origin": [-2.0, 0.0, -3.0],
                "size": [10.0, 6.0],
                "resolution": [11, 7],
            },
            "hole": {"position": [3.0, 0.0]},
            "game": {"start": [0.0, 0.0], "max_strokes": 5, **game},
        }
    )


# ---------------------------------------------------------------------------------------------
# The capture rule on exact straight paths
# ---------------------------------------------------------------------------------------------
def straight_roll(speed: float, offset: float, dt: float = 0.005, phase: float = 0.37) -> tuple:
    """A ball rolling along +x at ``speed``, ``offset`` from the cup's centre (at the origin), sampled
    every ``dt`` from a start 0.5 m before the cup shifted by ``phase`` of a sample; gap 0 (rolling)."""
    t = np.arange(0.0, 1.0 / speed + 0.3, dt)
    x = np.zeros((len(t), 3))
    x[:, 0] = -0.5 + speed * (t + phase * dt)
    x[:, 1] = R
    x[:, 2] = offset
    return t, x, np.zeros(len(t))


@pytest.mark.parametrize("offset", [0.0, 0.02, 0.045])
def test_rolling_ball_drops_in_below_the_capture_speed_only(offset):
    # reference: over the cup for the chord 2√(R_c² − b²) at speed v, it drops in when that time
    # reaches t_drop = √(2r/g), i.e. below v_c(b). The path is straight, so the time over the cup
    # between samples is exact: 1 % either side of v_c decides, whatever the sampling.
    v_c = capture_speed(R_CUP, R, G, offset)
    assert capture_speed(R_CUP, R, G) == pytest.approx(2 * R_CUP * math.sqrt(G / (2 * R)))
    for factor, holed in ((0.99, True), (1.01, False)):
        t, x, gap = straight_roll(factor * v_c, offset)
        at = holed_at(t, x, gap, (0.0, 0.0), R_CUP, R, G)
        assert (at is not None) == holed, (factor, v_c)
        if holed:  # it drops t_drop after its centre passed over the rim
            enter = (0.5 - math.sqrt(R_CUP**2 - offset**2)) / (factor * v_c) - 0.37 * 0.005
            assert at == pytest.approx(enter + drop_time(R, G), abs=1e-12)


def test_ball_beside_the_cup_or_flying_over_it_is_not_holed():
    t, x, gap = straight_roll(0.5, R_CUP + 1e-3)  # slow, but it misses the cup by a millimetre
    assert holed_at(t, x, gap, (0.0, 0.0), R_CUP, R, G) is None
    t, x, gap = straight_roll(0.5, 0.0)
    assert holed_at(t, x, gap + 0.2 * R, (0.0, 0.0), R_CUP, R, G) is None  # a fifth of a radius up


def test_ball_coming_down_over_the_cup_drops_in_where_it_touches():
    # a descending path: gap falls linearly from 5 cm to −1 cm while x crosses the cup. It drops in
    # when its gap reaches R/10 over the cup, and not when that point lies beyond the rim.
    t = np.linspace(0.0, 0.1, 11)
    for x_touch, holed in ((0.03, True), (R_CUP + 0.01, False)):
        gap = 0.05 - 0.6 * t
        s = (0.05 - 0.1 * R) / 0.6  # when gap = R/10
        x = np.zeros((11, 3))
        x[:, 0] = x_touch + 2.0 * (t - s)
        at = holed_at(t, x, gap, (0.0, 0.0), R_CUP, R, G)
        assert (at is not None) == holed
        if holed:
            assert at == pytest.approx(s, abs=1e-12)


def test_ball_that_stops_over_the_cup_is_holed():
    t = np.arange(0.0, 0.05, 0.005)
    x = np.tile([0.01, R, 0.0], (len(t), 1))
    assert holed_at(t, x, np.zeros(len(t)), (0.0, 0.0), R_CUP, R, G) is not None


# ---------------------------------------------------------------------------------------------
# Rounds on a course
# ---------------------------------------------------------------------------------------------
def speed_at_the_cup(scene: tg.Scene, shot: Shot) -> float | None:
    """The speed [m/s] at which the putt reaches the cup's near rim on the whole green (no cup), from
    the simulated roll sampled every 5 steps (it slows by under 0.004 m/s in between: 0.2 % of
    v_c); ``None`` when it stops short."""
    ball = GolfGame(scene).ball
    sim = tg.Simulation(scene, x=ball[None], v=shot.velocity()[None], track=False)
    rec = sim.run(t=10.0, until="rest", record_every=5)
    x = np.asarray(rec.x)[:, 0]
    k = np.flatnonzero(x[:, 0] >= 3.0 - R_CUP)
    return None if k.size == 0 else float((x[k[0], 0] - x[k[0] - 1, 0]) / (5 * scene.world.dt))


def test_a_putt_drops_when_it_reaches_the_cup_slower_than_the_capture_speed():
    # reference: the same putt rolled on the whole green (no cup), whose speed at the rim decides by
    # v_c = 1.64 m/s through the centre. Speeds within 5 % of v_c are not asked.
    sc = green()
    v_c = capture_speed(R_CUP, R, G)
    seen = set()
    for kmh in (7.0, 10.0, 11.0, 14.0):  # rim speeds: none (stops short), 1.06, 1.40, 2.23 m/s
        shot = Shot(0.0, kmh, 0.0, 0.0)
        v = speed_at_the_cup(sc, shot)
        game = GolfGame(sc)
        stroke = game.play(shot)
        if v is None:
            assert stroke.outcome == RESTS and stroke.end[0] < 3.0 - R_CUP
        else:
            assert abs(v / v_c - 1.0) > 0.05, "choose another speed: too close to v_c to decide"
            assert (stroke.outcome == HOLED) == (v < v_c), (kmh, v)
        seen.add(stroke.outcome if v is None or v < v_c else "lipped over")
        if stroke.outcome == HOLED:
            assert game.over and game.outcome == HOLED and len(game.strokes) == 1
            np.testing.assert_allclose(stroke.end[[0, 2]], [3.0, 0.0])
            with pytest.raises(RuntimeError, match="over"):
                game.play(shot)
    assert seen == {RESTS, HOLED, "lipped over"}  # the speeds cover all three


def test_out_of_bounds_ends_the_round():
    game = GolfGame(green())
    stroke = game.play(Shot(180.0, 30.0, 0.0, 0.0))  # toward the near edge, 2 m behind the ball
    assert stroke.outcome == OUT and game.over and game.outcome == OUT
    assert not game.terrain.contains(*stroke.end[[0, 2]]) or stroke.end[0] <= -2.0 + 1e-6


def test_the_round_ends_after_max_strokes():
    game = GolfGame(green(max_strokes=2))
    for _ in range(2):
        assert not game.over
        stroke = game.play(Shot(90.0, 1.0, 0.0, 0.0))  # a nudge sideways
        assert stroke.outcome == RESTS and stroke.number == len(game.strokes)
    assert game.over and game.outcome == "no strokes left"


def test_a_random_start_lies_outside_even_a_wide_cup_or_is_refused():
    # a cup wider than a quarter of the course: the start was drawn in it (and holed at once)
    sc = green()
    wide = dataclasses.replace(sc, game=dataclasses.replace(sc.game, start=None))
    for radius, inside in ((2.8, False), (20.0, True)):
        free = dataclasses.replace(wide, hole=dataclasses.replace(wide.hole, radius=radius))
        if inside:
            with pytest.raises(ConfigError, match="hole.radius.*leaves no point of the course to start from"):
                GolfGame(free, seed=1)
        else:
            for seed in range(20):
                assert GolfGame(free, seed=seed).to_hole()[0] > radius


def test_a_random_start_and_the_winds_follow_the_seed():
    sc = tg.load_scene("golf_hole")
    assert sc.game.start is not None  # the bundled hole starts at its tee; without one, at random:
    free = dataclasses.replace(sc, game=GameConfig(wind_max=3.0))
    a, b, c = GolfGame(free, seed=5), GolfGame(free, seed=5), GolfGame(free, seed=6)
    np.testing.assert_array_equal(a.ball, b.ball)
    np.testing.assert_array_equal(a.wind, b.wind)
    assert not np.array_equal(a.ball, c.ball)
    for g in (a, c):
        assert g.terrain.contains(*g.ball[[0, 2]])
        assert g.to_hole()[0] >= 0.25 * g.terrain.size.max()
        assert g.terrain.gap(g.ball[None], g.radius)[0] == pytest.approx(0.0, abs=1e-12)  # resting on it
        assert g.wind[1] == 0.0 and np.hypot(g.wind[0], g.wind[2]) <= 3.0


def test_an_empty_set_clears_the_fixed_start():
    # `--set game.start=` (and None in a mapping) takes the key back to its default: no fixed
    # start, so the ball starts at a random point drawn from the seed; other keys go back to theirs
    sc = tg.load_scene("golf_hole")
    assert sc.game.start == (0.0, 0.0)
    for overrides in (["game.start="], {"game.start": None}):
        free = tg.load_scene("golf_hole", overrides)
        assert free.game.start is None and free.game.wind_max == sc.game.wind_max
        a, b = GolfGame(free, seed=7), GolfGame(free, seed=7)
        np.testing.assert_array_equal(a.ball, b.ball)
        assert np.hypot(*a.ball[[0, 2]]) > 1.0  # not the tee
    assert tg.load_scene("golf_hole", ["contact.mu_roll="]).contact.mu_roll == 0.05  # the schema's default
    assert tg.load_scene("golf_hole", ["launch.angle_deg= "]).launch.angle_deg == 45.0
    for unset in ("hole.position=", "launch.position=", "air.wind="):  # (at its default: no effect)
        with pytest.raises(ConfigError, match=f"key '{unset[:-1]}' is not set by the scene: clearing it"):
            tg.load_scene("lab_vacuum", [unset])


def _first_lie(text: str) -> str:
    return re.search(r"^Stroke 1: the ball lies at (x = [-\d.]+ m, z = [-\d.]+ m)", text, re.M).group(1)


def test_both_game_modes_start_at_the_same_random_point_of_the_seed(green_file, tmp_path, capsys, monkeypatch):
    # the report's game places the ball at a random position: the console and the window take it
    # from --seed alike; without --seed the round's seed is printed and plays the same start again
    shots = tmp_path / "shots.txt"
    shots.write_text("0 1 0 0\n")
    console = ["play", str(green_file), "--set", "game.start=", "--shots", str(shots)]
    assert cli.main([*console, "--seed", "4"]) == 0
    seeded = capsys.readouterr().out
    assert "Round seed 4: --seed 4 plays this start again." in seeded
    assert "The ball starts at a random point of the course: " in seeded
    assert cli.main([*console, "--seed", "5"]) == 0
    assert _first_lie(capsys.readouterr().out) != _first_lie(seeded)
    assert cli.main(console) == 0
    drawn = capsys.readouterr().out
    seed = re.search(r"--seed (\d+) plays this start again", drawn).group(1)
    assert cli.main([*console, "--seed", seed]) == 0
    assert _first_lie(capsys.readouterr().out) == _first_lie(drawn)

    windows = []

    class Window:  # the window's game, without a display
        def __init__(self, game, on_stroke):
            windows.append(game)

        def run(self):
            pass

    monkeypatch.setattr("ti_golf.game.window.check_display", lambda: None)
    monkeypatch.setattr("ti_golf.game.window.GolfWindow", Window)
    assert cli.main(["play", str(green_file), "--set", "game.start=", "--gui", "--seed", "4"]) == 0
    assert "Round seed 4: --seed 4 plays this start again." in capsys.readouterr().out
    x, z = windows[0].ball[[0, 2]]
    assert _first_lie(seeded) == f"x = {x:.2f} m, z = {z:.2f} m"


def test_shot_conventions():
    # direction from +x toward +z; backspin about d × ŷ gives lift: ω × v points up
    shot = Shot(90.0, 36.0, 30.0, 3000.0)
    v, w = shot.velocity(), shot.angular_velocity()
    np.testing.assert_allclose(v, [0.0, 5.0, 10.0 * math.cos(math.radians(30.0))], atol=1e-12)
    assert np.linalg.norm(w) == pytest.approx(3000.0 * 2 * math.pi / 60)
    assert np.cross(w, v)[1] > 0.0 and abs(w @ v) < 1e-9


# ---------------------------------------------------------------------------------------------
# ti-golf play (in this process: main() returns the exit code)
# ---------------------------------------------------------------------------------------------
GREEN_TOML = """description = "test green"
[air]
rho = 0.0
[ball]
radius = 0.02134
mass = 0.04593
[world]
integrator = "semi_implicit"
dt = 0.001
[contact]
e = 0.3
mu = 0.4
mu_roll = 0.05
[terrain]
kind = "generated"
amplitude = 0.0
origin = [-2.0, 0.0, -3.0]
size = [10.0, 6.0]
resolution = [11, 7]
[hole]
position = [3.0, 0.0]
[game]
start = [0.0, 0.0]
max_strokes = 5
"""
"""The green of :func:`green` as a scene file."""


@pytest.fixture
def green_file(tmp_path):
    path = tmp_path / "green.toml"
    path.write_text(GREEN_TOML)
    return path


def test_play_from_a_shots_file_holes_out_and_saves_the_round(green_file, tmp_path, capsys):
    shots = tmp_path / "shots.txt"
    shots.write_text("# a lag putt, then one at the hole\n90 2 0 0\nhole, 10, 0\n")
    out, plot = tmp_path / "round.csv", tmp_path / "round.png"
    assert cli.main(["play", str(green_file), "--shots", str(shots), "--out", str(out), "--plot", str(plot)]) == 0
    text = capsys.readouterr().out
    assert "dropped into the cup" in text and "Holed in 2 strokes." in text
    rows = out.read_text().splitlines()
    assert rows[0].startswith("stroke,direction_deg,speed_kmh") and len(rows) == 3
    assert rows[2].split(",")[14] == "holed" and float(rows[2].split(",")[-1]) == 0.0
    # the map draws each stroke's path in its own colour of the autumn map, the first red, the
    # last (here the second) yellow, in the course's view and in the 12 m around the cup
    img = png_rgb(plot)
    half = img.shape[1] // 2
    for colour in ((1.0, 0.0, 0.0), (1.0, 1.0, 0.0)):
        assert colour_pixels(img[:, :half], colour, tol=0.1).sum() > 20, f"no stroke drawn in {colour}"
    assert colour_pixels(img[:, half:], (1.0, 1.0, 0.0), tol=0.1).sum() > 20  # the last putt, near the cup


def test_the_readme_round_holes_in_three_strokes(capsys):
    # the round of the docs' game page and `make demo` (its strokes in scenes/golf_hole_round.txt, its winds
    # from --seed 3): a regression check of the whole game on the bundled course
    from ti_golf.scene.loader import scenes_dir

    shots = str(scenes_dir() / "golf_hole_round.txt")
    assert cli.main(["play", "golf_hole", "--seed", "3", "--shots", shots]) == 0
    text = capsys.readouterr().out
    assert "carried 125.8 m (apex 21.5 m), went 131.7 m; the ball is 2.34 m from the hole." in text
    assert text.rstrip().endswith("Holed in 3 strokes.")


def test_a_stroke_that_never_comes_down_has_no_carry():
    # a path that leaves the ground and lands (at its fourth point), one that never leaves it (a
    # putt: 0), and one that leaves it and never comes down: out of bounds in the air, the carry
    # was the distance to where the record stopped, 180 m for a driver 29 m up
    from ti_golf.game.rules import _carry

    path = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 1.0, 0.0], [3.0, 0.0, 4.0], [9.0, 0.0, 4.0]])
    low = np.array([True, False, False, True, True])
    assert _carry(path, low) == 5.0
    assert _carry(path, np.ones(5, bool)) == 0.0
    assert np.isnan(_carry(path[:3], low[:3]))


def test_play_asks_again_after_bad_answers_and_stops_at_the_end_of_input(green_file, capsys, monkeypatch):
    answers = "north\n\n500\n4\nabc\n0\n\n"  # one answer a line, then the input ends
    monkeypatch.setattr("sys.stdin", io.StringIO(answers))
    assert cli.main(["play", str(green_file)]) == 0
    text = capsys.readouterr().out
    # a word and a number out of range are the same mistake: the same words, with the range
    assert "direction must be a number in [-360, 360] deg (got 'north'); try again" in text
    assert "speed must be a number in [0, 350] km/h (got '500'); try again" in text
    assert "loft must be a number in [-10, 90] deg (got 'abc'); try again" in text
    assert "spin must be a number" not in text  # Enter: no spin
    assert "Stroke 2:" in text  # the first stroke (4 km/h at the hole) was played
    assert "The round ends unfinished (no more input) after 1 stroke" in text


def test_every_round_says_its_seed_and_the_seed_plays_its_winds_again(green_file, tmp_path, capsys):
    # a course with a fixed start still draws its winds from the seed: the seed is said for every
    # round, and the round it names blows the same winds again
    shots = tmp_path / "shots.txt"
    shots.write_text("0 2 0 0\n90 2 0 0\n")
    console = ["play", str(green_file), "--set", "game.wind_max=4", "--shots", str(shots)]
    assert cli.main(console) == 0
    drawn = capsys.readouterr().out
    seed = re.search(r"^Round seed (\d+): --seed \1 plays these winds again\.$", drawn, re.M).group(1)
    assert cli.main([*console, "--seed", seed]) == 0
    again = capsys.readouterr().out
    lie_winds = r"^Stroke \d: the ball lies .*; (wind .*)$"
    winds = re.findall(lie_winds, drawn, re.M)
    assert len(set(winds)) >= 2 and re.findall(lie_winds, again, re.M) == winds
    # a round that draws nothing (a fixed start, no wind drawn) has no seed to say, or to give
    assert cli.main(console[:2] + console[4:]) == 0
    assert "Round seed" not in capsys.readouterr().out
    assert cli.main([*console[:2], *console[4:], "--seed", "3"]) == 2
    assert "--seed: has no effect: game.start places the ball" in capsys.readouterr().err


def test_the_first_prompt_offers_the_clubs_and_a_club_name_gives_its_stroke(green_file, capsys, monkeypatch):
    from ti_golf.game.rules import CLUBS

    monkeypatch.setattr("sys.stdin", io.StringIO("hole\nputter\n"))
    assert cli.main(["play", str(green_file)]) == 0
    text = capsys.readouterr().out
    before = text[: text.index("Stroke 1:")]
    for name, (speed, loft, spin) in CLUBS.items():
        assert re.search(rf"^  {re.escape(name)} +{speed:g} km/h, loft +{loft:g} deg, +{spin:g} rpm", before, re.M)
    assert "carries about 161 m on tour" in before  # a 7-iron (TrackMan: 176 yd)
    assert "speed [km/h, 0 to 350, or a club]: " in text
    assert "loft [" not in text  # the putter gave loft and spin
    assert "Stroke 2:" in text  # the putt was played


@pytest.mark.parametrize(
    "content, needle",
    [
        ("0 5 95 0\n", "shots.txt:1: key 'loft' must be a number in [-10, 90] deg (got '95')"),
        ("0 5\n", "shots.txt:1: a stroke is 'direction speed loft [spin]' or 'direction club'"),
        ("0 spoon\n", "shots.txt:1: a stroke is 'direction speed loft [spin]' or 'direction club'"),
        ("\n0 fast 0\n", "shots.txt:2: key 'speed' must be a number in [0, 350] km/h (got 'fast')"),
        ("0 putter 2\n", "shots.txt:1: a club gives speed, loft and spin: 'direction club', no more"),  # (was: speed)
        (b"0 5 \xff\n", "shots.txt: is not UTF-8 text (byte 4)"),
    ],
)
def test_play_rejects_a_bad_shots_file_naming_the_line_and_field(green_file, tmp_path, capsys, content, needle):
    shots = tmp_path / "shots.txt"
    if isinstance(content, bytes):
        shots.write_bytes(content)
    else:
        shots.write_text(content)
    assert cli.main(["play", str(green_file), "--shots", str(shots)]) == 2
    err = capsys.readouterr().err
    assert needle in err and "Traceback" not in err


def test_a_missing_shots_file_is_worded_as_every_missing_file(green_file, tmp_path, capsys):
    missing = tmp_path / "nothere.txt"
    assert cli.main(["play", str(green_file), "--shots", str(missing)]) == 2
    assert capsys.readouterr().err.strip() == f"ti-golf: error: {missing}: file not found"
    assert cli.main(["run", str(tmp_path / "nothere.npz")]) == 2  # (as a scene or a saved run: the same words)
    assert capsys.readouterr().err.strip() == f"ti-golf: error: {tmp_path / 'nothere.npz'}: file not found"


def test_a_bundled_round_is_found_by_its_name_from_any_folder(tmp_path, monkeypatch, capsys):
    # an installed copy has no scenes/ folder: the docs' `--shots scenes/golf_hole_round.txt`
    # failed outside a checkout, and the round's bare name was not looked up
    monkeypatch.chdir(tmp_path)
    for name in ("golf_hole_round", "golf_hole_round.txt"):
        assert cli.main(["play", "golf_hole", "--seed", "3", "--shots", name]) == 0
        assert "holed" in capsys.readouterr().out.lower()
    assert cli.main(["play", "golf_hole", "--shots", "golf_hole_rounds"]) == 2
    assert "file not found (the bundled rounds: golf_hole_round, lab_course_round)" in capsys.readouterr().err


@pytest.mark.parametrize(
    "overrides, needle",
    [
        (["--set", "hole.position=[30, 0]"], "key 'hole.position' must lie on the terrain (x in [-2, 8] m"),
        (["--set", "game.start=[0, 9]"], "key 'game.start' must lie on the terrain"),
        (["--set", "game.start=[1e9, 0]"], "; got [1e+09, 0])"),  # (numpy's np.float64(...) reprs were shown)
        (["--set", "game.start=[3.01, 0]"], "key 'game.start' must lie outside the cup"),  # (holed before a stroke)
        (["--set", "game.max_strokes=0"], "key 'game.max_strokes' must be in [1, 1000]"),
        (["--set", "game.shot_time=1e300"], "key 'game.shot_time' must be in (0, 1000000000] s"),  # (a traceback)
    ],
)
def test_play_rejects_a_bad_course(green_file, capsys, overrides, needle):
    assert cli.main(["play", str(green_file), *overrides]) == 2
    assert needle in capsys.readouterr().err


def test_play_needs_a_course(capsys):
    assert cli.main(["play", "break_shot"]) == 2
    assert "is not a course: the golf game needs a [terrain] and a [hole]" in capsys.readouterr().err


def test_play_in_a_window_needs_a_display(green_file, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert cli.main(["play", str(green_file), "--gui"]) == 2
    out, err = capsys.readouterr()
    assert "--gui: needs a display (neither DISPLAY nor WAYLAND_DISPLAY is set)" in err
    assert "Round seed" not in out  # no round was played: no seed to play it again


def test_play_in_a_window_needs_a_backend_ggui_draws_with(green_file, capsys, monkeypatch):
    monkeypatch.setattr("ti_golf.render.offscreen.arch_ggui_refuses", lambda: "vulkan")  # as with --arch vulkan
    assert cli.main(["play", str(green_file), "--gui"]) == 2
    assert "--gui: draws with the CPU or CUDA backend (this process runs on vulkan)" in capsys.readouterr().err


WINDOW_SCRIPT = """
import os
import sys
from pathlib import Path
import ti_golf as tg
from ti_golf.render import ggui_available
if not ggui_available():
    sys.exit(77)
tg.init()
from ti_golf.game.rules import GolfGame, Shot
from ti_golf.game.window import GolfWindow
out = Path(sys.argv[1])
os.chdir(out)  # the user's folder, which must get no imgui.ini
game = GolfGame(tg.load_scene(out / "green.toml"))
window = GolfWindow(game, (640, 360), show_window=False, replay_speed=1e9)
window.frame()
window.save(str(out / "before.png"))
window.hit(Shot(game.to_hole()[1], 10.0, 0.0, 0.0))  # a putt that drops (see the tests above)
window.frame()  # the replay ends in the first frame (1e9 times real time)
window.frame()
window.save(str(out / "after.png"))
window.close()
print(game.outcome, window.replay is None, repr(window.message))
"""


def _window_run(workdir):
    (workdir / "green.toml").write_text(GREEN_TOML)
    return background.python("-c", WINDOW_SCRIPT, str(workdir)), {}


background.declare("game-window", _window_run)


@ON_VULKAN
@pytest.mark.background("game-window")
def test_the_game_window_plays_a_stroke_and_draws_the_course(background_runs):
    # one GGUI window per process: a process of its own, hidden (show_window=False)
    done, workdir = background_runs.succeeded("game-window", "GGUI needs Vulkan (apt-get install mesa-vulkan-drivers)")
    assert done.stdout.split()[:2] == ["holed", "True"] and "dropped into the cup" in done.stdout
    import matplotlib.image as mpimg

    for name in ("before.png", "after.png"):
        img = mpimg.imread(workdir / name)[..., :3]
        assert img.shape == (360, 640, 3)
        green_minus_blue = img[..., 1] - img[..., 2]
        assert green_minus_blue[:60, 300:].mean() < 0.0  # the sky: pale blue
        assert green_minus_blue[230:290, 250:400].mean() > 0.1  # the green, 12 m ahead, under the camera
    panel = mpimg.imread(workdir / "after.png")[40:200, 20:200, :3]  # (ImGui lays it out in the first frame)
    assert panel.mean() < 0.35  # the panel: dark, with its text and buttons
    assert not (workdir / "imgui.ini").exists()  # (its folder: Dear ImGui's settings go elsewhere)


def test_enter_at_the_direction_prompt_aims_as_hole_does(green_file, tmp_path, capsys, monkeypatch):
    # Enter took the bearing as the prompt rounds it (-7.0 for -7.0306 deg), so the ball went
    # elsewhere than with 'hole', though the game page says Enter aims at the hole
    rounds = []
    for direction in ("", "hole"):
        monkeypatch.setattr("sys.stdin", io.StringIO(f"{direction}\n5\n0\n\n"))
        out = tmp_path / f"round{len(rounds)}.csv"
        args = ["play", str(green_file), "--set", "game.start=[0, 0.37]", "--out", str(out)]
        assert cli.main(args) == 0
        assert "Enter: at the hole, -7.0]" in capsys.readouterr().out
        rounds.append(out.read_text())
    assert rounds[0] == rounds[1] and ",-7.03" in rounds[0]  # (the stroke's direction_deg, to its digits)


def test_a_round_s_csv_may_not_replace_the_shots_it_plays(tmp_path, monkeypatch, capsys):
    # `play --shots r.csv --out r.csv` replaced the user's strokes with the round's CSV, silently
    monkeypatch.chdir(tmp_path)
    strokes = "hole 160 20 6000\n"
    (tmp_path / "r.csv").write_text(strokes)
    assert cli.main(["play", "golf_hole", "--seed", "3", "--shots", "r.csv", "--out", "./r.csv"]) == 2
    assert "--out: is the --shots file './r.csv'" in capsys.readouterr().err
    assert (tmp_path / "r.csv").read_text() == strokes


def test_the_course_map_and_the_top_view_plots_put_plus_z_down_the_page_as_the_top_camera(monkeypatch, tmp_path):
    # seen from above with y up, the golfer's right (+z, facing +x) lies below the line of play, as
    # the `top` camera draws it; the course map and the run plots drew +z up the page, the view
    # from below, so a shot pushed right curved left on the map
    from ti_golf.game import course_map
    from ti_golf.render import plots

    figures = []
    for module in (course_map, plots):
        monkeypatch.setattr(module, "save_figure", lambda fig, path, dpi: figures.append(fig))
    course_map.plot_round(GolfGame(green()), tmp_path / "round.png")
    path = np.zeros((5, 2, 3))
    path[:, :, 0], path[:, :, 2] = np.linspace(0.0, 4.0, 5)[:, None], [0.0, 1.0]  # (on the ground: a top view)
    plots.plot_trajectory(path, tmp_path / "paths.png")
    axes = [ax for fig in figures for ax in fig.axes]
    assert len(axes) == 3
    for ax in axes:
        (_, y0), (_, y1) = ax.transData.transform([(1.0, 0.0), (1.0, 1.0)])
        assert y1 < y0, ax.get_title()  # (display y grows up the page)


def test_a_round_in_a_window_ended_by_ctrl_c_exits_130_as_in_the_console(monkeypatch, green_file, capsys):
    # the console's round exited 130 when Ctrl-C ended it unfinished; the window's exited 0
    class Window:  # a window whose round Ctrl-C ends before a stroke, without a display
        def __init__(self, game, on_stroke):
            pass

        def run(self):
            raise KeyboardInterrupt

    monkeypatch.setattr("ti_golf.game.window.check_display", lambda: None)
    monkeypatch.setattr("ti_golf.game.window.GolfWindow", Window)
    assert cli.main(["play", str(green_file), "--gui"]) == 130
    assert "interrupted" in capsys.readouterr().out
