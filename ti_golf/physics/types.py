"""Taichi types of the physics kernels, made when the Taichi runtime starts.

Taichi fixes the meaning of ``float`` in a type when the type is made: a type made before
``ti.init(default_fp=ti.f64)`` would silently hold f32. So the float-dependent types below are
:class:`Deferred`: each is made on first use, after :func:`ti_golf.runtime.init` has chosen the
precision (first use initialises the runtime with its defaults if nothing chose it yet), and
kernels whose signatures name them are declared with :func:`kernel`, which applies ``ti.kernel``
on the first call. Importing the physics therefore starts no runtime.

Inside kernel and ``ti.func`` bodies, ``float`` is the chosen float type (Taichi resolves it when
it compiles), so bodies write ``ti.cast(x, float)`` and build vectors with :func:`vec` and
:func:`zero3` rather than calling the deferred types.
"""

import functools
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeAlias

import taichi as ti

from ti_golf import front_end, launcher, one_thread, runtime

front_end.install()  # before the kernel modules' decorators run: they read the caller's source line


class Deferred:
    """A Taichi type made on first use, after the runtime has chosen the float type.

    Calling it (outside kernels) or reading an attribute makes the type and forwards to it, so
    ``vec3(0.0, -9.81, 0.0)`` and ``AirParams(rho=1.2, ...)`` work as with the type itself.
    """

    def __init__(self, make: Callable[[], Any], name: str) -> None:
        self._make = make
        self._type: Any = None
        self.__name__ = name

    def get(self) -> Any:
        """The Taichi type (made now if this is its first use)."""
        if self._type is None:
            runtime.ensure_init()
            self._type = self._make()
        return self._type

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        """A value of the type (made now if this is its first use), as the type's own call makes it."""
        return self.get()(*args, **kwargs)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self.get(), name)

    def __repr__(self) -> str:
        return f"Deferred({self.__name__})"


@dataclass
class LaunchClock:
    """The host calls of the project's kernels (:func:`kernel`) while ``on``: how many, and the
    seconds spent inside them (the launch, and on CPU backends the kernel's run, which there
    runs in the calling thread; on GPU backends the wait for a result a kernel returns). Off, a
    launch costs one test more (for the benchmarks: ``ti-golf bench pit``)."""

    on: bool = False
    calls: int = 0
    inside_s: float = 0.0


LAUNCHES = LaunchClock()
"""The process's :class:`LaunchClock`."""


def kernel(fn: Callable[..., Any]) -> Callable[..., Any]:
    """``ti.kernel``, applied at the first call, when the :class:`Deferred` types in ``fn``'s
    annotations (arguments and return) can be made with the chosen float type; counted and timed
    by :data:`LAUNCHES` while it is on. Arguments may be passed by name, as to ``ti.kernel``.
    Inside :func:`ti_golf.one_thread.in_one_thread` it launches its one-thread variant, every loop
    in the calling thread (:func:`ti_golf.one_thread.variant`): the same result."""
    compiled: Callable[..., Any] | None = None
    in_one_thread: Callable[..., Any] | None = None

    def make() -> Callable[..., Any]:
        fn.__annotations__ = {k: a.get() if isinstance(a, Deferred) else a for k, a in fn.__annotations__.items()}
        made = ti.kernel(fn)
        return launcher.FastCall(made) if launcher.enabled() else made

    @functools.wraps(fn)
    def launch(*args: Any, **kwargs: Any) -> Any:
        nonlocal compiled, in_one_thread
        if one_thread.active():
            if in_one_thread is None:
                in_one_thread = one_thread.variant(make())
            target = in_one_thread
        else:
            if compiled is None:
                compiled = make()
            target = compiled
        if not LAUNCHES.on:
            return target(*args, **kwargs)
        t0 = time.perf_counter()
        try:
            return target(*args, **kwargs)
        finally:
            LAUNCHES.calls += 1
            LAUNCHES.inside_s += time.perf_counter() - t0

    return launch


def is_f64() -> bool:
    """Whether the chosen float type is f64 (for ``ti.static`` branches in kernels)."""
    return runtime.ensure_init().precision == "f64"


