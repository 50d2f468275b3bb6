"""The balls whose neighbour lists a build keeps (``grid.list_neighbours`` with ``amend``; see
the docstring of :mod:`.grid`): which ball keeps its list, which pair goes to which list when a
ball listed anew meets one that kept its list, and the balls promoted to be listed anew after the
others. Read through :class:`Keep`, bound once in the build's kernel."""

from typing import Any, NamedTuple

import taichi as ti

from ti_golf.solvers.stash import stashed_row


class Keep(NamedTuple):
    """What a build that keeps the lists of the balls that did not move reads (see
    :func:`.grid.list_neighbours`), bound once in its kernel (as ``solvers.step.Step`` is)."""

    amend: Any
    """1: the balls ``kept.marks`` marks keep their lists; 0: every ball is listed anew."""
    kept: Any
    """The :data:`~ti_golf.physics.types.KeptLists` pack."""
    sorted_ids: Any
    """With ``stored_sorted``, each ball's index before the build's reorder (``GridScratch``)."""
    stored_sorted: bool
    """Whether the build stored the balls in a new order (see :func:`.grid.list_neighbours`)."""


@ti.func
def amended_owner(i, j, mine, keep: ti.template()):
    """Whether ball i, listed anew at a build that keeps lists, owns its pair with ball j within
    reach (``mine``: whether it would by :func:`.grid.owns`; :class:`Keep`). Ball j's old list keeps
    the pair if it held it. Else a pair with a ball that keeps its list goes by :func:`.grid.owns`:
    when ball j would own it, ball i *promotes* j (``kept.marks[j][2]``), which is listed anew
    after the others (:func:`.grid.list_neighbours`' second pass) and takes it then. A promoted ball
    owns its pairs with the balls listed anew that its old list held or that it would own, with
    the balls that kept their lists those their old lists do not hold, and with the other
    promoted balls those it would own: each pair once, as by :func:`.grid.owns` but for the pairs that
    the old lists keep."""
    marks = ti.static(keep.kept.marks)
    promoted = marks[i][2] != 0.0  # (only in the second pass: the first lists the balls marked anew)
    if marks[j][1] == 0.0:  # j kept its list, and may have been promoted
        both = False
        if promoted:
            both = marks[j][2] != 0.0
        if not both:
            held = kept_by_other(i, j, keep)
            if promoted:
                mine = not held
            elif held:
                mine = False
            elif not mine:
                marks[j][2] = 1.0  # (every thread that promotes j writes the same)
    elif promoted:  # j listed anew, in the first pass: its pairs with i are the complement of its own
        mine = mine or kept_by_other(j, i, keep)
    return mine


@ti.func
def promoted(i, keep: ti.template()):
    """Whether ball i, which kept its list, is listed anew in the second pass (:func:`amended_owner`)."""
    anew = False
    if keep.amend != 0:
        anew = keep.kept.marks[i][2] != 0.0
    return anew


@ti.func
def keeps_list(i, keep: ti.template()):
    """Whether ball i keeps its old list at this build (:class:`Keep`)."""
    kept = False
    if keep.amend != 0:
        kept = keep.kept.marks[i][1] == 0.0
    return kept


@ti.func
def old_index(i, keep: ti.template()):
    """Ball i's index in the old lists: before the build's reorder, if it made one."""
    o = i
    if ti.static(keep.stored_sorted):
        o = keep.sorted_ids[i]
    return o


@ti.func
def kept_by_other(i, j, keep: ti.template()):
    """Whether the old list of ball j, which keeps its list, holds its pair with ball i."""
    row, _bits = stashed_row(keep.kept.stashed, keep.kept.stash_first, 0, old_index(j, keep), old_index(i, keep), True)
    return row >= 0


@ti.func
def rounded_up(d):
    """The distance ``d`` [m] >= 0 in f32, rounded up (never below ``d``): 2^-22 of it added
    before the cast to the nearest f32."""
    return ti.cast(d * (1.0 + 2.0**-22), ti.f32)
