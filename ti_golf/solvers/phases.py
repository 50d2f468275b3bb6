"""The phases of a contact sweep, as one namespace of int constants that the kernels compare
with (``phase == Phase.BOUNCE``; Taichi reads them as compile-time integers)."""


class Phase:
    """What a sweep over the contacts does (:func:`.sequential.pair_step`,
    :func:`.surfaces.surface_impulses`, :mod:`.colour`). A Gauss–Seidel step runs ``FIRST``,
    ``SOLVE`` …, ``SHOCK`` (with two sweeps or more), then ``BOUNCE`` (``colour.step_phases``),
    then ``PROJECT`` passes."""

    JACOBI = -1
    """A Jacobi sweep: every impulse from the velocities of the sweep before (:mod:`.collide`)."""
    FIRST = 0
    """The first Gauss–Seidel sweep, which also applies the friction carried from the last step."""
    SOLVE = 1
    """A later Gauss–Seidel sweep: sequential impulses toward closing each gap within the step."""
    PROJECT = 2
    """The position projection of the overlaps left after the step (B.18, ``colour.project_ball``)."""
    SHOCK = 3
    """The last sweep, with shock propagation: the lower ball of each pair stands firm."""
    BOUNCE = 4
    """The restitution pass, once a step after the sweeps."""