def no_f64_transcendentals() -> bool:
    """Whether kernels run on Taichi's Vulkan backend in f64, which has no 64-bit log, exp, sin,
    cos or atan2 (SPIR-V's GLSL.std.450 set stops at 32 bits): there they are worked out in f32
    (for ``ti.static`` branches in kernels)."""
    return is_f64() and ti.lang.impl.current_cfg().arch == ti.vulkan


@ti.func
def log(x):
    """ln x (a scalar or a vector) in the float type; in f32 where :func:`no_f64_transcendentals`
    (about 1e-7 of itself)."""
    y = x
    if ti.static(no_f64_transcendentals()):
        y = ti.cast(ti.log(ti.cast(x, ti.f32)), float)
    else:
        y = ti.log(x)
    return y


@front_end.expanded
def vec(a, b, c):
    """The 3-vector (a, b, c) in the chosen float type, inside kernels."""
    return front_end.float_vector(a, b, c)


@front_end.expanded
def zero3():
    """The zero 3-vector in the chosen float type, inside kernels."""
    return front_end.float_vector(0.0, 0.0, 0.0)


real: TypeAlias = Deferred(lambda: ti.f64 if is_f64() else ti.f32, "real")
"""The float type chosen at ``ti.init`` (f32 or f64): Taichi's own ``ti.f32``/``ti.f64`` objects,
which its argument checks compare by identity."""

vec3: TypeAlias = Deferred(lambda: ti.types.vector(3, float), "vec3")
"""3-vector of the chosen float [SI units]."""

AirParams: TypeAlias = Deferred(
    lambda: ti.types.struct(
        rho=float,  # air density ρ [kg/m³]
        gamma=ti.i32,  # flow type γ: 1 laminar, 2 turbulent
        C_D=float,  # drag coefficient (L.22)
        C_M=float,  # Magnus coefficient (L.21)
        omega_M=float,  # Magnus reference angular velocity ω_M [1/s] (L.2)
        C_omega=float,  # spin-decay coefficient (L.23)
        wind=vec3.get(),  # wind velocity [m/s]; with the log profile, at the height wind_height
        viscosity=float,  # dynamic viscosity μ [Pa·s] (Re = ρ|v_rel|·2R/μ; model 2)
        wind_height=float,  # reference height z_ref of the log profile [m]
        wind_z0=float,  # roughness length z₀ of the log profile [m]
        ground_height=float,  # y [m] from which the log profile's heights are measured
        C_D_S=vec3.get(),  # C_D0, C_D1, C_D2 of C_D(S) above the drag crisis (model 2)
        C_L_S=vec3.get(),  # C_L0, C_L1, C_L2 of C_L(S) (model 2)
        C_D_crisis=float,  # rise of C_D through the drag crisis (model 2)
        Re_crisis=float,  # Reynolds number at the middle of the crisis (model 2)
        spin_decay=float,  # λ of dω/dt = −λ|v_rel|ω/R (model 2)
    ),
    "AirParams",
)
"""Air parameters, passed to kernels by value (tunable without recompiling)."""

ContactParams: TypeAlias = Deferred(
    lambda: ti.types.struct(
        e=float,  # restitution (B.9)
        mu=float,  # Coulomb friction (B.15)
        k_p=float,  # position projection factor (B.18)
        mu_roll=float,  # rolling resistance: deceleration μ_roll·g_n while rolling
        relax=float,  # Jacobi relaxation of resting ball–ball impulses (see contact.pair_impulse)
        v_bounce=float,  # approach speeds below v_bounce + 2|g|h are inelastic [m/s]
        turf=ti.i32,  # 1: ground impacts as on turf (contact.turf_impact, built with Kinds.turf); 0: restitution e
    ),
    "ContactParams",
)
"""Impulse-contact parameters (report Appendix B)."""

TerrainParams: TypeAlias = Deferred(
    lambda: ti.types.struct(
        on=ti.i32,  # 1: the scene has a terrain (its heights are the kernel's height-grid argument); 0: none
        origin=vec3.get(),  # the grid's first corner [m]; heights are added to its y
        dx=float,  # grid spacing along x [m]
        dz=float,  # grid spacing along z [m]
        kill=float,  # balls below this height are out of bounds [m]
    ),
    "TerrainParams",
)
"""Height-field terrain parameters (see :mod:`ti_golf.physics.terrain`)."""

