"""The contact solvers: the balls' collisions with one another, the planes and the terrain.

A shared base lists the neighbours and keeps the carried impulses (:mod:`.sort`, :mod:`.grid`,
:mod:`.apart`, :mod:`.links`, :mod:`.stale`, :mod:`.pairs`, :mod:`.surfaces` with
:mod:`.surface_reach`, and their driver,
:class:`.solver.CollisionSolver`, with :mod:`.storage_order`, :mod:`.surface_rows`, its steps
and rebuild schedule, :mod:`.stepping`, and the saved :mod:`.record`); one kernel steps the balls
(:mod:`.collide`; Gauss–Seidel's serial steps by blocks: :mod:`.block_steps`); each solver's sweeps and driver lie side by side: Jacobi's (:mod:`.jacobi`)
and Gauss–Seidel's (:mod:`.gauss_seidel`: one contact's update, :mod:`.sequential`, swept by grid
columns, :mod:`.colour`, or by contact colours, :mod:`.contact_colour` with the colouring of
:mod:`.edge_colouring`). :mod:`.phases` names the phases of a sweep, and the kernels' functions
take the step's parameters and arrays as one :class:`.step.Step`.

``CollisionSolver(model)`` makes the solver that the scene's ``contact.solver`` names.
"""

from ti_golf.solvers.gauss_seidel import GaussSeidelSolver
from ti_golf.solvers.jacobi import JacobiSolver
from ti_golf.solvers.solver import CollisionSolver

__all__ = ["CollisionSolver", "GaussSeidelSolver", "JacobiSolver"]
