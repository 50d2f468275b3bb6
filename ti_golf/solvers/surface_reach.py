"""Which planes and terrain a ball may reach before the neighbour lists are rebuilt, and its row
of surface impulses (see :mod:`ti_golf.solvers.surfaces`): what the lists' build
(:func:`.surfaces.list_surfaces`) and the test of stale lists (:mod:`.stale`) both ask."""

import taichi as ti

from ti_golf.physics.terrain import same_cell, terrain_clearance
from ti_golf.physics.types import of_ball


@ti.func
def surface_row(start: ti.template(), i):
    """Ball i's row of surface impulses (see :func:`list_surfaces`), or −1 when it keeps none."""
    row = start[i]
    if start[i + 1] == row:
        row = -1
    return row


@ti.func
def near_a_surface(i, xi, reach, with_terrain: ti.template(), terrain: ti.template(), model: ti.template()):
    """Whether ball i at ``xi`` [m] may touch a plane or the terrain before the neighbour lists are
    rebuilt, when it moves no farther than ``reach`` [m] until then (see :func:`list_surfaces`). A
    plane is within reach when its surface gap is below it; the terrain when its clearance
    (:func:`ti_golf.physics.terrain.terrain_clearance`, at least the gap to any patch of the cell under the ball)
    is below twice the reach, since a patch taken under a moved point is nearer by up to twice the
    move, or when a move of the reach can take the ball over another cell (``with_terrain``: the
    scene has one, so that a kernel without holds no terrain code)."""
    r = of_ball(model.radius, i)
    near = False
    for p in range(model.plane_n.shape[0]):
        if (xi - model.plane_p[p]).dot(model.plane_n[p]) - r < reach:
            near = True
            break  # (an early exit: also keeps LLVM from vectorising a loop of a few planes)
    if ti.static(with_terrain):  # (a static `if` of its own: Taichi builds both sides of an `and`)
        if not near:
            if terrain_clearance(model.heights, terrain, xi, xi, r) < 2.0 * reach:
                near = True
            for corner in ti.static(range(4)):
                dx = ti.Vector([reach if corner % 2 else -reach, 0.0, reach if corner // 2 else -reach])
                if not same_cell(model.heights, terrain, xi, xi + dx):
                    near = True
    return near
