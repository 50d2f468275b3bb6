"""The narrow pit's pours (tests/test_piles.py): run in the test process, or on their own as a
background run (tests/background.py), which writes what the test checks to a file.

    python tests/pile_pours.py VARIANT OUT.npz

runs the pour ``VARIANT`` (one of :data:`VARIANTS`) to t = 4 s and saves its pile figures, its
energy samples and the balls' total mass to ``OUT.npz`` (written whole or not at all).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

import ti_golf as tg
from ti_golf.bench.pit import pile_quality, pit_scene

NARROW_PIT = 2250
"""Balls of a pit as deep as the bundled one in a 0.3 m bin."""

LANDED = 1.5
"""Time [s] by which every ball of the pour has landed: the highest starts 4.3 m up at −1 m/s and
meets the pile's top (1.45 m) after 0.7 s."""

END = 4.0
"""Time [s] at which a pour is measured (the pit benchmark's)."""

SAMPLE = 0.05
"""Time [s] between two energy samples from ``LANDED`` on."""


def kinetic(sim) -> float:
    """Translational and rotational kinetic energy [J] (solid spheres)."""
    m, r = np.asarray(sim.model.mass_np), np.asarray(sim.model.radius_np)
    return float(0.5 * np.sum(m * (sim.v**2).sum(axis=1)) + 0.5 * np.sum(0.4 * m * r**2 * (sim.w**2).sum(axis=1)))


def potential(sim) -> float:
    """Gravitational potential energy [J] above y = 0."""
    m = np.broadcast_to(np.asarray(sim.model.mass_np), sim.n)
    return float(np.sum(m * -sim.scene.world.gravity[1] * sim.x[:, 1]))


def total_mass(sim) -> float:
    """The balls' total mass [kg]."""
    return float(np.broadcast_to(np.asarray(sim.model.mass_np), sim.n).sum())


def pour(scene, side: float, snapshot: float | None = None, landed=None, sample: float = SAMPLE):
    """Run a pour to ``END`` and return it, its pile figures, its kinetic and potential energy [J]
    every ``sample`` s from ``LANDED`` on, shape (samples, 2), and (with ``snapshot``, a time
    before ``LANDED``) the balls' (x, v, w) at that time. ``landed(sim)``, when given, is called
    once every ball has landed, before the first sample."""
    sim = tg.Simulation(scene)
    taken = None
    if snapshot is not None:
        sim.run(t=snapshot)
        taken = (sim.x, sim.v, sim.w)
    sim.run(t=LANDED - sim.t)
    if landed is not None:
        landed(sim)
    energy = [(kinetic(sim), potential(sim))]
    while sim.t < END - 1e-9:
        sim.run(t=sample)
        energy.append((kinetic(sim), potential(sim)))
    return sim, pile_quality(sim, side), np.array(energy), taken


def _no_projection(sim) -> None:
    sim.set("contact.k_p", 0.0)


STEP = 0.001
"""The pit's time step [s] (``world.dt`` of the bundled ``ball_pit``)."""

VARIANTS = {
    "sleeping_off": (("world.v_rest=0.0",), None, SAMPLE),
    "lively": (("contact.e=0.8",), None, SAMPLE),
    "no_projection_once_landed": ((), _no_projection, STEP),
    "contacts": (("contact.layout=contacts",), None, SAMPLE),
    "contacts_lively": (("contact.layout=contacts", "contact.e=0.8"), None, SAMPLE),
}
"""The pours run on their own: the keys of the bundled pit they change (``--set`` syntax), what
they do once every ball has landed, and how often [s] they sample the energy."""


def run_variant(variant: str) -> dict:
    """Pour the narrow pit as ``variant`` says; returns its figures as arrays."""
    overrides, landed, sample = VARIANTS[variant]
    scene, side = pit_scene(NARROW_PIT, overrides)
    assert scene.world.dt == STEP
    sim, quality, energy, _ = pour(scene, side, landed=landed, sample=sample)
    return {"quality": np.array(json.dumps(quality)), "energy": energy, "total_mass": np.array(total_mass(sim))}


def load_variant(path: Path) -> tuple[dict, np.ndarray, float]:
    """(pile figures, energy samples, total mass) that :func:`main` saved to ``path``."""
    with np.load(path) as saved:
        return json.loads(str(saved["quality"])), saved["energy"], float(saved["total_mass"])


def main(argv: list[str]) -> int:
    variant, out = argv
    tg.init(None, "f64")  # the backend of TI_GOLF_ARCH (the test session's, see conftest)
    figures = run_variant(variant)
    part = Path(out + ".part.npz")
    np.savez(part, **figures)
    part.replace(out)
    return 0


if __name__ == "__main__":
    from ti_golf import runtime

    runtime.exit_process(main(sys.argv[1:]))
