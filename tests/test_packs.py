"""The kernels' argument packs (``sim.packs.Packs``): one per set of arrays while a solver swaps its
arrays, and past the few it alternates between, an old pack takes the new arrays rather than a new
pack being made (Taichi 1.7.4 keeps memory of every pack it makes)."""

import taichi as ti

from ti_golf.physics.packs import Packs
from ti_golf.physics.types import float_array
from ti_golf.runtime import ensure_init


def arrays(*values: float) -> list:
    """One-entry float arrays holding ``values``."""
    out = []
    for v in values:
        a = ti.ndarray(float, 1)
        a.fill(v)
        out.append(a)
    return out


class Counted:
    """A pack type that counts the packs made of it."""

    def __init__(self) -> None:
        self.kind, self.made = ti.types.argpack(a=float_array.get(), b=float_array.get()), 0

    def __call__(self, **members):
        self.made += 1
        return self.kind(**members)


def test_a_third_set_of_arrays_takes_over_the_least_recently_used_pack():
    ensure_init()
    kind = Counted()

    @ti.kernel
    def read(p: kind.kind, out: float_array.get()):
        out[0], out[1] = p.a[0], p.b[0]

    packs, out = Packs(), ti.ndarray(float, 2)
    x1, x2, x3, y = arrays(1.0, 2.0, 3.0, 10.0)
    p1 = packs.get(kind, a=x1, b=y)
    p2 = packs.get(kind, a=x2, b=y)
    assert p2 is not p1
    assert packs.get(kind, a=x1, b=y) is p1  # kept: now the most recently used
    p3 = packs.get(kind, a=x3, b=y)
    assert p3 is p2  # the least recently used of the two took the new arrays
    assert kind.made == 2  # and no pack was made
    read(p3, out)
    assert out.to_numpy().tolist() == [3.0, 10.0]  # the kernel sees the new member
    read(packs.get(kind, a=x1, b=y), out)
    assert out.to_numpy().tolist() == [1.0, 10.0]  # the other pack kept its own
    assert packs.get(kind, a=x2, b=y) is p3  # x1 was used last: x3's pack takes x2
    assert kind.made == 2
    read(p3, out)
    assert out.to_numpy().tolist() == [2.0, 10.0]  # a kernel launched with the pack before sees it too


def test_arrays_of_other_shapes_get_a_new_pack_and_drop_the_old_ones():
    ensure_init()
    kind, packs = Counted(), Packs()
    x1, x2, y = arrays(1.0, 2.0, 10.0)
    packs.get(kind, a=x1, b=y)
    packs.get(kind, a=x2, b=y)
    wide = ti.ndarray(float, 4)
    p = packs.get(kind, a=wide, b=y)
    assert kind.made == 3
    assert len(packs._kept) == 1  # (the narrower arrays are no longer held by any pack)
    assert packs.get(kind, a=wide, b=y) is p
