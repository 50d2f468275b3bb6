"""The scene's choices of code: which integrator, air model, wind profile, ground, contact solver,
friction model and turf impacts the kernels run.

Each choice selects code rather than a number, so the kernels take them as one compile-time
argument (``ti.template()``), :class:`Kinds`, and test them with ``ti.static``: a kernel is built
for the kinds it is given, and Taichi's front end, which runs over every kernel in every new
process even when the compiled kernel comes from the cache, never reads the branches a scene does
not use. A change of kind (``Simulation.set``) builds the kernels for the new kinds once; the
numbers of the air, the contact and the terrain stay kernel arguments.
"""

from __future__ import annotations

from typing import Any, NamedTuple

from ti_golf.physics.aero import AIR_MODEL_CODES, WIND_PROFILE_CODES
from ti_golf.physics.integrate import INTEGRATOR_CODES
from ti_golf.scene.schema import FRICTION_MODELS


class Kinds(NamedTuple):
    """The compile-time choices of a scene's kernels (a ``ti.template()`` argument: a tuple of ints
    and bools, so that equal kinds share a compiled kernel)."""

    integrator: int
    """:data:`~ti_golf.physics.integrate.INTEGRATOR_CODES` of ``world.integrator``."""
    air_model: int
    """:data:`~ti_golf.physics.aero.AIR_MODEL_CODES` of ``air.model``."""
    wind_profile: int
    """:data:`~ti_golf.physics.aero.WIND_PROFILE_CODES` of ``air.wind_profile``."""
    terrain: bool
    """Whether the scene has a height field (``[terrain]``)."""
    gauss_seidel: bool
    """Whether ``contact.solver`` is ``"gauss_seidel"`` (its sweeps, projection and sleeping, else
    the Jacobi sweeps')."""
    friction: int
    """:data:`~ti_golf.scene.schema.FRICTION_MODELS` index of ``contact.friction_model`` (the
    report's friction at the centres, :data:`~ti_golf.physics.contact.CENTRE_FRICTION`, or at the
    contact point with spin)."""
    turf: bool
    """Whether some surface may take impacts as on turf (``contact.turf``, or a ``[[surfaces]]``
    entry's ``turf``): the turf impact's code is built, and each contact's ``turf`` value says
    whether it applies."""


def kinds_of(scene: Any) -> Kinds:
    """The :class:`Kinds` of a validated scene (:class:`ti_golf.scene.schema.Scene`); a choice
    without code (a scene built by hand, not read) raises ValueError."""
    for key, value, codes in (
        ("world.integrator", scene.world.integrator, INTEGRATOR_CODES),
        ("air.model", scene.air.model, AIR_MODEL_CODES),
        ("air.wind_profile", scene.air.wind_profile, WIND_PROFILE_CODES),
    ):
        if value not in codes:
            raise ValueError(f"{key} must be one of {', '.join(codes)} (got {value!r})")
    return Kinds(
        integrator=INTEGRATOR_CODES[scene.world.integrator],
        air_model=AIR_MODEL_CODES[scene.air.model],
        wind_profile=WIND_PROFILE_CODES[scene.air.wind_profile],
        terrain=scene.terrain is not None,
        gauss_seidel=scene.contact.solver == "gauss_seidel",
        friction=FRICTION_MODELS.index(scene.contact.friction_model),
        turf=bool(scene.contact.turf) or any(bool(sf.turf) for sf in scene.surfaces),
    )
