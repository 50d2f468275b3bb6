"""Off-screen pictures: GGUI snapshots against baselines (with a tolerance), where balls appear,
and the matplotlib fallback.

Snapshots are compared by mean absolute difference and by the share of strongly changed pixels,
never byte for byte (software Vulkan drivers differ in the last bits), and, so that a small object
cannot go missing within those shares (a ball is a few pixels of 76,800, a trail a few hundred),
by the pixels of each ball and trail colour counted in each of 4 × 4 regions. ``TI_GOLF_UPDATE_BASELINES=1``
rewrites tests/baselines/*.png; a failing comparison leaves the obtained picture and an amplified
difference in the test's tmp_path and names them in the message.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from conftest import ON_VULKAN

import ti_golf as tg
import ti_golf.render as R
from ti_golf.render import camera, frame

pytestmark = ON_VULKAN  # one worker draws with GGUI at a time (conftest)

ROOT = Path(__file__).resolve().parent.parent
BASELINES = Path(__file__).resolve().parent / "baselines"
SIZE = (320, 240)
UPDATE = os.environ.get("TI_GOLF_UPDATE_BASELINES") == "1"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
BACKGROUND = np.asarray(R.BACKGROUND_COLOR)

MAX_MEAN_DIFF_PCT = 1.0  # mean |obtained - baseline| over all pixels and channels, % of full scale
CHANGED_LEVEL = 0.25  # a pixel "changed strongly" when a channel moved by more than 25 % ...
MAX_CHANGED_FRACTION = 0.01  # ... and at most 1 % of the pixels may do so
REGIONS = (4, 4)  # the picture cut into 4 × 4 regions (rows, columns) ...
MAX_OBJECT_PIXELS_CHANGE = (2, 0.02)  # ... where the pixels of each ball and trail colour may differ
# in number from the baseline's by at most 2 pixels or 2 %, whichever is more (a ball's edge)

GGUI = R.ggui_available()
needs_ggui = pytest.mark.skipif(
    not GGUI,
    reason="GGUI needs Vulkan, which this machine lacks (apt-get install mesa-vulkan-drivers libvulkan1, "
    "or `make system-deps`); the matplotlib fallback is still tested",
)
BACKENDS = [pytest.param("ggui", marks=needs_ggui), "matplotlib"]


def read_png(path: Path) -> np.ndarray:
    import matplotlib.image as mpimg

    with open(path, "rb") as fh:
        assert fh.read(8) == PNG_SIGNATURE, f"{path} is not a PNG"
    return np.asarray(mpimg.imread(path), dtype=float)[..., :3]


def matches(
    img: np.ndarray, color: tuple[float, float, float], cos_min: float = 0.995, min_norm: float = 0.15
) -> np.ndarray:
    """Pixels whose colour is a shade of ``color`` (lit or in shadow: the same direction in RGB)."""
    c = np.asarray(color, float)
    norm = np.linalg.norm(img, axis=2)
    cos = (img @ c) / np.maximum(norm * np.linalg.norm(c), 1e-12)
    return (cos >= cos_min) & (norm >= min_norm)


def object_colours() -> dict[str, tuple[float, float, float]]:
    """The colours of balls (by status) and of their trails (blended toward white), by name."""
    from ti_golf.render import style
    from ti_golf.scene.schema import STATUS_NAMES

    colours = {}
    for status, colour in R.STATUS_COLORS.items():
        colours[f"ball {STATUS_NAMES[status]}"] = colour
        colours[f"trail {STATUS_NAMES[status]}"] = tuple(
            np.asarray(colour) * (1.0 - style.TRAIL_WHITEN) + style.TRAIL_WHITEN
        )
    return colours


def object_pixels(img: np.ndarray) -> dict[str, np.ndarray]:
    """For each ball and trail colour, how many pixels of it each of the REGIONS holds."""
    rows, cols = REGIONS
    h, w = img.shape[:2]
    counts = {}
    for name, colour in object_colours().items():
        mask = matches(img, colour)
        counts[name] = np.array(
            [
                [
                    mask[r * h // rows : (r + 1) * h // rows, c * w // cols : (c + 1) * w // cols].sum()
                    for c in range(cols)
                ]
                for r in range(rows)
            ]
        )
    return counts


def missing_objects(a: np.ndarray, b: np.ndarray) -> list[str]:
    """Where picture ``a`` holds more or fewer pixels of a ball or trail colour than ``b``, region by
    region, beyond MAX_OBJECT_PIXELS_CHANGE: a ball or a trail missing, added or moved."""
    least, share = MAX_OBJECT_PIXELS_CHANGE
    found = []
    for (name, ca), cb in zip(object_pixels(a).items(), object_pixels(b).values()):
        for (r, c), want in np.ndenumerate(cb):
            if abs(int(ca[r, c]) - int(want)) > max(least, share * want):
                found.append(f"{name} colour in region ({r}, {c}): {ca[r, c]} pixels, the baseline {want}")
    return found


def compare_with_baseline(obtained: Path, name: str, tmp_path: Path) -> None:
    baseline = BASELINES / name
    if UPDATE:
        BASELINES.mkdir(exist_ok=True)
        shutil.copyfile(obtained, baseline)
        return
    assert baseline.exists(), (
        f"no baseline {baseline}; obtained picture: {obtained}. Run with TI_GOLF_UPDATE_BASELINES=1 to create it."
    )
    a, b = read_png(obtained), read_png(baseline)
    assert a.shape == b.shape, f"size {a.shape[1]}x{a.shape[0]} differs from the baseline's {b.shape[1]}x{b.shape[0]}"
    diff = np.abs(a - b)
    mean_pct = 100.0 * float(diff.mean())
    changed = float(np.mean(diff.max(axis=2) > CHANGED_LEVEL))
    objects = missing_objects(a, b)
    if mean_pct > MAX_MEAN_DIFF_PCT or changed > MAX_CHANGED_FRACTION or objects:
        import matplotlib.image as mpimg

        kept = tmp_path / f"obtained_{name}"
        amplified = tmp_path / f"diff_x8_{name}"
        shutil.copyfile(obtained, kept)
        mpimg.imsave(amplified, np.clip(8.0 * diff, 0.0, 1.0))
        pytest.fail(
            f"{name} differs from {baseline}: mean difference {mean_pct:.3f} % (allowed "
            f"{MAX_MEAN_DIFF_PCT} %), {100 * changed:.3f} % of pixels changed by more than "
            f"{100 * CHANGED_LEVEL:.0f} % (allowed {100 * MAX_CHANGED_FRACTION:g} %); "
            f"{'; '.join(objects) or 'the balls and trails as in the baseline'}. Obtained: {kept}; "
            f"difference x8: {amplified}. If the change is intended: TI_GOLF_UPDATE_BASELINES=1 pytest "
            "tests/test_render.py"
        )


@pytest.fixture(scope="module")
def lab():
    """The lab's turbulent shot 2 s after launch (in flight), with its recorded path, over the
    ground plane."""
    sim = tg.Simulation.from_scene("lab_turbulent")
    assert len(sim.model.plane_p) == 1, "the bundled lab scene has its ground plane"
    rec = sim.run(t=2.0, record_every=5)
    assert sim.counts()["flying"] == 1
    return sim, rec


@pytest.fixture(scope="module")
def rack():
    """The break shot 0.05 s in: the cue ball rolling toward a rack of 15 balls."""
    sim = tg.Simulation.from_scene("break_shot")
    sim.step(100)
    return sim


# -- snapshots ------------------------------------------------------------------------------------
def snapshot(sim, name: str, tmp_path: Path, **kwargs) -> None:
    """Draw ``sim`` with GGUI at SIZE and compare it with tests/baselines/``name``.

    Mesa's software Vulkan driver, with the other xdist worker busy, has now and then left every
    mesh (the ground) out of a worker's first picture: the camera, the balls and the trails were
    where they belong (to the pixel), the rest was background. Such a picture, when the scene has
    a ground to draw, is drawn once more; when that one too has no meshes (the process's window
    has kept dropping them), it is drawn in a fresh process from the run saved
    (:func:`draw_in_a_fresh_process`).
    The last one drawn is compared: a ground that a change to the code stops drawing is missing
    from all of them and still fails."""
    out, baseline = tmp_path / name, BASELINES / name
    assert R.render(sim, out, size=SIZE, backend="ggui", **kwargs) == "ggui"
    expected = None if UPDATE or not baseline.exists() else read_png(baseline)
    if expected is None or not meshes_dropped(read_png(out), expected):
        compare_with_baseline(out, name, tmp_path)
        return
    assert len(sim.model.plane_p) or sim.model.terrain is not None, "a ground to draw"
    import warnings

    warnings.warn(f"GGUI drew {name} without its meshes; drawn again", stacklevel=2)
    assert R.render(sim, out, size=SIZE, backend="ggui", **kwargs) == "ggui"
    if meshes_dropped(read_png(out), expected):
        warnings.warn(f"GGUI drew {name} without its meshes twice; drawn in a fresh process", stacklevel=2)
        draw_in_a_fresh_process(sim, out, tmp_path, **kwargs)
    compare_with_baseline(out, name, tmp_path)


FRESH_DRAW = """
import sys
import numpy as np
import ti_golf as tg
import ti_golf.render as R
saved, out, camera, trails, width, height = sys.argv[1:]
tg.init(None, "f64")
sim = tg.Simulation.load(saved)
drawn = R.render(sim, out, camera=camera, size=(int(width), int(height)), backend="ggui",
                 trails=np.load(trails) if trails else None)
