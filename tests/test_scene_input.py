"""Bad scene input gets one clear error naming the file, the key and what is allowed.

Each class of mistake is checked through the API (``ti_golf.load_scene`` raising ``ConfigError``
with ``.key`` and a message holding the path and the allowed values) and, for a representative
subset, through the command line (exit code 2, one short line on stderr, no traceback).
Scene files are written into ``tmp_path`` from a copy of ``scenes/lab_turbulent.toml``.
"""

from __future__ import annotations

import dataclasses
import os
import re
import subprocess
from pathlib import Path

import pytest
from conftest import SCENES, run_cli

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

import numpy as np

import ti_golf
from ti_golf import ConfigError
from ti_golf.scene.schema import parse_range

BASE_SCENE = SCENES / "lab_turbulent.toml"


# ----------------------------------------------------------------------------------------------
# Helpers
# ----------------------------------------------------------------------------------------------
def edit_scene(section: str, key: str, value: str, text: str | None = None) -> str:
    """``text`` (default: lab_turbulent.toml) with ``[section] key = value`` set (value is TOML text).

    The key's line is replaced when the section has it, else inserted right after the section
    header; a missing section is appended. Works line by line so that the scene's description
    (which mentions "C_D = 0.3") is never touched.
    """
    lines = (BASE_SCENE.read_text(encoding="utf-8") if text is None else text).splitlines()
    header = f"[{section}]"
    try:
        start = next(i for i, ln in enumerate(lines) if ln.strip() == header)
    except StopIteration:
        return "\n".join(lines + ["", header, f"{key} = {value}", ""])
    end = next((i for i in range(start + 1, len(lines)) if lines[i].lstrip().startswith("[")), len(lines))
    pattern = re.compile(rf"^\s*{re.escape(key)}\s*=")
    for i in range(start + 1, end):
        if pattern.match(lines[i]):
            lines[i] = f"{key} = {value}"
            break
    else:
        lines.insert(start + 1, f"{key} = {value}")
    return "\n".join(lines) + "\n"


