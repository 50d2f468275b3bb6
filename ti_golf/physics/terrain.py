"""Ball–terrain contact on a height field: the local tangent plane under a ball.

The terrain is a grid ``heights`` (nx, nz) [m] above ``terrain.origin`` with spacing
(``terrain.dx``, ``terrain.dz``); between grid points the surface is the bilinear patch of its cell
(see :mod:`ti_golf.scene.terrain`, the numpy version, which this matches operation for operation).
A ball touches the terrain through the plane (p, n̂) of the patch under it: p = (x, h(x, z), z)
and n̂ = (−∂h/∂x, 1, −∂h/∂z)/|…|, handed to the plane routines of :mod:`.contact` each step
(restitution, friction and spin, rolling resistance, time-of-impact split, position projection).
For a flat terrain that plane is exactly the ground plane, so the results agree to round-off.
"""

import taichi as ti

from ti_golf.physics.types import (
    TerrainParams,
    float_grid,
    int_array,
    kernel,
    vec,
    vec3_array,
)


@ti.func
def cell_under(heights: ti.template(), terrain, x):
    """(i, k, s, t): the grid cell under x [m] and the position s, t ∈ [0, 1] inside it.

    Outside the grid the edge cells are used with the cell coordinates clamped.
    """
    nx, nz = heights.shape[0], heights.shape[1]
    u = (x[0] - terrain.origin[0]) / terrain.dx
    w = (x[2] - terrain.origin[2]) / terrain.dz
    uc, wc = 0.0, 0.0  # NaN and everything below the grid clamp to 0
    if u > 0.0:
        uc = ti.min(u, nx - 1.0)
    if w > 0.0:
        wc = ti.min(w, nz - 1.0)
    i = ti.min(ti.cast(ti.floor(uc), ti.i32), nx - 2)
    k = ti.min(ti.cast(ti.floor(wc), ti.i32), nz - 2)
    return i, k, uc - i, wc - k


@ti.func
def surface_contact(contact, table: ti.template(), cells: ti.template(), heights: ti.template(), terrain, x):
    """The contact parameters of the surface type of the cell under x: ``contact`` with e, μ,
    μ_roll and turf from row ``cells[i, k]`` of ``table`` (S, 4)."""
    i, k, _, _ = cell_under(heights, terrain, x)
    row = cells[ti.min(i, cells.shape[0] - 1), ti.min(k, cells.shape[1] - 1)]
    c = contact
    c.e = table[row, 0]
    c.mu = table[row, 1]
    c.mu_roll = table[row, 2]
    c.turf = ti.cast(table[row, 3], ti.i32)
    return c


@ti.func
def surface(heights: ti.template(), terrain, x):
    """(p, n̂): the point of the terrain under x [m] and the unit normal of the bilinear patch there.

    Outside the grid the edge cells are used with the cell coordinates clamped to [0, 1].
    """
    i, k, s, t = cell_under(heights, terrain, x)
    h00, h10 = heights[i, k], heights[i + 1, k]
    h01, h11 = heights[i, k + 1], heights[i + 1, k + 1]
    h = terrain.origin[1] + ((h00 * (1.0 - s) + h10 * s) * (1.0 - t) + (h01 * (1.0 - s) + h11 * s) * t)
    hx = ((h10 - h00) * (1.0 - t) + (h11 - h01) * t) / terrain.dx
    hz = ((h01 - h00) * (1.0 - s) + (h11 - h10) * s) / terrain.dz
    n = vec(-hx, 1.0, -hz)
    return vec(x[0], h, x[2]), n / n.norm()


