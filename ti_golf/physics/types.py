"""Taichi types of the physics kernels (created after ``ti.init``, see the package docstring)."""


import taichi as ti

from ti_golf.physics import _ensure_init  # noqa: F401  (Taichi must be initialised before the types below)

real = ti.f64 if ti.lang.impl.get_runtime().default_fp == ti.f64 else ti.f32
"""The float type chosen at ``ti.init`` (f32 or f64), spelled out so numpy arrays can be checked against it."""

vec3 = ti.types.vector(3, real)
"""3-vector of the default float [SI units]."""

AirParams = ti.types.struct(
    rho=float,  # air density ρ [kg/m³]
    gamma=ti.i32,  # flow type γ: 1 laminar, 2 turbulent
    C_D=float,  # drag coefficient (L.22)
    C_M=float,  # Magnus coefficient (L.21)
    omega_M=float,  # Magnus reference angular velocity ω_M [1/s] (L.2)
    C_omega=float,  # spin-decay coefficient (L.23)
    wind=vec3,  # constant wind velocity [m/s]
    model=ti.i32,  # aerodynamic model (aero.AIR_MODEL_CODES): 0 the report's laws, 1 coefficients of the spin ratio
)
"""Air parameters, passed to kernels by value (tunable without recompiling)."""

ContactParams = ti.types.struct(
    e=float,  # restitution (B.9)
    mu=float,  # Coulomb friction (B.15)
    k_p=float,  # position projection factor (B.18)
    mu_roll=float,  # rolling resistance: deceleration μ_roll·g_n while rolling
    relax=float,  # Jacobi relaxation of resting ball–ball impulses
    v_bounce=float,  # approach speeds below v_bounce + 2|g|h are inelastic [m/s]
    turf=ti.i32,  # 1: ground impacts as on turf (contact.turf_impact); 0: restitution e
)
"""Impulse-contact parameters (report Appendix B)."""

# ndarray annotations (any length; element types follow the precision chosen at init)
vec3_array = ti.types.ndarray(dtype=vec3, ndim=1)
float_array = ti.types.ndarray(dtype=real, ndim=1)
int_array = ti.types.ndarray(dtype=ti.i32, ndim=1)
vec3_table = ti.types.ndarray(dtype=vec3, ndim=2)
vec3f = ti.types.vector(3, ti.f32)
"""3-vector of f32 whatever the precision (positions kept only to test how far balls moved, see
``collide.moved_past``)."""
vec3f_array = ti.types.ndarray(dtype=vec3f, ndim=1)
f32_array = ti.types.ndarray(dtype=ti.f32, ndim=1)
f32_table = ti.types.ndarray(dtype=ti.f32, ndim=2)
pair_entry = ti.types.vector(5, real)
"""A pair's entry in a sweep: its impulse [N·s], inverse distance [1/m] and gap [m] (see collide.owned_pairs)."""
pair_table = ti.types.ndarray(dtype=pair_entry, ndim=2)
float_grid = ti.types.ndarray(dtype=real, ndim=2)

TerrainParams = ti.types.struct(
    on=ti.i32,  # 1: the scene has a terrain (its heights are the kernel's height-grid argument); 0: none
    origin=vec3,  # the grid's first corner [m]; heights are added to its y
    dx=float,  # grid spacing along x [m]
    dz=float,  # grid spacing along z [m]
    kill=float,  # balls below this height are out of bounds [m]
)
"""Height-field terrain parameters (see :mod:`ti_golf.physics.terrain`)."""
int_grid = ti.types.ndarray(dtype=ti.i32, ndim=2)
"""2-D int array (terrain cell surface types)."""


@ti.func
def of_ball(a: ti.template(), i):
    """Entry ``i`` of a per-ball array of shape (N,), or its only entry when every ball shares the
    value (shape (1,): the radius and mass of balls all alike, see ``Model``)."""
    return a[ti.min(i, a.shape[0] - 1)]