assert drawn == "ggui", drawn
"""


def draw_in_a_fresh_process(sim, out: Path, tmp_path: Path, camera: str = "iso", trails=None) -> None:
    """Draw ``sim`` as :func:`snapshot` does (a preset ``camera``, ``trails`` a
    :class:`~ti_golf.Recording` or None) to ``out``, in a process of its own (and so with a GGUI
    window of its own) from the run saved and the trails' positions."""
    saved, trail_file = tmp_path / "fresh_draw.npz", ""
    sim.save(saved)
    if trails is not None:
        trail_file = str(tmp_path / "fresh_draw_trails.npy")
        np.save(trail_file, np.asarray(trails.x))
    argv = [str(saved), str(out), camera, trail_file, str(SIZE[0]), str(SIZE[1])]
    done = subprocess.run([sys.executable, "-c", FRESH_DRAW, *argv], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]


def meshes_dropped(obtained: np.ndarray, baseline: np.ndarray) -> bool:
    """Whether ``obtained`` is background where ``baseline`` shows meshes: over 95 % of its pixels
    in the background colour, against less than 80 % of the baseline's."""
    background = np.all(np.abs(obtained - BACKGROUND) < 0.02, axis=2).mean()
    return bool(background > 0.95 and np.all(np.abs(baseline - BACKGROUND) < 0.02, axis=2).mean() < 0.8)