# ndarray annotations (any length; element types follow the precision chosen at init)
vec3_array: TypeAlias = Deferred(lambda: ti.types.ndarray(dtype=vec3.get(), ndim=1), "vec3_array")
float_array: TypeAlias = Deferred(lambda: ti.types.ndarray(dtype=real.get(), ndim=1), "float_array")
vec3_table: TypeAlias = Deferred(lambda: ti.types.ndarray(dtype=vec3.get(), ndim=2), "vec3_table")
float_grid: TypeAlias = Deferred(lambda: ti.types.ndarray(dtype=real.get(), ndim=2), "float_grid")
"""2-D float array (terrain heights, tables)."""
pair_table: TypeAlias = ti.types.ndarray(ndim=2)
"""The pairs' sweep entries, a row per listed pair (see ``NeighbourLists.first``): ``INV`` to
``P_Z`` in the float type with the Jacobi sweeps, ``INV`` to ``FRIC`` in f32 with the
Gauss–Seidel sweeps (see :func:`pair_columns`, :func:`pair_table_type`)."""

INV, GAP, P_X, P_Y, P_Z = 0, 1, 2, 3, 4
"""Columns of a pair's row in the sweep's table (``StepScratch.J``): its inverse distance [1/m] and
surface gap [m] (the Gauss–Seidel sweeps read no more), then with the Jacobi sweeps the impulse P
[N·s] that the pair's owner takes in the sweep (see ``pairs.owned_pairs``). Between steps a
rebuild of the lists keeps each pair's resting impulse and neighbour id in the first two (see
``links.stash``)."""
GAP_LOW = 2
"""The column of the Gauss–Seidel sweeps' f32 table that holds, in f64, the low 32 bits of a pair's
gap, its high 32 bits in ``GAP`` (see ``pairs.put_gap``)."""
LAM, ID, FRIC = 0, 1, 2
"""Columns of a stashed pair in the sweep's table during a rebuild (see ``links.stash``): its
resting impulse, its neighbour's id and, with the Gauss–Seidel sweeps, its friction impulse in 32
bits (see ``links.put_stashed``)."""


def pair_columns(gauss_seidel: bool) -> int:
    """Columns of the sweep's table (see ``INV``): 3 with the Gauss–Seidel sweeps, which apply each
    pair's impulse at once (the third for the gap's low bits, ``GAP_LOW``, and the friction impulse
    a rebuild stashes, ``FRIC``), 5 with the Jacobi sweeps, whose balls gather the impulses after."""
    return 3 if gauss_seidel else 5


def pair_table_type(gauss_seidel: bool) -> Any:
    """The element type of the sweep's table: f32 with the Gauss–Seidel sweeps, 12 bytes a pair
    (its inverse distance is refined to the float type where it is read, see
    ``pairs.kept_normal``; its gap keeps every bit of the float type, see ``pairs.put_gap``), and
    the float type with the Jacobi sweeps (the report's, whose figures do not change)."""
    return ti.f32 if gauss_seidel else real.get()


# Types that do not depend on the precision.
int_array: TypeAlias = ti.types.ndarray(dtype=ti.i32, ndim=1)
i64_array: TypeAlias = ti.types.ndarray(dtype=ti.i64, ndim=1)
"""1-D i64 array (the bits of non-negative f64 values, maximised with integer atomics)."""
int_grid: TypeAlias = ti.types.ndarray(dtype=ti.i32, ndim=2)
"""2-D int array (terrain cell surface types)."""
vec3f: TypeAlias = ti.types.vector(3, ti.f32)
"""3-vector of f32 whatever the precision (positions kept only to test how far balls moved, see
``links.distance_from_build``)."""
vec3f_array: TypeAlias = ti.types.ndarray(dtype=vec3f, ndim=1)
f32_array: TypeAlias = ti.types.ndarray(dtype=ti.f32, ndim=1)
vec4f: TypeAlias = ti.types.vector(4, ti.f32)
"""A contact's (λ, F_x, F_y, F_z) in f32 (see ``NeighbourLists.surface_impulse``)."""
vec4f_table: TypeAlias = ti.types.ndarray(dtype=vec4f, ndim=2)
int_table: TypeAlias = ti.types.ndarray(dtype=ti.i32, ndim=2)
"""2-D int array (neighbour lists: a row per ball)."""

