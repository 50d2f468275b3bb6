"""The arguments that a collision step's functions share, bundled as one (:class:`Step`)."""

from typing import Any, NamedTuple


class Step(NamedTuple):
    """The parameters and arrays of a collision step, which its functions take as one
    ``ti.template()`` argument and read by name (``s.contact.mu``, ``s.lists.lam[p]``): the
    contact, terrain and step parameters (:func:`ti_golf.physics.types.scalars_of`), the model's
    arrays, the neighbour lists, the balls' state and the step's scratch (the argument packs of
    :mod:`ti_golf.physics.types`); the scene's kinds of code (:class:`ti_golf.physics.kinds.Kinds`),
    which the functions test with ``ti.static`` (``s.kinds.gauss_seidel``), so that a kernel holds
    only the code its scene runs (None in a kernel whose functions read none); and in the kernel
    of the whole step (:func:`.collide.collision_step`) the air parameters and the flight record.

    A kernel makes it once, ``s = ti.static(Step(...))``: a tuple, which Taichi binds as it is when
    it compiles the kernel, so that passing it on costs nothing and each function reads the same
    arrays and parameters it would read passed one by one."""

    contact: Any
    terrain: Any
    params: Any
    model: Any
    lists: Any
    state: Any
    scratch: Any
    kinds: Any = None
    air: Any = None
    flight: Any = None
