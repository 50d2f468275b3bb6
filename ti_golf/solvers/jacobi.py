"""The Jacobi solver (``contact.solver = "jacobi"``, report Appendix B): every pair's impulse in a
sweep from the velocities of the sweep before. Its sweeps are loops of the step kernel
(:func:`.collide.collision_step`), launched here a few sweeps at a time."""

from __future__ import annotations

from ti_golf.solvers import collide
from ti_golf.solvers.solver import CollisionSolver

UNROLL_MAX_SWEEPS = 4
"""Most Jacobi sweeps in one kernel launch of a parallel step: a step of more
(``contact.iterations``) is split into launches of at most this many sweeps each
(:func:`sweep_launches`): compiling a kernel grows faster than the sweeps unrolled in it, while
each launch costs a fraction of a millisecond (see the docs' performance page, "Design
measurements")."""


def sweep_launches(iterations: int) -> list[tuple[bool, int, bool]]:
    """The launches of one parallel step of ``iterations`` Jacobi sweeps, as the ``(warm, sweeps,
    last)`` flags of :func:`.collide.launch`: the sweeps in order, at most ``UNROLL_MAX_SWEEPS``
    per launch; the first launch also takes the free flight and the warm start, and the one with
    the last sweep finishes the step. Any split gives the same step, bit for bit."""
    launches, first = [], 1
    while first <= iterations:
        end = min(first + UNROLL_MAX_SWEEPS - 1, iterations)
        last = end == iterations
        launches.append((first == 1, end - first + 1 - int(last), last))
        first = end + 1
    return launches


class JacobiSolver(CollisionSolver, kind="jacobi"):
    """A :class:`.solver.CollisionSolver` whose sweeps are Jacobi's (:func:`sweep_launches`)."""

    gauss_seidel = False

    def _sweep(self, iterations: int, arguments: tuple) -> tuple[bool, bool | None]:
        rebuild = 0
        for warm, sweeps, last in sweep_launches(iterations):
            rebuild = collide.launch(arguments, serial=collide.PARALLEL, warm=warm, sweeps=sweeps, last=last)
        return bool(rebuild), None