def toml_text(doc: dict) -> str:
    """A scene document of top-level strings, tables and arrays of tables as TOML text."""
    from ti_golf.scene.keys import toml_value

    lines = [f"{k} = {toml_value(v)}" for k, v in doc.items() if not isinstance(v, (dict, list))]
    for name, value in doc.items():
        tables = [(f"[{name}]", value)] if isinstance(value, dict) else []
        tables += [(f"[[{name}]]", t) for t in value] if isinstance(value, list) else []
        for header, table in tables:
            lines += [header] + [f"{k} = {toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


def write_scene(tmp_path: Path, text: str, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def assert_short_cli_error(proc: subprocess.CompletedProcess, *fragments: str) -> None:
    """Exit code 2, one short message on stderr holding every fragment, no traceback."""
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    err = proc.stderr
    assert "Traceback" not in err, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert 1 <= len(lines) <= 2, err
    assert len(err) < 600, err
    for frag in fragments:
        assert frag in err, (frag, err)


# ----------------------------------------------------------------------------------------------
# Every bundled scene is valid
# ----------------------------------------------------------------------------------------------
SCENE_FILES = sorted(SCENES.glob("*.toml"))


def test_there_are_bundled_scenes():
    assert len(SCENE_FILES) >= 4  # at least the four rows of the report's Table 3.1-1


@pytest.mark.parametrize("path", SCENE_FILES, ids=[p.stem for p in SCENE_FILES])
def test_bundled_scene_loads_with_description(path: Path):
    scene = ti_golf.load_scene(path)
    assert scene.name == path.stem
    assert isinstance(scene.description, str) and scene.description.strip()
    # the description is the file's own text, not a default
    assert scene.description == tomllib.loads(path.read_text(encoding="utf-8"))["description"]
    # a bare name resolves to the same bundled file
    assert Path(ti_golf.load_scene(path.stem).path).resolve() == path.resolve()


def test_edit_helper_produces_loadable_scene(tmp_path):
    """Guards the helper: a valid edit loads and takes effect (so the failures below are real)."""
    path = write_scene(tmp_path, edit_scene("air", "C_D", "0.25"))
    scene = ti_golf.load_scene(path)
    assert scene.air.C_D == 0.25
    assert scene.description == ti_golf.load_scene(BASE_SCENE).description  # description untouched
    path = write_scene(tmp_path, edit_scene("contact", "e", "0.7"), "new_section.toml")
    assert ti_golf.load_scene(path).contact.e == 0.7


# ----------------------------------------------------------------------------------------------
# Bad keys and values, through the API
# ----------------------------------------------------------------------------------------------
# (section, key, TOML value, expected ConfigError.key, fragments the message must contain)
BAD_VALUES = {
    # unknown keys: the message lists what the table allows
    "unknown_key": ("air", "rhoo", "1.3", "air.rhoo", ["'rho'", "rho, gamma, C_D, C_M, omega_M, C_omega, wind"]),
    "unknown_key_world": ("world", "dtt", "0.01", "world.dtt", ["'dt'", "integrator"]),
    # wrong types
    "string_for_number": ("air", "C_D", '"0.3"', "air.C_D", ["must be a number", "'0.3'"]),
    "bool_for_number": ("ball", "mass", "true", "ball.mass", ["must be a number in [1e-06, 1000000] kg", "True"]),
    "list_of_2_for_vec3": ("air", "wind", "[1, 2]", "air.wind", ["list of 3 numbers", "m/s"]),
    "string_for_vec3": ("launch", "spin", '"0,0,10"', "launch.spin", ["list of 3 numbers", "rad/s"]),
    "bool_in_vec3": ("world", "gravity", "[0, true, 0]", "world.gravity", ["list of 3 numbers"]),
    "float_for_int": ("air", "gamma", "1.5", "air.gamma", ["integer", "1.5"]),
    "number_for_bool": ("world", "ground", "1", "world.ground", ["true or false"]),
    "number_for_str": ("world", "integrator", "4", "world.integrator", ["string"]),
    "unknown_integrator": ("world", "integrator", '"euler"', "world.integrator", ["'semi_implicit'", "'rk4'", "euler"]),
    "unknown_air_model": ("air", "model", '"wind_tunnel"', "air.model", ["'lab'", "'spin_ratio'", "wind_tunnel"]),
    # non-finite numbers (nan and inf are valid TOML floats)
    "nan_C_D": ("air", "C_D", "nan", "air.C_D", ["finite", "nan"]),
    "inf_C_D": ("air", "C_D", "inf", "air.C_D", ["finite", "inf"]),
    "minus_inf_dt": ("world", "dt", "-inf", "world.dt", ["finite"]),
    "nan_speed": ("launch", "speed", "nan", "launch.speed", ["finite"]),
    "nan_in_vec3": ("air", "wind", "[nan, 0, 0]", "air.wind", ["finite"]),
    "nan_gamma": ("air", "gamma", "nan", "air.gamma", ["integer"]),
    "nan_in_sweep_list": ("sweep", "angles", "[36, nan]", "sweep.angles", ["finite"]),
    # out of range
    "mass_zero": ("ball", "mass", "0", "ball.mass", ["in [1e-06, 1000000] kg", "0.0"]),
    "dt_negative_with_its_unit": ("world", "dt", "-1", "world.dt", ["must be in (0, 1] s (got -1.0)"]),
    "altitude_with_its_unit": ("air", "altitude", "6000", "air.altitude", ["must be in [-500, 5000] m (got 6000.0)"]),
    "mass_negative": ("ball", "mass", "-0.045", "ball.mass", ["in [1e-06, 1000000] kg", "-0.045"]),
    "radius_zero": ("ball", "radius", "0.0", "ball.radius", ["in [0.0001, 10] m"]),
    "radius_negative": ("ball", "radius", "-0.02", "ball.radius", ["in [0.0001, 10] m", "-0.02"]),
    "e_above_1": ("contact", "e", "1.5", "contact.e", ["[0, 1]", "1.5"]),
    "e_negative": ("contact", "e", "-0.1", "contact.e", ["[0, 1]", "-0.1"]),
    "mu_negative": ("contact", "mu", "-0.1", "contact.mu", [">= 0", "-0.1"]),
    "k_p_negative": ("contact", "k_p", "-0.01", "contact.k_p", ["[0, 1]"]),
    "k_p_above_1": ("contact", "k_p", "1.01", "contact.k_p", ["[0, 1]", "1.01"]),
    "dt_zero": ("world", "dt", "0.0", "world.dt", ["in (0, 1] s"]),
    "dt_negative": ("world", "dt", "-0.01", "world.dt", ["in (0, 1] s", "-0.01"]),
    "gamma_3": ("air", "gamma", "3", "air.gamma", ["1, 2", "3"]),
    "gamma_0": ("air", "gamma", "0", "air.gamma", ["1, 2"]),
    "angle_above_90": ("launch", "angle_deg", "100", "launch.angle_deg", ["[-90, 90] degrees"]),
    "e_has_no_unit": ("contact", "e", "2", "contact.e", ["must be in [0, 1] (got 2.0)"]),
    "sweep_range_backwards": ("sweep", "angles", '"36:30:0.1"', "sweep.angles", ["STOP must be >= START"]),
    "sweep_range_step_zero": ("sweep", "angles", '"36:37:0"', "sweep.angles", ["STEP must be > 0"]),
    # the hole: a position is required, the cup has a size
    "hole_without_position": ("hole", "radius", "0.054", "hole.position", ["required", "[x, z]"]),
    "hole_radius_zero": ("hole", "radius", "0", "hole.radius", ["> 0"]),
    "hole_flag_negative": ("hole", "flag_height", "-1", "hole.flag_height", [">= 0"]),
}


@pytest.mark.parametrize("model", ["spin_ratio", "spin_reynolds"])
def test_the_spin_ratio_models_need_turbulent_flow(tmp_path, model):
    # their C_D, C_L are quadratic-drag coefficients: with γ = 1 the scene is refused, in the
    # file and through the API, rather than flown with a law nobody asked for
    text = edit_scene("air", "gamma", "1", edit_scene("air", "model", f'"{model}"'))
    text = "\n".join(ln for ln in text.splitlines() if not re.match(r"\s*(C_D|C_M|omega_M|C_omega)\s*=", ln))  # unread
    path = write_scene(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        ti_golf.load_scene(path)
    assert info.value.key == "air.gamma" and info.value.source == str(path)
    assert "must be 2" in str(info.value) and model in str(info.value)
    laminar = ti_golf.load_scene("lab_laminar")
    scene = dataclasses.replace(laminar, air=dataclasses.replace(laminar.air, model=model))
    with pytest.raises(ValueError, match="air.gamma must be 2"):
        ti_golf.Simulation(scene)


@pytest.mark.parametrize(
    "name, value, fragment",
    [
        ("C_D_S", "[-5, 0, 0]", "gives C_D(S) from -5 to -5 over the spin ratios 0.02 ≤ S ≤ 0.75"),
        ("C_D_S", "[0.1, 0, -1]", "gives C_D(S) from -0.4625 to 0.0996"),  # negative past S = 0.316
        ("C_L_S", "[0, 0, -300]", "gives C_L(S) from -168.8 to -0.12"),
        ("C_D_S", "[0, 0, 1000]", "it must stay within [0, 100]"),
    ],
)
def test_spin_reynolds_coefficients_whose_drag_turns_negative_or_overflows_are_refused(name, value, fragment):
    # a negative drag fed the ball energy: apex 1.4e40 yd, exit 0; the quadratic is checked at the
    # ends of the fits' spin ratios and at its vertex
    with pytest.raises(ConfigError) as info:
        ti_golf.load_scene("tour_shot", [f"air.{name}={value}"])
    assert info.value.key == f"air.{name}" and fragment in str(info.value), str(info.value)
    assert ti_golf.load_scene("tour_shot", ["air.C_D_S=[0.1, 0, -0.1]"]).air.C_D_S == (0.1, 0.0, -0.1)


def test_every_key_that_its_setting_leaves_unread_is_refused(tmp_path):
    # walks the key table: each key declared with read_when (it takes effect only under another
    # key's setting) is given with that setting violated, and refused naming the file, the key
    # and the setting it needs
    from ti_golf.scene.schema import ARRAY_SCHEMA, SCHEMA

    sample = {"float": 0.5, "int": 2, "bool": True, "str": "x", "vec3": [1.0, 1.0, 1.0], "vec2": [2.0, 2.0]}
    base = {"description": "t", "launch": {"speed": 10.0}, "world": {"dt": 0.01}}
    cases = [(s, k, key) for s, keys in SCHEMA.items() for k, key in keys.items() if key.read_when]
    cases += [(a, k, key) for a, keys in ARRAY_SCHEMA.items() for k, key in keys.items() if key.read_when]
    assert {(s, k) for s, k, _ in cases} >= {
        ("game", "wind_max"),
        ("air", "C_D"),
        ("terrain", "seed"),
        ("blocks", "number"),
        ("contact", "iterations"),
    }
    for section, name, key in cases:
        other, allowed = key.read_when
        if other.startswith("["):  # a table the scene must have: leave it out
            doc = {**base, section: {name: sample.get(key.kind, 1.0)}}
            doc.pop(other.strip("[]"), None)
            with pytest.raises(ConfigError) as err:
                ti_golf.load_scene("s.toml", data=doc)
            assert err.value.key == f"{section}.{name}" and f"only read when the scene has a {other}" in str(err.value)
            continue
        table_of_other, other_key = other.split(".") if "." in other else (section, other)
        other_decl = (SCHEMA | ARRAY_SCHEMA)[table_of_other][other_key]
        choices = (True, False) if other_decl.kind == "bool" else other_decl.check.choices
        bad = next(c for c in choices if c not in allowed)  # a valid setting that leaves the key unread
        doc = {k: dict(v) for k, v in base.items() if isinstance(v, dict)} | {"description": "t"}
        value = sample.get(key.kind, 1.0)
        if getattr(key.check, "choices", None):  # a valid value: only the setting is wrong
            value = key.check.choices[0]
        if section in ARRAY_SCHEMA:
            doc[section] = [{name: value, other_key: bad}]
            where = f"{section}[0].{name}"
        else:
            doc.setdefault(section, {})[name] = value
            doc.setdefault(table_of_other, {})[other_key] = bad
            where = f"{section}.{name}"
        with pytest.raises(ConfigError) as err:
            ti_golf.load_scene("s.toml", data=doc)
        text = str(err.value)
        assert err.value.key == where and "is only read when" in text and other.split(".")[-1] in text, text


def test_keys_read_under_other_tables_are_refused_where_those_leave_them_unread(tmp_path):
    # world.ground_height places the ground plane, measures the log wind's heights and rests a
    # launched ball on the ground; with none of the three it does nothing. contact.turf shapes
    # impacts on a ground, and does nothing without one.
    balls = [{"position": [0.0, 1.0, 0.0]}, {"position": [1.0, 1.0, 0.0]}]
    unread = {
        "world.ground_height": {"world": {"ground": False, "ground_height": 1.0}, "balls": balls},
        "world.ground_height ": {
            "world": {"ground_height": 1.0},
            "planes": [{"point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}],
            "launch": {"position": [0.0, 0.1, 0.0]},
        },
        "contact.turf": {"world": {"ground": False}, "contact": {"turf": True}, "balls": balls},
    }
    for dotted, doc in unread.items():
        path = write_scene(tmp_path, toml_text({"description": "t", **doc}))
        with pytest.raises(ConfigError) as err:
            ti_golf.load_scene(path)
        assert err.value.key == dotted.strip() and "is only read when" in str(err.value), str(err.value)
        assert err.value.source == str(path)
    read = [
        {"world": {"ground_height": 1.0}, "balls": balls},  # the ground plane
        {"world": {"ground": False, "ground_height": 1.0}, "air": {"wind_profile": "log"}, "balls": balls},
        {"world": {"ground": False, "ground_height": 1.0}, "launch": {"speed": 10.0}},  # rests on it
        {
            "world": {"ground": False},
            "contact": {"turf": True},
            "balls": balls,
            "planes": [{"point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}],
        },
    ]
    for doc in read:
        ti_golf.load_scene("s.toml", data={"description": "t", **doc})
    # the command line's --set is named as the source, and exits with code 2
    path = write_scene(tmp_path, toml_text({"description": "t", "world": {"ground": False}, "balls": balls}))
    with pytest.raises(ConfigError) as err:
        ti_golf.load_scene(path, ["world.ground_height=2"])
    assert err.value.source == "overrides" and err.value.key == "world.ground_height"
    res = run_cli("run", str(path), "--steps", "1", "--set", "contact.turf=true")
    assert res.returncode == 2 and "contact.turf" in res.stderr and "Traceback" not in res.stderr


OVERFLOWING = {
    "launch.speed": 1e200,
    "launch.spin": [0.0, 0.0, 1e200],
    "air.wind": [1e200, 0.0, 0.0],
    "air.rho": 1e200,
    "air.C_D": 1e200,
    "air.C_M": 1e200,
    "air.omega_M": 1e-200,
    "air.C_omega": 1e200,
    "world.gravity": [0.0, -1e200, 0.0],
    "world.dt": 1e200,
    "ball.mass": 1e-200,
    "ball.radius": 1e200,
    "launch.position": [1e200, 0.0, 0.0],
    "terrain.origin": [0.0, 0.0, 1e200],
}
"""Values that the keys' old bounds (>= 0, > 0, none) allowed and that overflowed in the first
steps, each ending the run with "went non-finite" (exit code 3) instead of naming the key."""


def test_values_that_overflow_the_arithmetic_are_refused_and_the_limits_themselves_fly():
    for dotted, value in OVERFLOWING.items():
        with pytest.raises(ConfigError) as err:
            ti_golf.load_scene("lab_magnus", {dotted: value})
        assert err.value.key == dotted and "must be" in str(err.value), str(err.value)
    res = run_cli("run", "lab_magnus", "--steps", "1", "--set", "launch.speed=1e200")
    assert res.returncode == 2 and "launch.speed" in res.stderr and "[0, 1000] m/s" in res.stderr, res.stderr
    with pytest.raises(ConfigError, match=r"sweep.speeds' must each be in \[0, 1000\] m/s"):
        ti_golf.load_scene("lab_magnus", {"sweep.speeds": [10.0, 2000.0]})
    res = run_cli("sweep", "lab_magnus", "--angles", "30", "--speeds", "1e200")  # ("no ball landed" before)
    assert res.returncode == 2 and "--speeds" in res.stderr and "[0, 1000] m/s" in res.stderr, res.stderr
    with pytest.raises(ConfigError) as err:  # from Python, the error names the argument, not the option
        ti_golf.sweep("lab_magnus", speeds=[2000.0])
    assert err.value.source == "speeds" and "[0, 1000] m/s" in str(err.value)
    # at a limit, alone, the ball flies with finite numbers (larger steps still blow up, as any
    # explicit step does: that is world.dt's error, "went non-finite; try a smaller world.dt")
    from ti_golf.scene.checks import GRAVITY_LIMIT, SPEED_LIMIT, SPIN_LIMIT

    at_limits = {
        "launch.speed": SPEED_LIMIT,
        "launch.spin": [SPIN_LIMIT, -SPIN_LIMIT, SPIN_LIMIT],
        "air.wind": [-SPEED_LIMIT, SPEED_LIMIT, SPEED_LIMIT],
        "world.gravity": [GRAVITY_LIMIT, -GRAVITY_LIMIT, GRAVITY_LIMIT],
    }
    for dotted, value in at_limits.items():
        sim = ti_golf.Simulation(ti_golf.load_scene("lab_magnus", {dotted: value, "world.dt": 1e-4}))
        sim.step(20)
        assert np.isfinite(sim.x).all() and np.isfinite(sim.v).all(), dotted


def test_a_flight_that_ctrl_c_could_not_stop_is_refused():
    # a sweep flies every ball to landing in one kernel launch, which holds Ctrl-C: world.t_max /
    # world.dt steps of a ball that never lands (no gravity) ran for days
    from ti_golf.golf.sweep import FLIGHT_STEPS_MAX

    scene = ti_golf.load_scene("lab_vacuum", {"world.dt": 1e-7, "world.gravity": [0.0, 0.0, 0.0]})
    with pytest.raises(ConfigError) as err:
        ti_golf.sweep(scene, angles_deg=[30.0])
    # (named where the step came from: the overrides gave world.dt)
    assert (err.value.source, err.value.key) == ("overrides", "world.dt")
    assert f"at most {FLIGHT_STEPS_MAX:.0e}" in str(err.value) and "6e+08 steps" in str(err.value)
    scene = ti_golf.load_scene("lab_vacuum", {"world.t_max": 1e3, "world.dt": 1e-6})
    with pytest.raises(ConfigError) as err:
        ti_golf.sweep(scene, angles_deg=[30.0])
    assert (err.value.source, err.value.key) == ("overrides", "world.t_max")


def test_balls_too_small_for_how_far_they_are_spread_stop_with_a_message():
    # the grid's cells are the largest diameter (plus the skin) wide, and their coordinates i32:
    # two 0.1 mm balls a thousand kilometres apart lie 4.5e9 cells apart (a Python OverflowError
    # deep in the grid's set-up before, for a block of balls of radius 1e-200 m)
    def two_grains(apart: float) -> ti_golf.Simulation:
        balls = [{"position": [0.0, 0.0, 0.0]}, {"position": [apart, 0.0, 0.0]}]
        doc = {"description": "t", "world": {"ground": False}, "ball": {"radius": 1e-4}, "balls": balls}
        return ti_golf.Simulation(ti_golf.load_scene("s.toml", data=doc))

    far = two_grains(1e6)
    with pytest.raises(ti_golf.SimulationError, match="grid cells from the origin"):
        far.step(1)
    two_grains(1.0).step(1)  # a metre apart: 4,500 cells


def test_a_set_setting_that_leaves_a_key_of_the_file_unread_drops_that_key():
    # across places the command line wins: flying tour_shot without its ground leaves the file's
    # contact.turf unread, and switching lab_magnus to the spin_ratio air its C_D and C_M
    flight = ti_golf.load_scene("tour_shot", ["world.ground=false"])
    assert ti_golf.load_scene("tour_shot").contact.turf and not flight.contact.turf
    assert not flight.world.ground
    air = ti_golf.load_scene("lab_magnus", ["air.model=spin_ratio"]).air
    assert air.model == "spin_ratio" and air.C_D == 0.3 and air.C_M == 0.0  # (the defaults)
    # but a key given on the command line, or in a file that its own settings leave unread, is refused
    with pytest.raises(ConfigError) as err:
        ti_golf.load_scene("tour_shot", ["world.ground=false", "contact.turf=true"])
    assert err.value.source == "overrides" and err.value.key == "contact.turf"
    with pytest.raises(ConfigError) as err:
        ti_golf.load_scene("lab_magnus", ["air.model=spin_ratio", "air.C_D=0.2"])
    assert err.value.source == "overrides" and err.value.key == "air.C_D"


def test_a_change_that_leaves_a_key_read_across_tables_unread_drops_it():
    # the launched ball rests on the ground at ground_height; once it is placed, the key is read by
    # nothing (no ground plane, no log wind), so a change that places it takes the key back to its
    # default, as changes do with the keys a read_when setting leaves unread
    from ti_golf.scene.document import scene_document, with_changes

    scene = ti_golf.load_scene(
        "s.toml", data={"description": "t", "world": {"ground": False, "ground_height": 1.5}, "launch": {}}
    )
    assert scene.world.ground_height == 1.5 and scene_document(scene)["world"]["ground_height"] == 1.5
    placed = with_changes(scene, {"launch.position": [0.0, 3.0, 0.0]})
    assert placed.world.ground_height == 0.0 and "ground_height" not in scene_document(placed)["world"]
    kept = with_changes(scene, {"launch.speed": 20.0})  # still resting on the ground: kept
    assert kept.world.ground_height == 1.5
    from ti_golf.lab.params import parameters  # the lab shows it unread, so it cannot be changed

    def shown_read(s):
        return next(p.read for p in parameters(s) if p.key == "world.ground_height")

    assert shown_read(scene) and not shown_read(placed)


@pytest.mark.parametrize("case", list(BAD_VALUES), ids=list(BAD_VALUES))
def test_bad_value_names_file_key_and_allowed(tmp_path, case):
    section, key, value, want_key, fragments = BAD_VALUES[case]
    path = write_scene(tmp_path, edit_scene(section, key, value))
    with pytest.raises(ConfigError) as info:
        ti_golf.load_scene(path)
    err = info.value
    assert err.key == want_key
    assert err.source == str(path)
    msg = str(err)
    assert str(path) in msg and f"'{want_key}'" in msg, msg
    for frag in fragments:
        assert frag in msg, (frag, msg)
    assert "\n" not in msg


@pytest.mark.parametrize(
    "section, key, value, attr",
    [
        ("contact", "e", "0", 0.0),
        ("contact", "e", "1", 1.0),
        ("contact", "k_p", "0", 0.0),
        ("contact", "k_p", "1.0", 1.0),
        ("contact", "mu", "0", 0.0),
        ("air", "gamma", "1", 1),
        ("air", "gamma", "2.0", 2),  # an integral float is an integer
        ("air", "C_D", "0", 0.0),
    ],
)
def test_range_boundaries_are_allowed(tmp_path, section, key, value, attr):
    """The documented ranges are inclusive where the schema says so ([0, 1], >= 0, 1 or 2)."""
    scene = ti_golf.load_scene(write_scene(tmp_path, edit_scene(section, key, value)))
    got = getattr(getattr(scene, section), key)
    assert got == attr and type(got) is type(attr)


# Unknown tables and top-level keys: (appended TOML text, expected key, fragments)
BAD_TABLES = {
    "unknown_table": ("[weather]\nrain = 0.1\n", "weather", ["air, ball, launch, world, contact, sweep, terrain"]),
    "misspelt_table": ("[airr]\nrho = 1.2\n", "airr", ["did you mean 'air'", "air, ball, launch"]),
}


@pytest.mark.parametrize("case", list(BAD_TABLES), ids=list(BAD_TABLES))
def test_unknown_table_names_file_and_allowed_tables(tmp_path, case):
    extra, want_key, fragments = BAD_TABLES[case]
    path = write_scene(tmp_path, BASE_SCENE.read_text(encoding="utf-8") + "\n" + extra)
    with pytest.raises(ConfigError) as info:
        ti_golf.load_scene(path)
    assert info.value.key == want_key
    msg = str(info.value)
    assert str(path) in msg and want_key in msg
    for frag in fragments:
        assert frag in msg, (frag, msg)


def test_table_given_as_value_is_rejected(tmp_path):
    text = "launch = 5\n" + BASE_SCENE.read_text(encoding="utf-8").replace("[launch]", "[launch_removed]")
    text = text.replace("[launch_removed]\nspeed = 80.0\nangle_deg = 36.6\n", "")
    assert "[launch" not in text
    path = write_scene(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        ti_golf.load_scene(path)
    assert info.value.key == "launch"
    assert str(path) in str(info.value) and "table" in str(info.value)


def test_description_must_be_text(tmp_path):
    text = re.sub(r'^description = ".*"$', "description = 5", BASE_SCENE.read_text(encoding="utf-8"), flags=re.M)
    path = write_scene(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        ti_golf.load_scene(path)
    assert info.value.key == "description"
    assert str(path) in str(info.value) and "string" in str(info.value)


# ----------------------------------------------------------------------------------------------
# Files that cannot be read or parsed
# ----------------------------------------------------------------------------------------------
def _missing(tmp_path: Path) -> Path:
    return tmp_path / "no_such_folder" / "missing.toml"


def _directory(tmp_path: Path) -> Path:  # unreadable as a file, even for root
    d = tmp_path / "folder.toml"
    d.mkdir()
    return d


def _bad_utf8(tmp_path: Path) -> Path:
    p = tmp_path / "latin1.toml"
    p.write_bytes(BASE_SCENE.read_bytes().replace(b"Lab Table", b"Lab \xff\xfe Table", 1))
    return p


def _malformed(tmp_path: Path) -> Path:
    return write_scene(tmp_path, BASE_SCENE.read_text(encoding="utf-8").replace("[world]", "[world", 1), "broken.toml")


def _duplicate_table(tmp_path: Path) -> Path:
    return write_scene(tmp_path, BASE_SCENE.read_text(encoding="utf-8") + "\n[world]\ndt = 0.02\n", "dup.toml")


BAD_FILES = {
    "missing": (_missing, ["not found"]),
    "directory": (_directory, ["directory"]),
    "invalid_utf8": (_bad_utf8, ["UTF-8"]),
    "malformed_toml": (_malformed, ["not valid TOML", "line"]),
    "duplicate_table": (_duplicate_table, ["not valid TOML"]),
}


@pytest.mark.parametrize("case", list(BAD_FILES), ids=list(BAD_FILES))
def test_bad_file_names_the_file(tmp_path, case):
    make, fragments = BAD_FILES[case]
    path = make(tmp_path)
    with pytest.raises(ConfigError) as info:
        ti_golf.load_scene(path)
    assert info.value.key is None
    assert info.value.source == str(path)
    msg = str(info.value)
    assert msg.startswith(str(path)), msg
    for frag in fragments:
        assert frag in msg, (frag, msg)


# ----------------------------------------------------------------------------------------------
# The same errors through the command line (a representative subset)
# ----------------------------------------------------------------------------------------------
CLI_VALUE_CASES = [
    ("sweep", "unknown_key"),
    ("run", "list_of_2_for_vec3"),
    ("sweep", "bool_for_number"),
    ("run", "nan_C_D"),
    ("sweep", "mass_zero"),
    ("run", "e_above_1"),
    ("sweep", "gamma_3"),
]


@pytest.mark.parametrize("command, case", CLI_VALUE_CASES, ids=[f"{c}-{k}" for c, k in CLI_VALUE_CASES])
def test_cli_bad_value_exits_2_with_one_line(tmp_path, command, case):
    section, key, value, want_key, fragments = BAD_VALUES[case]
    path = write_scene(tmp_path, edit_scene(section, key, value))
    proc = run_cli(command, str(path))
    assert_short_cli_error(proc, str(path), want_key, *fragments)
    assert proc.stdout.strip() == ""


CLI_FILE_CASES = [("sweep", "missing"), ("run", "directory"), ("sweep", "invalid_utf8"), ("run", "malformed_toml")]


@pytest.mark.parametrize("command, case", CLI_FILE_CASES, ids=[f"{c}-{k}" for c, k in CLI_FILE_CASES])
def test_cli_bad_file_exits_2_with_one_line(tmp_path, command, case):
    make, fragments = BAD_FILES[case]
    path = make(tmp_path)
    proc = run_cli(command, str(path))
    assert_short_cli_error(proc, str(path), *fragments)


def test_cli_unknown_table_exits_2(tmp_path):
    path = write_scene(tmp_path, BASE_SCENE.read_text(encoding="utf-8") + "\n[weather]\nrain = 0.1\n")
    proc = run_cli("sweep", str(path))
    assert_short_cli_error(proc, str(path), "weather", "air, ball, launch")


# ----------------------------------------------------------------------------------------------
# --set overrides
# ----------------------------------------------------------------------------------------------
def test_set_override_changes_the_scene():
    base = ti_golf.load_scene(BASE_SCENE)
    scene = ti_golf.load_scene(BASE_SCENE, ["air.wind=[-5,0,0]"])
    assert base.air.wind == (0.0, 0.0, 0.0)
    assert scene.air.wind == (-5.0, 0.0, 0.0)
    assert scene.air.C_D == base.air.C_D and scene.launch == base.launch  # nothing else changed
    # several overrides, a bare word and a new table
    scene = ti_golf.load_scene(BASE_SCENE, ["air.C_D=0.25", "world.integrator=semi_implicit", "contact.e=0.8"])
    assert (scene.air.C_D, scene.world.integrator, scene.contact.e) == (0.25, "semi_implicit", 0.8)
    # the mapping form of the API
    assert ti_golf.load_scene(BASE_SCENE, {"ball.mass": 0.05}).ball.mass == 0.05


# (override, expected .key, fragments)
BAD_SETS = {
    "unknown_key": ("air.rhoo=1", "air.rhoo", ["is not a scene key", "air.rho"]),
    "unknown_table": ("weather.rain=1", "weather.rain", ["is not a scene key"]),
    "out_of_range": ("contact.e=2", "contact.e", ["[0, 1]", "2.0"]),
    "wrong_type": ("air.wind=[1,2]", "air.wind", ["list of 3 numbers"]),
    "non_finite": ("air.C_D=nan", "air.C_D", ["finite"]),
    "invalid_toml": ("air.wind=[1,2", "air.wind", ["not valid TOML"]),
    "no_equals": ("air.C_D", "air.C_D", ["KEY=VALUE"]),
}


@pytest.mark.parametrize("case", list(BAD_SETS), ids=list(BAD_SETS))
def test_bad_set_names_set_and_key(case):
    override, want_key, fragments = BAD_SETS[case]
    with pytest.raises(ConfigError) as info:
        ti_golf.load_scene(BASE_SCENE, [override])
    assert info.value.source == "overrides"
    assert info.value.key == want_key
    msg = str(info.value)
    assert msg.startswith("overrides: ") and f"'{want_key}'" in msg
    for frag in fragments:
        assert frag in msg, (frag, msg)


@pytest.mark.parametrize("case", ["unknown_key", "out_of_range"])
def test_cli_bad_set_exits_2(case):
    override, want_key, fragments = BAD_SETS[case]
    proc = run_cli("run", "lab_turbulent", "--steps", "1", "--set", override)  # (a run reads every table of it)
    assert_short_cli_error(proc, "--set", want_key, *fragments)


def test_set_changes_a_key_of_one_of_the_scene_s_array_tables(tmp_path):
    # --set said 'blocks[0].count' is not a scene key, where the docs say it changes any scene key
    # and errors name the keys of [[blocks]] that way
    text = (
        "[[balls]]\nposition = [0, 1, 0]\n[[blocks]]\ncount = [2, 1, 1]\norigin = [1, 0.5, 0]\n"
        '[[blocks]]\nkind = "random"\nnumber = 10\nbox_min = [3, 0, 0]\nbox_max = [4, 1, 1]\n'
    )
    path = write_scene(tmp_path, "[world]\nground = true\n" + text)
    scene = ti_golf.load_scene(path, ["blocks[0].count=[3,2,1]", "blocks[1].number=20", "balls[0].position=[0,2,0]"])
    assert scene.blocks[0].count == (3, 2, 1) and scene.blocks[1].number == 20 and scene.balls[0].position[1] == 2
    assert ti_golf.Simulation(scene).n == 1 + 6 + 20
    assert ti_golf.load_scene(path).blocks[0].count == (2, 1, 1)  # (the file's own, untouched)
    assert ti_golf.load_scene(path, ["blocks[0].count="]).blocks[0].count == (1, 1, 1)  # (cleared: the default)
    for override, key, fragment in (
        ("blocks[2].number=5", "blocks[2].number", "names table 2 of [[blocks]], and the scene has 2"),
        ("blocks[0].numbr=5", "blocks[0].numbr", "is unknown (did you mean 'number'?)"),
        ("blocks[0].count=[0,1,1]", "blocks[0].count", "must be 3 whole numbers >= 1"),
        ("blocks=[]", "blocks", "--set changes one key of one of them, blocks[INDEX].KEY"),
        ("planes[0].point=[0,0,0]", "planes[0].point", "the scene has 0"),
        ("balls[0].radius=-1", "balls[0].radius", "must be"),
    ):
        with pytest.raises(ConfigError) as info:
            ti_golf.load_scene(path, [override])
        assert (info.value.source, info.value.key) == ("overrides", key) and fragment in str(info.value), str(
            info.value
        )
    with pytest.raises(ConfigError) as info:  # (checked as the balls are made: still named as --set's)
        ti_golf.Simulation(ti_golf.load_scene(path, ["blocks[0].spacing=0.01"]))
    assert (info.value.source, info.value.key) == ("overrides", "blocks[0].spacing"), str(info.value)
    # a lattice made random by --set: the file's lattice keys are the ones left unread, and go
    random = ti_golf.load_scene(path, ['blocks[0].kind="random"', "blocks[0].number=4", "blocks[0].box_max=[2,1,1]"])
    assert random.blocks[0].kind == "random" and random.blocks[0].number == 4


def test_a_simulation_changes_an_array_table_s_key_at_t0_only():
    sim = ti_golf.Simulation(ti_golf.load_scene("newtons_cradle"))
    n = sim.n
    sim.set("blocks[0].count", [3, 1, 1])  # (at t0: set up again, as a new simulation would be)
    assert sim.n == n - 2
    sim.step(1)
    with pytest.raises(ConfigError, match="sets up the balls or the ground at t0"):
        sim.set("blocks[0].count", [4, 1, 1])


def test_cli_set_wind_changes_the_result():
    """A 5 m/s headwind shortens the turbulent carry below the still-air maximum."""
    proc = run_cli("sweep", "lab_turbulent", "--angles", "36.6", "--set", "air.wind=[-5,0,0]")
    assert proc.returncode == 0, proc.stderr
    carry = float(re.search(r"carry ([\d.]+) m", proc.stdout).group(1))
    # report Appendix A: turbulent max 212.243 m at 36.6° in still air
    assert 100.0 < carry < 212.243 - 5.0, proc.stdout


# ----------------------------------------------------------------------------------------------
# --angles (and the other range options)
# ----------------------------------------------------------------------------------------------
BAD_RANGES = {
    "backwards": ("36:30:0.1", "STOP must be >= START"),
    "not_numbers": ("a:b:c", "START:STOP:STEP"),
    "step_zero": ("36:37:0", "STEP must be > 0"),
    "step_negative": ("36:37:-0.1", "STEP must be > 0"),
    "two_parts": ("36:37", "START:STOP:STEP"),
    "empty": ("", "at least one value"),
    "empty_item": ("30,,40", "has an empty item in '30,,40'"),  # (40 and 30 were swept, the gap dropped)
    "trailing_comma": ("30,", "has an empty item"),
    "nan": ("36,nan", "finite"),
    "too_many": ("0:90:0.000001", "at most 10,000,000"),
}


@pytest.mark.parametrize("case", list(BAD_RANGES), ids=list(BAD_RANGES))
def test_parse_range_rejects(case):
    text, fragment = BAD_RANGES[case]
    with pytest.raises(ConfigError) as info:
        parse_range(text, "--angles", None)
    assert info.value.source == "--angles"
    assert fragment in str(info.value) and str(info.value).startswith("--angles")


def test_parse_range_accepts_documented_forms():
    assert parse_range("36:37:0.5", "--angles", None) == (36.0, 36.5, 37.0)  # STOP included
    assert parse_range("36:37.4:0.02", "--angles", None)[-1] == 37.4
    assert len(parse_range("36:37.4:0.02", "--angles", None)) == 71
    assert parse_range("60,80", "--speeds", None) == (60.0, 80.0)
    assert parse_range([1, 2.5], "sweep.angles", "sweep.angles") == (1.0, 2.5)


@pytest.mark.parametrize(
    "option, value, fragment",
    [
        ("--angles", "36:30:0.1", "STOP must be >= START"),
        ("--angles", "a:b:c", "START:STOP:STEP"),
        ("--angles", "36:37:0", "STEP must be > 0"),
        ("--angles", "100", "[-90, 90]"),
        ("--speeds", "-10,5", "--speeds"),
    ],
)
def test_cli_bad_range_exits_2(option, value, fragment):
    proc = run_cli("sweep", "lab_turbulent", f"{option}={value}")
    assert_short_cli_error(proc, option, fragment)
    assert proc.stdout.strip() == ""


@pytest.mark.parametrize(
    "text, key, fragment",
    [
        ('[[blocks]]\nkind = "random"\nnumber = 3\nseed = -1\n', "blocks[0].seed", "must be >= 0 (got -1)"),
        ('[[blocks]]\nkind = "random"\nnumber = 0\n', "blocks[0].number", "must be in [1, 50000000] (got 0)"),
        ('[[blocks]]\nkind = "random"\n', "blocks[0].number", "is required for a random block"),
        ("[sweep]\nangles = [100, 200]\n", "sweep.angles", "must each be in [-90, 90] deg (got 100.0)"),
        ("[hole]\nposition = [1e9, 0]\n", "hole.position", "must be in [-1000000, 1000000] m on both axes"),
        (  # (the launched ball was out of bounds before its first step, and the run said nothing)
            "[launch]\nspeed = 10.0\n[terrain]\norigin = [10, 0, 10]\n",
            "terrain.origin",
            "leaves x = z = 0, where the [launch] ball rests, off the terrain (x in [10, 110], z in [10, 110] m)",
        ),
        ("[[blocks]]\ncount = [2, 1, 1]\nseed = 5\n", "blocks[0].seed", "has no effect: the lattice draws nothing"),
        (
            '[terrain]\n[[surfaces]]\nname = "a"\n[[surfaces]]\nname = "b"\n',
            "terrain.surface_levels",
            "is required with 2 [[surfaces]]",
        ),
        (
            '[[blocks]]\nkind = "random"\nnumber = 10\nbox_min = [-1e200, 0, -1e200]\nbox_max = [1e200, 1, 1e200]\n',
            "blocks[0].box_min",
            "must lie within ±1,000,000 m on every axis",
        ),
        ('[[blocks]]\nkind = "lattice"\ncount = [2, 2, 2]\nspacing = 1e308\n', "blocks[0].spacing", "spans more than"),
        ("[terrain]\nseed = -1\n", "terrain.seed", "must be >= 0 (got -1)"),
        (
            '[[blocks]]\nkind = "random"\nnumber = 3\nbackspin = [1, 2]\n',
            "blocks[0].backspin",
            "is read only for shots (a block with speed and angle_deg)",
        ),
        ("[terrain]\nslope = [1e308, 0]\n", "terrain.slope", "must be in [-100, 100] on both axes"),
        ("[terrain]\namplitude = 1e308\n", "terrain.amplitude", "must be in [0, 10000] m"),
        (  # (two balls at one point never parted: their contact has no direction)
            "[[balls]]\nposition = [0, 0.5, 0]\n[[blocks]]\ncount = [2, 2, 2]\norigin = [0, 0.5, 0]\n",
            "blocks[0]",
            "puts ball 1 at the point of ball 0 (balls[0].position), [0.0, 0.5, 0.0] m",
        ),
        (  # (a scene's ball 5 m under the ground was shoved up by it, silently; the API refused it)
            "[[balls]]\nposition = [0, 1, 0]\n[[balls]]\nposition = [0, -5, 0]\n",
            "balls[1].position",
            "puts ball 1 5 m inside the ground, [0.0, -5.0, 0.0] m, the whole ball in the solid (1 ball(s) are)",
        ),
        (
            "[[planes]]\npoint = [1, 0, 0]\nnormal = [-1, 0, 0]\n[[blocks]]\ncount = [4, 1, 1]\norigin = [0, 0.5, 0]\n"
            "spacing = 0.5\n",
            "blocks[0]",
            "puts ball 3 0.5 m inside planes[0], [1.5, 0.5, 0.0] m",
        ),
        (  # (a ball under the terrain came up through it, silently)
            "[terrain]\norigin = [0, 5, 0]\nsize = [10, 10]\namplitude = 0\n[[balls]]\nposition = [5, 4, 5]\n",
            "balls[0].position",
            "puts ball 0 1 m inside the terrain, [5.0, 4.0, 5.0] m",
        ),
        (  # (a jitter beyond the gap was cut to it, silently)
            "[[blocks]]\ncount = [2, 1, 1]\norigin = [0, 0.5, 0]\njitter = 10\n",
            "blocks[0].jitter",
            "must be at most half the free gap between the lattice's balls, (spacing − 2R)/2 = 0.0002 m (got 10)",
        ),
        (  # (the cup was drawn off the course, and run measured distances to it; play refused it)
            "[terrain]\nsize = [20, 20]\namplitude = 0\n[hole]\nposition = [500, 0]\n[[balls]]\nposition = [5, 1, 5]\n",
            "hole.position",
            "must lie on the terrain (x in [0, 20] m, z in [0, 20] m; got [500, 0])",
        ),
    ],
)
def test_a_block_or_terrain_value_that_a_run_cannot_use_is_refused_before_it_starts(tmp_path, text, key, fragment):
    # each of these ended in a traceback (a negative seed in numpy, a box whose volume overflowed,
    # a terrain of NaN heights, a random block of no balls), hung (a box of 1e200 m: its spacing
    # overflowed to inf), or was quietly without effect (a backspin for balls that are not shots, a
    # lattice's seed that draws nothing, surface types beyond the first without the levels that
    # divide them)
    path = write_scene(tmp_path, "[world]\nground = true\n" + text)
    with pytest.raises(ConfigError) as info:
        ti_golf.Simulation(ti_golf.load_scene(path))
    assert info.value.key == key and fragment in str(info.value), str(info.value)


@pytest.mark.parametrize("planes", ["", "[[planes]]\npoint = [0, 0, 0]\nnormal = [1, 0, 0]\n"])
def test_a_hole_with_nothing_to_sit_on_is_refused(tmp_path, planes):
    # no terrain, no ground and no upward-facing plane: the cup and its flag were drawn in the air
    text = f"[world]\nground = false\n[hole]\nposition = [1, 0]\n[[balls]]\nposition = [2, 1, 0]\n{planes}"
    with pytest.raises(ConfigError) as info:
        ti_golf.load_scene(write_scene(tmp_path, text))
    assert info.value.key == "hole.position" and "has nothing to sit on" in str(info.value), str(info.value)
    upward = text.replace("normal = [1, 0, 0]", "normal = [0.5, 1, 0]") if planes else text.replace("false", "true")
    assert ti_golf.load_scene(write_scene(tmp_path, upward)).hole is not None


def test_the_launch_ball_rests_on_a_sloping_terrain(tmp_path):
    # its centre was R above the surface point under it, not R / cos θ: on a 45° slope it started
    # 5.9 mm into the surface and the position projection shoved it out along the normal in its
    # first step (at the grid's corner, off the grid: out of bounds). Now it starts touching the
    # tangent plane, and its first step moves it by what gravity gives in a step, g·h², at most
    text = "[terrain]\nsize = [10, 10]\namplitude = 0\nslope = [-1, 0]\n[launch]\nspeed = 0\nangle_deg = 0\n[air]\nrho = 0\n"
    scene = ti_golf.load_scene(write_scene(tmp_path, text))
    sim = ti_golf.Simulation(scene)
    x0 = sim.x[0].copy()
    assert x0[1] == pytest.approx(scene.ball.radius * np.sqrt(2.0), rel=1e-12)
    sim.step(1)
    assert sim.status[0] != ti_golf.OUT_OF_BOUNDS
    assert np.linalg.norm(sim.x[0] - x0) <= 9.81 * scene.world.dt**2, sim.x[0] - x0


def test_one_ball_of_a_lattice_spans_nothing_whatever_its_spacing(tmp_path):
    # the span was spacing × count: one ball with a wide spacing (which bounds its jitter) was refused
    path = write_scene(tmp_path, '[[blocks]]\nkind = "lattice"\ncount = [1, 1, 1]\nspacing = 2e6\njitter = 0.5\n')
    assert len(ti_golf.load_scene(path).blocks) == 1


@pytest.mark.parametrize("normal", ["[0, 1e-170, 0]", "[0, 1e300, 0]", "[0, 2, 0]"])
def test_a_plane_normal_too_small_or_too_large_to_square_is_still_its_direction(tmp_path, normal):
    # |n|² of 1e-170 underflows to 0 (a ZeroDivisionError) and of 1e300 overflows (a zero normal)
    path = write_scene(tmp_path, f"[world]\nground = false\n[[planes]]\npoint = [0, 0, 0]\nnormal = {normal}\n")
    assert ti_golf.load_scene(path).planes[0].normal == (0.0, 1.0, 0.0)


def test_a_heights_file_that_is_empty_too_high_or_too_large_is_refused(tmp_path):
    # a header that claims 200,000 x 200,000 heights had numpy allocate 298 GiB (a MemoryError
    # traceback); the header is now checked against the file, and the points against the limit
    # (the int64 height of least value passed: its absolute value overflows back to itself; a text
    # file named .npy was said to hold pickled data, to be loaded unsafely)
    names = ("empty", "high", "lying", "large", "least", "text")
    empty, high, lying, large, least, text_file = (tmp_path / f"{name}.npy" for name in names)
    empty.write_bytes(b"")
    np.save(high, np.full((4, 4), 1e308))
    np.save(least, np.array([[0, 0, 0], [0, np.iinfo(np.int64).min, 0], [0, 0, 0]], dtype=np.int64))
    text_file.write_text("1 2 3\n4 5 6\n")
    with open(lying, "wb") as fh:
        np.lib.format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False, "shape": (200_000, 200_000)})
        fh.write(b"\0" * 800)
    with open(large, "wb") as fh:  # (as long as its header says, but sparse: nothing written)
        np.lib.format.write_array_header_1_0(fh, {"descr": "<f4", "fortran_order": False, "shape": (8, 6_250_001)})
        fh.truncate(fh.tell() + 8 * 6_250_001 * 4)
    for path, fragment in (
        (empty, "cannot be read as a .npy array ("),
        (high, "beyond ±10000 m"),
        (lying, "cannot be read as a .npy array (mmap length is greater than file size)"),
        (large, "holds 50,000,008 points; at most 50,000,000"),
        (least, "beyond ±10000 m (got 9.22337e+18)"),
        (text_file, "is not a .npy file (one begins with the bytes \\x93NUMPY)"),
    ):
        text = f'[terrain]\nkind = "file"\nfile = "{path.name}"\nsize = [10, 10]\n'
        with pytest.raises(ConfigError) as info:
            ti_golf.load_scene(write_scene(tmp_path, text))
        assert info.value.key == "terrain.file" and fragment in str(info.value), str(info.value)


def test_a_scene_saved_with_a_byte_order_mark_loads_as_without_one(tmp_path):
    # Windows editors save UTF-8 with a BOM, which TOML's parser called an "invalid statement"
    text = 'description = "with a BOM"\n[launch]\nspeed = 12.5\n'
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + text.encode())
    scene = ti_golf.load_scene(path)
    assert scene.description == "with a BOM" and scene.launch.speed == 12.5


def test_a_scene_or_heights_file_that_is_a_fifo_is_refused_at_once(tmp_path):
    # reading a FIFO waits for a writer: the run waited for ever
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    with pytest.raises(ConfigError, match="is not a regular file"):
        ti_golf.load_scene(fifo)
    os.mkfifo(tmp_path / "pipe.npy")
    text = '[terrain]\nkind = "file"\nfile = "pipe.npy"\nsize = [10, 10]\n'
    with pytest.raises(ConfigError, match="is not a regular file"):
        ti_golf.load_scene(write_scene(tmp_path, text))


def test_a_random_blocks_centres_lie_in_its_box_whatever_its_spacing(tmp_path):
    # few balls in a box: the sites' spacing is wide, and the jitter within a site (half the
    # spacing less a diameter) took centres up to 7 cm out of the box, through the wall beside it
    # (the pit scaled to 16 balls; 316 of avalanche's 3,000 centres lay outside its box)
    from ti_golf.scene.balls import build_balls

    path = write_scene(
        tmp_path,
        '[world]\nground = true\n[[planes]]\npoint = [0, 0, 0]\nnormal = [1, 0, 0]\n[[blocks]]\nkind = "random"\n'
        "number = 16\nbox_min = [0.004, 0.3, 0.004]\nbox_max = [0.146, 4.3, 0.146]\nseed = 1\n",
    )
    scene = ti_golf.load_scene(path)
    block, x = scene.blocks[0], build_balls(scene).x
    assert np.all(x >= np.asarray(block.box_min)) and np.all(x <= np.asarray(block.box_max)), x
    d = np.linalg.norm(x[:, None] - x[None], axis=-1) + np.eye(len(x))
    assert d.min() >= 2 * scene.ball.radius  # (no two balls overlap)