ivec3: TypeAlias = ti.types.vector(3, ti.i32)
"""3-vector of i32 (grid cells)."""

# Kernel data grouped by what it is (argument packs of arrays, structs of scalars), as the
# kernels take it: model before state, inputs before outputs.
StepParams: TypeAlias = Deferred(
    lambda: ti.types.struct(
        gravity=vec3.get(),  # g [m/s²]
        h=float,  # time step [s]
        half_skin=float,  # half the neighbour lists' skin [m]
        skin=float,  # the neighbour lists' skin [m]
        v_rest=float,  # speed and R|ω| below which a touching ball counts as still [m/s]
        t_rest=float,  # time still before a ball is put at rest [s]
        v_cut=float,  # balls faster than this own no pair in the lists [m/s]
        r_cut=float,  # balls bigger than this own no pair in the lists [m]
    ),
    "StepParams",
)
"""Scalars of a step of the collision solver (the launch's start time and step count are kernel
arguments of their own: they change from launch to launch)."""

SCALAR_STRUCTS = (AirParams, ContactParams, TerrainParams, StepParams)
"""The structs whose members a kernel reads from one array of scalars (:func:`scalars_of`), in
the array's order."""


def scalar_slots(struct_type: Any) -> list[tuple[str, int, int, bool]]:
    """Each member of ``struct_type`` (a Taichi struct type of floats, integers and vectors) as
    (name, offset in the struct's run of the scalar array, width: 0 for a scalar, whether an
    integer)."""
    slots, k = [], 0
    for name, dtype in struct_type.members.items():
        width = dtype.get_shape()[0] if isinstance(dtype, ti.lang.matrix.MatrixType) else 0
        slots.append((name, k, width, dtype in (ti.i32, ti.i64)))
        k += max(width, 1)
    return slots


def scalar_count(struct_type: Any) -> int:
    """How many scalars of the array a struct of ``struct_type`` takes."""
    return sum(max(width, 1) for _, _, width, _ in scalar_slots(struct_type))


def scalar_values(*structs: Any) -> list[float]:
    """The members of ``structs`` (Python-scope struct values of :data:`SCALAR_STRUCTS`, in order),
    one scalar after another, integers as floats: what :func:`scalars_of` reads back."""
    values: list[float] = []
    for kind, struct in zip(SCALAR_STRUCTS, structs, strict=True):
        for name, _, width, _ in scalar_slots(kind.get()):
            v = struct[name]
            if width:
                values.extend(float(v[c]) for c in range(width))
            else:
                values.append(float(v))
    return values


def scalar_runs() -> list[tuple[Any, int]]:
    """Each struct type of :data:`SCALAR_STRUCTS` with the offset of its run in the scalar array."""
    runs, base = [], 0
    for kind in SCALAR_STRUCTS:
        runs.append((kind.get(), base))
        base += scalar_count(kind.get())
    return runs


@front_end.expanded
def scalar_member(s: ti.template(), k: ti.template(), width: ti.template(), integer: ti.template()):
    """The struct member at offset ``k`` of the scalar array ``s``: a vector of ``width`` floats, an
    integer or a float."""
    if ti.static(width > 0):
        return front_end.float_vector(*[front_end.element(s, k + c) for c in ti.static(range(width))])
    elif ti.static(integer):
        return ti.cast(front_end.element(s, k), ti.i32)
    else:
        return front_end.element(s, k)


@front_end.expanded
def struct_at(kind: ti.template(), s: ti.template(), base: ti.template()):
    """The struct of type ``kind`` whose members start at offset ``base`` of the scalar array ``s``."""
    return kind(*[scalar_member(s, base + k, w, i) for _, k, w, i in ti.static(scalar_slots(kind))])


