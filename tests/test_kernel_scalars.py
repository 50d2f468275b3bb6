"""The kernels' scalar parameters travel in one array (``physics.types.scalars_of``): every member
of the air, contact, terrain and step structs comes back in the kernel as it was set, floats,
integers and vectors alike, and the array is filled again when a struct is replaced."""

import numpy as np
import taichi as ti

from ti_golf.physics.packs import Packs
from ti_golf.physics.types import (
    SCALAR_STRUCTS,
    float_array,
    kernel,
    scalar_slots,
    scalars_of,
)
from ti_golf.runtime import ensure_init


def distinct_structs(offset: float = 0.0) -> list:
    """A struct of each kind of ``SCALAR_STRUCTS`` whose scalars are all different (the k-th scalar
    of the whole array is k + 1 + offset; integers too), so that a member read from another
    member's place cannot go unseen."""
    structs, k = [], 0
    for kind in SCALAR_STRUCTS:
        members = {}
        for name, _, width, integer in scalar_slots(kind.get()):
            if width:
                members[name] = [k + 1.0 + offset + c for c in range(width)]
            else:
                members[name] = int(k + 1 + offset) if integer else k + 1.0 + offset
            k += max(width, 1)
        structs.append(kind(**members))
    return structs


@kernel
def read_back(scalars: float_array, out: float_array):
    """Named members of each struct, in the order of ``NAMED``."""
    air, contact, terrain, params = scalars_of(scalars)
    out[0], out[1], out[2] = air.rho, ti.cast(air.gamma, float), air.spin_decay
    out[3], out[4], out[5] = air.wind[0], air.wind[1], air.wind[2]
    out[6], out[7] = contact.e, ti.cast(contact.turf, float)
    out[8], out[9], out[10] = ti.cast(terrain.on, float), terrain.origin[2], terrain.kill
    out[11], out[12], out[13] = params.gravity[0], params.h, params.r_cut


NAMED = [
    (0, "rho", None),
    (0, "gamma", None),
    (0, "spin_decay", None),
    (0, "wind", 0),
    (0, "wind", 1),
    (0, "wind", 2),
    (1, "e", None),
    (1, "turf", None),
    (2, "on", None),
    (2, "origin", 2),
    (2, "kill", None),
    (3, "gravity", 0),
    (3, "h", None),
    (3, "r_cut", None),
]


def expected(structs: list) -> np.ndarray:
    return np.array([structs[s][name] if c is None else structs[s][name][c] for s, name, c in NAMED], dtype=float)


def test_every_kind_of_member_reaches_the_kernel_from_its_own_place():
    ensure_init()
    structs = distinct_structs()
    out = ti.ndarray(float, len(NAMED))
    read_back(Packs().scalars(*structs), out)
    assert np.array_equal(out.to_numpy(), expected(structs))
    assert len(set(expected(structs))) == len(NAMED)  # (the test's own premise: all different)


def test_the_array_is_filled_again_only_when_a_struct_is_replaced():
    ensure_init()
    packs, structs = Packs(), distinct_structs()
    first = packs.scalars(*structs)
    assert packs.scalars(*structs) is first  # the same structs: nothing to fill
    moved = distinct_structs(offset=100.0)
    out = ti.ndarray(float, len(NAMED))
    read_back(packs.scalars(structs[0], structs[1], structs[2], moved[3]), out)
    assert np.array_equal(out.to_numpy()[11:], expected(moved)[11:])  # the new step parameters
    assert np.array_equal(out.to_numpy()[:11], expected(structs)[:11])  # the others as they were