@needs_ggui
def test_lab_trajectory_side_view_snapshot(lab, tmp_path):
    sim, rec = lab
    snapshot(sim, "lab_turbulent_side.png", tmp_path, camera="side", trails=rec)


@needs_ggui
def test_break_shot_top_view_snapshot(rack, tmp_path):
    snapshot(rack, "break_shot_top.png", tmp_path, camera="top")


@needs_ggui
def test_ball_pit_snapshot(tmp_path):
    # 100,000 balls in their bin at the start of the pour (seeded random fill: always the same)
    snapshot(tg.Simulation.from_scene("ball_pit"), "ball_pit_iso.png", tmp_path, camera="iso")


@needs_ggui
def test_terrain_snapshot(tmp_path):
    # generated hills (seed 11) with bunkers, fairway and rough, and 400 balls above them
    snapshot(tg.Simulation.from_scene("terrain_3d"), "terrain_3d_iso.png", tmp_path, camera="iso")


def test_the_snapshot_comparison_sees_a_missing_ball_and_a_missing_trail(tmp_path):
    # On the baselines themselves (no GGUI needed): the flying ball of the lab shot (a few pixels),
    # most of its trail, or the cue ball of the rack erased. Each change is within the limits on the
    # whole picture (1 % mean difference, 1 % of the pixels changed strongly); the count of each
    # ball and trail colour by region must catch it.
    import matplotlib.image as mpimg

    lab = read_png(BASELINES / "lab_turbulent_side.png")
    ball = matches(lab, R.FLYING_COLOR)
    trail = matches(lab, object_colours()["trail flying"])
    assert 0 < ball.sum() < 20 and trail.sum() > 200, (ball.sum(), trail.sum())  # a tiny ball, a long trail
    most_of_trail = trail & (np.arange(lab.shape[1]) < np.percentile(np.nonzero(trail)[1], 70))
    rack = read_png(BASELINES / "break_shot_top.png")
    cue = matches(rack, R.ROLLING_COLOR) & (np.arange(rack.shape[1]) < rack.shape[1] // 4)  # left of the rack
    assert 30 < cue.sum() < 200, cue.sum()
    for baseline, name, erased, what in (
        (lab, "lab_turbulent_side.png", ball, "ball flying"),
        (lab, "lab_turbulent_side.png", most_of_trail, "trail flying"),
        (rack, "break_shot_top.png", cue, "ball rolling"),
    ):
        img = baseline.copy()
        img[erased] = np.median(baseline[~erased & ~matches(baseline, R.ROLLING_COLOR)], axis=0)  # what lies behind
        diff = np.abs(img - baseline)
        assert (
            100 * diff.mean() < MAX_MEAN_DIFF_PCT and np.mean(diff.max(axis=2) > CHANGED_LEVEL) < MAX_CHANGED_FRACTION
        )
        out = tmp_path / name
        mpimg.imsave(out, img)
        with pytest.raises(pytest.fail.Exception, match=f"{what} colour in region"):
            compare_with_baseline(out, name, tmp_path)


def test_a_picture_without_its_meshes_is_told_from_one_with_them():
    # The lab's baseline with everything but its ball and trail turned to background (what the
    # driver drew when it dropped the meshes) is told apart; the baselines themselves are not, nor
    # the rack's with its cue ball gone.
    lab = read_png(BASELINES / "lab_turbulent_side.png")
    kept = np.zeros(lab.shape[:2], bool)
    for colour in object_colours().values():
        kept |= matches(lab, colour)
    assert 200 < kept.sum() < 2000, kept.sum()
    bare = np.where(kept[..., None], lab, BACKGROUND)
    assert meshes_dropped(bare, lab)
    for name in ("lab_turbulent_side.png", "break_shot_top.png", "ball_pit_iso.png", "terrain_3d_iso.png"):
        assert not meshes_dropped(read_png(BASELINES / name), read_png(BASELINES / name)), name
    rack = read_png(BASELINES / "break_shot_top.png")
    no_cue = np.where(matches(rack, R.ROLLING_COLOR)[..., None], np.median(rack, axis=(0, 1)), rack)
    assert not meshes_dropped(no_cue, rack)


# -- where balls appear ---------------------------------------------------------------------------
@pytest.mark.parametrize("backend", BACKENDS)
def test_flying_ball_appears_where_it_is_projected(lab, tmp_path, backend):
    sim, _ = lab
    out = tmp_path / f"flying_{backend}.png"
    assert R.render(sim, out, camera="side", size=SIZE, backend=backend, min_px=3.0) == backend
    img = read_png(out)
    assert img.shape == (SIZE[1], SIZE[0], 3)
    view = R.camera_view(sim, "side", SIZE)
    (px, py), depth = view.project(sim.x)[0][0], view.project(sim.x)[1][0]
    assert depth > view.z_near and 0 <= px < SIZE[0] and 0 <= py < SIZE[1]
    ys, xs = np.nonzero(matches(img, R.FLYING_COLOR))
    assert len(xs) >= 5, f"no flying-ball colour in {out}"
    dist = np.hypot(xs + 0.5 - px, ys + 0.5 - py)
    assert dist.max() <= 3.0 + 2.0, f"flying-ball colour {dist.max():.1f} px from the projected centre ({out})"
    assert np.hypot(xs.mean() + 0.5 - px, ys.mean() + 0.5 - py) < 1.5
    for other in (R.ROLLING_COLOR, R.AT_REST_COLOR, R.OUT_OF_BOUNDS_COLOR):
        assert not matches(img, other).any()


@pytest.mark.parametrize("backend", BACKENDS)
def test_no_ball_in_view_shows_no_ball_colour(rack, tmp_path, backend):
    # above the rack, looking straight up: the sky only (the ground is behind the camera)
    view = R.View(position=(0.5, 1.0, 0.0), lookat=(0.5, 2.0, 0.0), up=(1.0, 0.0, 0.0), size=SIZE)
    out = tmp_path / f"empty_{backend}.png"
    assert R.render(rack, out, camera=view, size=SIZE, backend=backend) == backend
    img = read_png(out)
    for color in R.STATUS_COLORS.values():
        assert not matches(img, color).any(), f"a ball colour shows in {out}"
    assert np.allclose(img, R.BACKGROUND_COLOR, atol=2.5 / 255)
    # and the same camera turned toward the rack shows it
    view = R.View(position=(0.5, 1.0, 0.0), lookat=(1.07, 0.02, 0.0), size=SIZE)
    R.render(rack, out, camera=view, size=SIZE, backend=backend)
    assert matches(read_png(out), R.ROLLING_COLOR).sum() > 50


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_wall_seen_from_its_solid_side_is_cut_away(tmp_path, backend):
    # a floor and a wall at x = 1 whose solid side is x > 1, one ball in front of the wall
    scene = tg.load_scene(
        None,
        data={
            "planes": [
                {"point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]},
                {"point": [1.0, 0.0, 0.0], "normal": [-1.0, 0.0, 0.0]},
            ],
            "balls": [{"position": [0.5, 0.1, 0.0], "radius": 0.1}],
        },
    )
    sim = tg.Simulation(scene)
    out = tmp_path / "wall.png"
    inside = R.View(position=(-1.5, 0.6, 0.0), lookat=(0.5, 0.1, 0.0), size=SIZE)  # from the open side
    R.render(sim, out, camera=inside, size=SIZE, backend=backend)
    img = read_png(out)
    assert matches(img, R.WALL_COLORS[0], cos_min=0.9995).sum() > 1000  # the wall stands behind the ball
    assert matches(img, R.FLYING_COLOR).sum() > 100
    outside = R.View(position=(3.0, 0.6, 0.0), lookat=(0.5, 0.1, 0.0), size=SIZE)  # from inside the solid
    R.render(sim, out, camera=outside, size=SIZE, backend=backend)
    img = read_png(out)
    assert not matches(img, R.WALL_COLORS[0], cos_min=0.9995).any()  # cut away: the ball shows
    assert matches(img, R.FLYING_COLOR).sum() > 100


@pytest.mark.parametrize("backend", BACKENDS)
def test_hole_and_flag_appear_where_the_hole_is(tmp_path, backend):
    # putting_green: the cup at (6, 0) on the terrain, a 2.13 m flagstick; seen from above and the side
    green = tg.Simulation.from_scene("putting_green")
    cup, _, _, flag_h = camera._hole(green)
    assert cup[1] == pytest.approx(float(green.model.terrain.height(6.0, 0.0)))  # on the surface
    view = R.View(position=(6.0, 6.0, 0.0), lookat=(6.0, 0.0, 0.0), up=(1.0, 0.0, 0.0), size=SIZE)
    out = tmp_path / f"hole_top_{backend}.png"
    R.render(green, out, camera=view, size=SIZE, backend=backend)
    img = read_png(out)
    ((px, py),) = view.project(cup[None])[0]
    dark = np.nonzero(img.max(axis=2) < 0.12)
    assert len(dark[0]) >= 4, f"no cup in {out}"
    assert np.hypot(dark[1].mean() + 0.5 - px, dark[0].mean() + 0.5 - py) < 3.0  # centred on the hole
    side = R.View(position=(6.0, 1.0, 8.0), lookat=(6.0, 1.0, 0.0), size=SIZE)
    out = tmp_path / f"flag_side_{backend}.png"
    R.render(green, out, camera=side, size=SIZE, backend=backend)
    img = read_png(out)
    red = matches(img, R.FLAG_COLOR)
    assert red.sum() > 30, f"no flag in {out}"
    (_, y_top), (_, y_cup) = side.project(np.array([cup + [0.0, flag_h, 0.0], cup]))[0]
    rows = np.nonzero(red)[0]
    assert y_top - 1 <= rows.min() and rows.max() <= y_cup  # the flag flies at the top of the stick
    assert rows.mean() < 0.5 * (y_top + y_cup)


def test_no_hole_no_flag(rack, tmp_path):
    out = tmp_path / "rack.png"
    R.render(rack, out, camera="iso", size=SIZE, backend="matplotlib")
    assert not matches(read_png(out), R.FLAG_COLOR).any()
    assert camera._hole(rack) is None


def test_status_colours_are_distinct_from_each_other_and_the_scenery():
    colors = list(R.STATUS_COLORS.values())
    assert len(set(colors)) == 4
    scenery = [
        R.BACKGROUND_COLOR,
        *R.GROUND_COLORS,
        *R.WALL_COLORS,
        *R.TERRAIN_COLORS,
        *R.SURFACE_COLORS.values(),
        R.FLAG_COLOR,
        R.FLAGSTICK_COLOR,
    ]
    for i, c in enumerate(colors):
        for other in colors[i + 1 :] + scenery:
            assert not matches(np.array([[other]], float), c, cos_min=0.98).any(), (c, other)


# -- cameras and colours (no picture) -------------------------------------------------------------
def test_terrain_is_coloured_by_surface_type_and_by_height_where_a_type_has_no_colour():
    # a 4 x 4-cell slope rising along x; cells of types 0 (green), 1 (a name with no colour), 2 (rough)
    h = np.repeat(np.linspace(0.0, 1.0, 5)[:, None], 5, axis=1)
    cells = np.array([[0, 0, 1, 1], [0, 0, 1, 1], [2, 2, 1, 1], [2, 2, 0, 0]])
    origin, spacing = np.zeros(3), np.ones(2)
    _, _, by_height = frame._terrain_tiles(h, origin, spacing)
    _, _, colors = frame._terrain_tiles(h, origin, spacing, surfaces=(cells, ("green", "heather", "rough")))
    kind = cells.ravel()  # one quad per cell, in the same (x, z) order
    for k, name in ((0, "green"), (2, "rough")):
        assert matches(colors[None, kind == k], R.SURFACE_COLORS[name], cos_min=0.9999).all(), name
    np.testing.assert_array_equal(colors[kind == 1], by_height[kind == 1])  # no colour for "heather"
    # within a type, higher cells are lighter: the relief still shows
    green = np.linalg.norm(colors, axis=1)[kind == 0]
    assert green[-1] > green[0]  # the green cells at x = 3 lie above those at x = 0


def test_camera_presets_frame_the_balls(lab, rack):
    sim, rec = lab
    path = np.vstack([np.asarray(rec.x).reshape(-1, 3), sim.x])
    cases = [
        ("side", R.camera_view(sim, "side", SIZE, trails=rec), path),
        ("iso", R.camera_view(sim, "iso", SIZE, trails=rec), path),
        ("top", R.camera_view(rack, "top", SIZE), rack.x),
        ("iso", R.camera_view(rack, "iso", SIZE), rack.x),
        ("follow", R.camera_view(sim, "follow", SIZE), sim.x),
    ]
    for name, view, pts in cases:
        p, d = view.project(pts)
        assert np.all(d > view.z_near) and np.all(d < view.z_far), name
        assert np.all((p >= 0) & (p <= SIZE)), name  # every ball (and the path) in the picture
    side = cases[0][1]
    px, _ = side.project(np.array([[0.0, 0.0, 0.0], [50.0, 0.0, 0.0], [0.0, 20.0, 0.0]]))
    assert px[1, 0] > px[0, 0] and px[2, 1] < px[0, 1]  # side view: x to the right, y up
    top = cases[2][1]
    px, _ = top.project(np.array([[0.0, 0.02, 0.0], [1.0, 0.02, 0.0], [0.0, 0.02, 0.1]]))
    assert px[1, 0] > px[0, 0] and px[2, 1] > px[0, 1]  # top view: x to the right, +z down the picture
    follow = cases[4][1]
    assert follow.position[0] < sim.x[0, 0] < follow.lookat[0]  # behind ball 0, looking downrange
    still = tg.Simulation(rack.scene, x=rack.x, track=False)  # ball 0 at rest, and no launch point kept
    follow = R.camera_view(still, "follow", SIZE)
    assert follow.position[0] < still.x[0, 0] < follow.lookat[0]  # then it looks along +x


def test_ball_colours(rack):
    n = rack.n
    for mode in ("speed", "spin", "id"):
        c = R.ball_colors(rack, mode)
        assert c.shape == (n, 3) and np.all((c >= 0) & (c <= 1))
    assert len({tuple(c) for c in R.ball_colors(rack, "id")}) == n  # 16 balls, 20 colours
    speed = R.ball_colors(rack, "speed")
    assert not np.allclose(speed[0], speed[1])  # the moving cue ball stands out
    np.testing.assert_allclose(R.ball_colors(rack, "status"), [R.STATUS_COLORS[s] for s in rack.status])
    with pytest.raises(ValueError, match="color_by"):
        R.ball_colors(rack, "mass")
    with pytest.raises(ValueError, match="camera"):
        R.render(rack, "unused.png", camera="front")


# -- fallback -------------------------------------------------------------------------------------
def test_matplotlib_fallback_writes_a_png(lab, tmp_path):
    sim, rec = lab
    out = tmp_path / "fallback.png"
    assert R.render(sim, out, camera="iso", size=SIZE, trails=rec, backend="matplotlib") == "matplotlib"
    img = read_png(out)
    assert img.shape == (SIZE[1], SIZE[0], 3)
    assert matches(img, R.GROUND_COLORS[0], cos_min=0.999).any()  # the ground is drawn
    assert not list(tmp_path.glob(".ti_golf_render_*"))  # no temporary file left behind


@needs_ggui
def test_other_size_than_the_window_falls_back_or_raises(rack, tmp_path, capfd):
    R.render(rack, tmp_path / "a.png", camera="top", size=SIZE, backend="ggui")  # the window exists now
    with pytest.raises(R.RenderError, match="cannot be resized"):
        R.render(rack, tmp_path / "b.png", camera="top", size=(160, 120), backend="ggui")
    capfd.readouterr()
    for _ in range(2):
        assert R.render(rack, tmp_path / "c.png", camera="top", size=(160, 120)) == "matplotlib"
    err = capfd.readouterr().err
    assert err.count("rendering with matplotlib") <= 1  # one note per process and reason, not per frame
    assert read_png(tmp_path / "c.png").shape == (120, 160, 3)


def _python(code: str, cwd: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        cwd=cwd,
        env={**os.environ, **(env or {})},
        timeout=300,
    )


RENDER_ONE = """
    import ti_golf as tg
    from ti_golf.render import render
    sim = tg.Simulation.from_scene("break_shot")
    print(render(sim, "pic.png", camera="iso", size=(160, 120)))
"""


def test_without_vulkan_one_line_and_a_matplotlib_picture(tmp_path):
    # no Vulkan driver to be found: the loader gets an ICD list that does not exist
    proc = _python(
        RENDER_ONE,
        tmp_path,
        {"VK_ICD_FILENAMES": str(tmp_path / "none.json"), "VK_DRIVER_FILES": str(tmp_path / "none.json")},
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip().splitlines()[-1] == "matplotlib"
    assert proc.stderr.strip().splitlines() == ["ti_golf: Vulkan is not available, rendering with matplotlib"]
    assert read_png(tmp_path / "pic.png").shape == (120, 160, 3)


@needs_ggui
def test_ggui_process_is_quiet_and_leaves_no_imgui_ini(tmp_path):
    proc = _python(RENDER_ONE, tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip().splitlines()[-1] == "ggui"
    assert proc.stderr.strip() == ""  # no Taichi warnings about GGUI's own kernels
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pic.png"]  # Dear ImGui's imgui.ini went elsewhere


@pytest.mark.slow
def test_run_writes_numbered_frames_and_a_gif(tmp_path):
    # ti-golf run --frames-every K: one frame at the start and one every K steps, kept as PNGs and
    # as an animated GIF with the same number of frames
    from PIL import Image

    from tests.conftest import run_cli

    out = run_cli(
        "run",
        "break_shot",
        "--steps",
        "200",
        "--frames-every",
        "100",
        "--frames",
        str(tmp_path / "f"),
        "--gif",
        str(tmp_path / "a.gif"),
        "--size",
        "160x120",
        "--camera",
        "top",
        "--follow",  # (framed on the balls of each frame, as render frames them: see the last check)
        "--out",
        str(tmp_path / "run.npz"),
    )
    assert out.returncode == 0, out.stderr
    frames = sorted((tmp_path / "f").glob("frame_*.png"))
    assert [p.name for p in frames] == ["frame_00000.png", "frame_00001.png", "frame_00002.png"]
    with Image.open(frames[0]) as im:
        assert im.size == (160, 120)
    with Image.open(tmp_path / "a.gif") as gif:
        assert gif.n_frames == 3
    # the balls moved between the first and the last frame
    first = np.asarray(Image.open(frames[0]).convert("RGB"), dtype=float)
    last = np.asarray(Image.open(frames[-1]).convert("RGB"), dtype=float)
    assert np.abs(first - last).mean() > 0.01
    # ti-golf render --resume draws the saved run where it stopped: the run's last frame
    drawn = run_cli(
        "render",
        "--resume",
        str(tmp_path / "run.npz"),
        "--size",
        "160x120",
        "--camera",
        "top",
        "--out",
        str(tmp_path / "p.png"),
    )
    assert drawn.returncode == 0, drawn.stderr
    np.testing.assert_array_equal(np.asarray(Image.open(tmp_path / "p.png").convert("RGB"), dtype=float), last)


@pytest.mark.parametrize("backend", BACKENDS)
def test_wind_indicator_shows_only_in_wind(tmp_path, backend):
    # lab_headwind blows at 5 m/s: its picture has the wind arrow's colour; lab_turbulent is calm
    def wind_pixels(scene_name):
        sim = tg.Simulation.from_scene(scene_name)
        sim.run(t=2.0)
        out = tmp_path / f"{scene_name}_{backend}.png"
        assert R.render(sim, out, camera="side", size=SIZE, backend=backend) == backend
        img = read_png(out).astype(float)
        img = img / 255.0 if img.max() > 1.0 else img
        return int(np.count_nonzero(np.linalg.norm(img - np.asarray(frame.WIND_COLOR), axis=-1) < 0.12))

    assert wind_pixels("lab_headwind") >= 10
    assert wind_pixels("lab_turbulent") == 0