@front_end.expanded
def scalars_of(s: ti.template()):
    """The air, contact, terrain and step parameters (:data:`SCALAR_STRUCTS`) from the scalar array
    ``s`` that :func:`scalar_values` filled. The kernels of a step take them as one array rather
    than as four struct arguments, which Taichi would set up member by member from Python at
    every launch (the docs' performance page gives the cost)."""
    runs = ti.static(scalar_runs())
    return (
        struct_at(runs[0][0], s, runs[0][1]),
        struct_at(runs[1][0], s, runs[1][1]),
        struct_at(runs[2][0], s, runs[2][1]),
        struct_at(runs[3][0], s, runs[3][1]),
    )


ModelArrays: TypeAlias = Deferred(
    lambda: ti.types.argpack(
        radius=float_array.get(),  # ball radii [m], (N,) or (1,) (see of_ball)
        mass=float_array.get(),  # ball masses [kg], (N,) or (1,)
        launch_height=float_array.get(),  # heights whose downward crossing is a landing [m], (N,) or (1,)
        plane_p=vec3_array.get(),  # a point on each plane [m], (P,)
        plane_n=vec3_array.get(),  # each plane's unit normal, (P,)
        heights=float_grid.get(),  # terrain heights [m], (nx, nz) (2×2 zeros without a terrain)
        terrain_cells=int_grid,  # surface type of each terrain cell, (nx − 1, nz − 1)
        surface_table=float_grid.get(),  # e, μ, μ_roll, turf of each surface type, (S, 4)
    ),
    "ModelArrays",
)
"""The model's arrays (see :class:`ti_golf.physics.model.Model`)."""

BallState: TypeAlias = Deferred(
    lambda: ti.types.argpack(
        x=vec3_array.get(),  # positions [m], (N,)
        v=vec3_array.get(),  # velocities [m/s], (N,)
        w=vec3_array.get(),  # angular velocities [rad/s], (N,)
        status=int_array,  # FLYING, ROLLING, AT_REST or OUT_OF_BOUNDS, (N,)
        rest_time=float_array.get(),  # time spent still [s], (N,)
    ),
    "BallState",
)
"""The balls' state (see :class:`ti_golf.physics.state.State`)."""

FlightRecord: TypeAlias = Deferred(
    lambda: ti.types.argpack(
        landed=int_array,  # IN_FLIGHT, LANDED or NOT_TRACKED, (N,) or (1,) when no ball is tracked
        apex=float_array.get(),  # highest centre height so far [m]
        t_land=float_array.get(),  # time of landing [s]
        land_x=vec3_array.get(),  # position at landing [m]
        land_v=vec3_array.get(),  # velocity at landing [m/s]
    ),
    "FlightRecord",
)
"""Each tracked ball's flight: landing and apex (see :class:`ti_golf.physics.state.State`)."""

NeighbourLists: TypeAlias = Deferred(
    lambda: ti.types.argpack(
        upper=int_table,  # the neighbours whose pairs each ball owns (grid.owns), sorted by index, (N, K)
        # ball i's pairs: upper[i, :first[i + 1] − first[i]], and in lam, friction, J the entries from first[i]
        first=int_array,  # (N + 1,)
        lower=int_array,  # each ball's lower neighbours, as slots of the pairs in their upper lists, ball after ball
        lower_first=int_array,  # where each ball's lower list starts in lower, (N + 1,) (links.link_lower_lists)
        x_at_build=vec3f_array,  # positions when the lists were built [m], f32, (N,)
        # how far [m] each ball may have moved, before the last build, since its list was made (a build keeps
        # the lists of the balls that did not move: see grid.list_kept), f32, (N,); 0 for a list the build made
        drift=f32_array,
        lam=f32_array,  # each pair's accumulated resting impulse [N·s], f32, (pairs,) (see first)
        # ball i has a row of surface impulses, surface_start[i], when surface_start[i + 1] > surface_start[i]
        surface_start=int_array,  # (N + 1,) (see surfaces.list_surfaces)
        # each row's accumulated resting impulse λ and (Gauss–Seidel) friction impulse F per unit mass [m/s]
        surface_impulse=vec4f_table,  # on each plane and the terrain, (λ, F_x, F_y, F_z) in f32, (rows, P + 1)
        friction=vec3f_array,  # each pair's friction impulse on its owner [N·s], f32, as lam (Gauss–Seidel)
    ),
    "NeighbourLists",
)
"""The collision solver's neighbour lists and the impulses it carries from step to step."""