@ti.func
def terrain_clearance(heights: ti.template(), terrain, x, x_free, radius):
    """A lower bound [m] on the surface gap of a ball of ``radius`` at x [m] to the plane of any
    patch point of the cell under x (:func:`surface`), less the ball's free-flight displacement
    |x_free − x|; or −1 when x_free lies over another cell or the ball is not above the cell's
    highest node. A patch plane at q has the normal (−h_x, 1, −h_z)/N, N = √(1 + h_x² + h_z²), so
    for x above the cell's top node by a > 0, with |(h_x, h_z)| ≤ S in the cell and q within d of
    x horizontally: gap ≥ (a − S·d)/√(1 + S²) − radius ≥ a/√(1 + S²) − d − radius once
    a > S·d; a point y within D of x is then at least D less. Lets a step skip the terrain for
    balls that cannot reach it (a pile on a height-field floor) without changing any result."""
    c = -1.0
    i, k, _, _ = cell_under(heights, terrain, x)
    i2, k2, _, _ = cell_under(heights, terrain, x_free)
    if i == i2 and k == k2:
        h00, h10 = heights[i, k], heights[i + 1, k]
        h01, h11 = heights[i, k + 1], heights[i + 1, k + 1]
        above = x[1] - terrain.origin[1] - ti.max(ti.max(h00, h10), ti.max(h01, h11))
        sx = ti.max(ti.abs(h10 - h00), ti.abs(h11 - h01)) / terrain.dx
        sz = ti.max(ti.abs(h01 - h00), ti.abs(h11 - h10)) / terrain.dz
        if above > 0.0:
            c = above / ti.sqrt(1.0 + sx * sx + sz * sz) - radius - (x_free - x).norm()
    return c


@ti.func
def same_cell(heights: ti.template(), terrain, x, y):
    """Whether the points x and y [m] lie over the same grid cell (clamped at the edges, see
    :func:`cell_under`)."""
    i, k, _, _ = cell_under(heights, terrain, x)
    i2, k2, _, _ = cell_under(heights, terrain, y)
    return i == i2 and k == k2


@ti.func
def outside(heights: ti.template(), terrain, x):
    """Whether a ball at x [m] is out of bounds: its (x, z) off the grid or y below ``terrain.kill``."""
    ex = terrain.dx * (heights.shape[0] - 1)
    ez = terrain.dz * (heights.shape[1] - 1)
    out = False
    if not (
        x[0] >= terrain.origin[0]
        and x[0] <= terrain.origin[0] + ex
        and x[2] >= terrain.origin[2]
        and x[2] <= terrain.origin[2] + ez
        and x[1] >= terrain.kill
    ):
        out = True  # (NaN positions are out too)
    return out


@ti.func
def terrain_position(x, x1, p, n, radius, heights: ti.template(), terrain):
    """End-of-step position x1 [m] of a ball that started the step at x, kept out of the patch it
    ends over.

    The contact used the plane (p, n̂) of the patch under the free-flight end point. A ball may end
    over another patch, or (on a concave fold) start the step below the extended plane of the
    contact patch while touching the patch under it; both are artefacts of using one plane per
    step, not contact penetration. So the ball may penetrate the patch it ends over no deeper than
    it penetrates (p, n̂) at x1, or, when it started over another patch, than it penetrated that
    patch at x; deeper, it is moved out along the end patch's normal. (On a plane, flat or tilted,
    all patches coincide and this changes nothing.)
    """
    allowed = ti.min((x1 - p).dot(n) - radius, 0.0)
    pa, na = surface(heights, terrain, x)
    if (na != n).any():
        allowed = ti.max(allowed, ti.min((x - pa).dot(na) - radius, 0.0))
    p2, n2 = surface(heights, terrain, x1)
    gap = (x1 - p2).dot(n2) - radius
    if gap < allowed:
        x1 += (allowed - gap) * n2
    return x1


@kernel
def sample_surface(
    terrain: TerrainParams, heights: float_grid, x: vec3_array, p: vec3_array, n: vec3_array, out: int_array
):
    """For points x (N,) [m]: the terrain point p under each and its unit normal n, and ``out`` = 1
    where a ball centred there would be out of bounds (the contact's own functions, for checks)."""
    for i in range(x.shape[0]):
        p[i], n[i] = surface(heights, terrain, x[i])
        out[i] = ti.cast(outside(heights, terrain, x[i]), ti.i32)
