"""``ti-golf figure``: the report's figures one command each, and plots in PNG, SVG, PDF and EPS.

References: the report's own statements about its figures: the example round of Figure 3.1-5 ends
in the hole after its five strokes; in Figure 3.2-7 the ball stops on an inclined part of the
terrain (a slope no steeper than μ, the report's friction), where in Figure 3.2-6, without
friction, it is still moving; in Figure 3.2-3 the spin decays through every flight.
"""

from __future__ import annotations

import contextlib
import io
import math
import re

import numpy as np
import pytest
from conftest import ROOT

import ti_golf as tg
from ti_golf.cli import main
from ti_golf.cli.figure import FIGURES


def run_main(*args: str) -> tuple[int, str, str]:
    """``ti_golf.cli.main(args)`` in this process: (exit code, standard output, standard error)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(list(args))
        except SystemExit as exc:
            code = int(exc.code or 0)
    return code, out.getvalue(), err.getvalue()


MAGIC = {"png": b"\x89PNG\r\n\x1a\n", "svg": b"<?xml", "pdf": b"%PDF-", "eps": b"%!PS-Adobe-3.0 EPSF"}
"""The first bytes of each format's files."""


@pytest.mark.parametrize("fmt", list(MAGIC))
def test_a_plot_is_written_in_the_format_of_its_extension(tmp_path, fmt):
    path = tmp_path / f"carry.{fmt.upper() if fmt == 'pdf' else fmt}"  # (the case of the extension does not matter)
    code, out, err = run_main("sweep", "lab_vacuum", "--angles", "44:46:1", "--trajectories", "3", "--plot", str(path))
    assert code == 0, err
    assert path.read_bytes().startswith(MAGIC[fmt])
    assert f".{path.name}.".encode() not in path.read_bytes()[:2000]  # (EPS's title named the temporary file)
    assert "transparency" not in err  # (EPS has none: said in the help, not at every plot)
    assert f"wrote {path}" in out


@pytest.mark.parametrize(
    "command",
    [
        ["sweep", "lab_vacuum"],
        ["run", "lab_vacuum"],
        ["table"],
        ["play", "golf_hole", "--shots", str(ROOT / "scenes" / "golf_hole_round.txt")],
        ["figure", "3.2-3"],
        ["dispersion", "tour_shot", "--n", "10"],
        ["tour"],
    ],
    ids=lambda c: c[0],
)
def test_an_unknown_plot_extension_is_one_line_naming_the_option_and_the_formats(tmp_path, command):
    path = tmp_path / "plot.jpg"
    code, out, err = run_main(*command, "--plot", str(path))
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("ti-golf: error: --plot: ") and "'.jpg'" in lines[0]
    assert ".png, .svg, .pdf, .eps" in lines[0]
    assert not path.exists() and out == ""  # refused before anything ran


def test_every_plot_option_names_the_formats():
    for command in ("sweep", "run", "table", "play", "figure", "dispersion", "tour"):
        code, out, _ = run_main(command, "--help")
        assert code == 0
        assert re.search(r"PNG,\s+SVG,\s+PDF\s+or\s+EPS", out), command


def test_the_figure_help_lists_every_figure_and_the_docs_show_each():
    code, out, _ = run_main("figure", "--help")
    assert code == 0
    docs = (ROOT / "docs" / "lab.md").read_text(encoding="utf-8")
    for number in FIGURES:
        assert re.search(rf"^\s+{re.escape(number)}\s+\S", out, re.M), number
        assert f"ti-golf figure {number}" in docs, number
    code, _, err = run_main("figure", "3.9-9")
    assert code == 2 and "no figure '3.9-9' (choose from 3.1-1," in err
    code, _, err = run_main("figure", "3.2-2")  # a picture of balls: the command that draws it
    assert code == 2 and "ti-golf render terrain_3d --t 3 --out figure_3_2_2.png" in err
    assert "ti-golf render terrain_3d --t 3 --out figure_3_2_2.png" in docs


def test_figure_3_1_5_holes_the_reports_five_strokes(tmp_path):
    path = tmp_path / "round.png"
    code, out, err = run_main("figure", "3.1-5", "--plot", str(path))
    assert code == 0, err
    assert out.count("Stroke ") == 5
    assert "Holed in 5 strokes." in out
    assert path.read_bytes().startswith(MAGIC["png"])


def test_figures_3_2_6_and_3_2_7_without_and_with_friction(tmp_path):
    code, out, err = run_main("figure", "3.2-6", "--plot", str(tmp_path / "free.png"))
    assert code == 0, err
    assert "mu = 0 (report friction)" in out and "still moves" in out
    code, out, err = run_main("figure", "3.2-7", "--plot", str(tmp_path / "held.svg"))
    assert code == 0, err
    assert "mu = 0.4 (report friction)" in out and "rests" in out
    slope = float(re.search(r"rests on a slope of ([\d.]+) deg", out).group(1))
    assert 3.0 < slope <= math.degrees(math.atan(0.4))


def test_figure_3_2_3_spin_decays_through_every_flight(tmp_path):
    code, out, err = run_main("figure", "3.2-3", "--plot", str(tmp_path / "nine_iron.pdf"))
    assert code == 0, err
    rows = re.findall(r"^\s*([\d.]+)°\s+([\d.]+) m\s+([\d.]+) m\s+([\d.]+) s\s+([\d.]+) rad/s", out, re.M)
    assert [float(r[0]) for r in rows] == [25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0]  # the scene's [sweep] angles
    spin0 = 10800 * 2 * math.pi / 60
    for _, carry, _, flight, spin in rows:
        assert float(carry) > 50.0 and float(flight) > 3.0
        assert 0.0 < float(spin) < 0.2 * spin0  # C_ω = 1 takes most of the spin in flight
    # the 40° row as one ball flown alone without a ground, sampled at every 1 ms step: its spin
    # where it comes down through its launch height (its landing) and its apex above the launch.
    # The table gave the spin of its last 10 ms sample before the landing (0.1 rad/s more) and the
    # apex's height above the ground (R higher)
    one = tg.Simulation.from_scene("lab_spin_decay", ["launch.angle_deg=40", "world.ground=false"])
    y0 = one.x[0, 1]
    rec = one.run(t=6.0, record_every=1).arrays()
    y, spin_now = rec["traj_x"][:, 0, 1], np.linalg.norm(rec["traj_w"][:, 0], axis=1)
    k = int(np.nonzero((y[1:] <= y0) & (y[:-1] > y0))[0][-1])  # the step that crosses the launch height
    f = (y[k] - y0) / (y[k] - y[k + 1])
    _, _, apex, _, spin = rows[3]
    assert float(spin) == pytest.approx(spin_now[k] + f * (spin_now[k + 1] - spin_now[k]), abs=0.051)
    assert float(apex) == pytest.approx(y.max() - y0, abs=0.0051)