BlockOrder: TypeAlias = Deferred(
    lambda: ti.types.argpack(
        start=int_array,  # each hash bucket's first entry in ids, (B + 1,)
        ids=int_array,  # the balls bucket by bucket, bottom-up in each, (N,)
        colour=int_array,  # the colour of each entry's block, (N,)
    ),
    "BlockOrder",
)
"""The balls grouped by block of grid columns for the Gauss–Seidel sweeps (:mod:`ti_golf.solvers.colour`)."""

StepScratch: TypeAlias = Deferred(
    lambda: ti.types.argpack(
        x_free=vec3_array.get(),  # free-flight positions, then the step's new positions [m], (N,)
        v_free=vec3_array.get(),  # free-flight velocities [m/s], (N,)
        calm=float_array.get(),  # least rest timer of the balls touching each ball [s], (N,)
        clear=f32_array,  # clearance to the nearest plane or terrain [m], (N,)
        J=pair_table,  # each pair's inverse distance, gap and (Jacobi) impulse in a sweep, (pairs, 3 or 5)
        impact=int_array,  # Jacobi: each ball's first impact key; Gauss–Seidel: 1 for a ball to bounce, (N,)
        flag=int_array,  # [0]: rebuild the lists; [1]: the sweep marked impacts, (2,)
    ),
    "StepScratch",
)
"""Per-step work arrays of the collision solver."""


@front_end.expanded
def of_ball(a: ti.template(), i):
    """Entry ``i`` of a per-ball array of shape (N,), or its only entry when every ball shares the
    value (shape (1,): the radius and mass of balls all alike, see ``Model``)."""
    return front_end.element(a, ti.min(i, a.shape[0] - 1))


GridParams: TypeAlias = Deferred(
    lambda: ti.types.struct(
        inv_cell=float,  # 1 / the grid's cell size [1/m]
        mask=ti.i32,  # the hash table's size − 1 (a power of two − 1)
        origin=ivec3,  # the least cell of the balls
        stride=ivec3,  # the hash's strides per cell axis
        skin=float,  # the lists' skin [m]: pairs closer than the sum of their radii plus this are listed
        h=float,  # time step [s]
        fast=ti.i32,  # 1: some balls are set apart as fast or big (apart_ids)
        v_cut=float,  # balls faster than this own no pair [m/s]
        r_cut=float,  # balls bigger than this own no pair [m]
        n_apart=ti.i32,  # how many balls are set apart
        scan_apart=ti.i32,  # 1: every ball tests the balls set apart
    ),
    "GridParams",
)
"""Scalars of a neighbour-list build (see :func:`ti_golf.solvers.grid.list_neighbours`)."""

KeptLists: TypeAlias = Deferred(
    lambda: ti.types.argpack(
        marks=vec3_array.get(),  # each ball's (skin owed [m], 1 when its list is made again, 0) at a build, (N,)
        new_index=int_array,  # each ball's index in the new storage order, by its old index, (N,)
        stashed=pair_table,  # the old lists' pairs, laid out as their pair tables (links.stash)
        stash_first=int_array,  # where each ball's old pairs start in stashed, (N + 1,)
    ),
    "KeptLists",
)
"""What a build that keeps the lists of the balls that did not move reads (``grid.list_neighbours``)."""

GridScratch: TypeAlias = ti.types.argpack(
    rank=int_array,  # each ball's rank within its bucket, (N,)
    start=int_array,  # each bucket's first entry in sorted_ids, (buckets + 1,)
    chunk_start=int_array,  # the counting sort's per-chunk starts
    sorted_ids=int_array,  # ball ids sorted by bucket, (N,)
)
"""Work arrays of the grid's counting sort."""
