"""Gauss–Seidel sweeps laid out by contact colours (``contact.layout = "contacts"``).

The column layout (:mod:`.colour`) hands each thread a block of 2 × 2 grid columns and walks its
balls bottom-up: a pour of 100,000 balls gives about a hundred blocks of a colour, so a GPU runs
about a hundred threads. This layout hands each thread one *pair*: the listed pairs are given
colours so that no two pairs of a colour share a ball (:mod:`.edge_colouring`, made on the device
at each rebuild of the lists), and a sweep takes the colours in turn, every pair of a colour at
once, one thread each. The update of a pair is the column layout's
(:func:`.sequential.sweep_pair`: the same equations, :func:`.sequential.pair_step`); only the
order in which the pairs meet differs.

**A sweep** (:func:`colour_pass`): each ball meets its planes and the terrain (a thread per ball:
:func:`surface_ball`), then the colours follow one another (a parallel loop per colour, a thread
per pair: :func:`colour_pair`, its bounds read from ``start`` on the device), then the overflow
set: all in one launch on CUDA (``CUDA_SPAN``), elsewhere ``SPAN`` colours a launch (the first
with the surfaces) and the overflow set a launch of its own (:meth:`ContactColours.spans`). A sweep's
parallel loops therefore each hold a ball per thread, or a pair per thread: work in proportion to
the balls. The position projection (B.18) is laid out the same way, its planes last
(:func:`project_colour_pair`).
"""

import os
from dataclasses import dataclass
from typing import Any

import numpy as np
import taichi as ti

from ti_golf.errors import ConfigError
from ti_golf.physics.types import (
    BallState,
    ModelArrays,
    NeighbourLists,
    StepScratch,
    float_array,
    kernel,
    of_ball,
    scalars_of,
)
from ti_golf.runtime import ensure_init, on_cpu, plain_compile
from ti_golf.scene.schema import AT_REST, OUT_OF_BOUNDS
from ti_golf.solvers.colour import PROJECTIONS, step_phases
from ti_golf.solvers.edge_colouring import COLOURS, OVERFLOW, ColourTables, PairColouring
from ti_golf.solvers.pairs import QUIET
from ti_golf.solvers.phases import Phase
from ti_golf.solvers.sequential import (
    body,
    inelastic_speed,
    project_pair,
    project_planes,
    stands_firm,
    sweep_constants,
    sweep_pair,
)
from ti_golf.solvers.step import Step
from ti_golf.solvers.surfaces import surface_impulses

SPAN = 4
"""Colours a launch of :func:`colour_pass` takes, one parallel loop each, on backends other than
CUDA: the pair update is compiled once per colour of a launch, so a launch of all ``COLOURS``
costs a host call a pass instead of nine, but took 2.6 times as long to compile on the CPU (a
fresh cache's first step, with every other kernel: 251 s against 97 s on a loaded 2-core
machine). On CUDA a launch takes all ``COLOURS`` (``CUDA_SPAN``)."""

CUDA_SPAN = COLOURS
"""Colours a launch takes on CUDA: all of them, one host call a pass. Measured on an H200
(``make gpu-check``), against ``SPAN``: the 100,000-ball pour's first second in 23.1 s against 45.1 s,
the same pile; the pour's kernels compiled from an empty cache in 19.3 s against 8.5 s."""

SPAN_ENV = "TI_GOLF_COLOURS_PER_LAUNCH"
"""The environment variable that sets the colours a launch takes (see ``SPAN``)."""


def resolve_layout(layout: str) -> str:
    """The layout the sweeps take for ``contact.layout``: ``auto`` is the column layout on CPU
    backends (a few threads, each walking its columns bottom-up, is the fastest there) and the
    contact colours elsewhere (a GPU needs thousands of threads)."""
    if layout == "auto":
        return "columns" if on_cpu() else "contacts"
    return layout


def colours_per_launch() -> int:
    """Colours a launch of :func:`colour_pass` takes: ``TI_GOLF_COLOURS_PER_LAUNCH`` (a divisor of
    ``COLOURS``) when set, else ``CUDA_SPAN`` on CUDA and ``SPAN`` elsewhere (and on CUDA with
    Taichi's advanced IR passes, ``TI_GOLF_CUDA_PASSES=1``, under which a launch of all the colours
    did not compile within 200 s)."""
    text = os.environ.get(SPAN_ENV, "")
    if not text:
        runtime = ensure_init()
        return CUDA_SPAN if runtime.arch == "cuda" and runtime.plain_on_cuda else SPAN
    allowed = [k for k in range(1, COLOURS + 1) if COLOURS % k == 0]
    if not text.isdigit() or int(text) not in allowed:
        raise ConfigError(SPAN_ENV, None, f"must be one of {', '.join(map(str, allowed))}, not {text!r}")
    return int(text)


@ti.func
def colour_pair(p, phase, s: ti.template(), tables: ti.template()):
    """Pair p's update in a sweep of ``phase`` (:func:`.sequential.sweep_pair`; ``s``: the step's
    :class:`.step.Step`), as :func:`.colour.sweep_ball` makes it for the pairs its ball owns: none
    for an owner out of bounds or quiet, or in the restitution pass (``BOUNCE``) unmarked; the
    first sweep marks the owner when the pair approached faster than the inelastic speed."""
    contact, model, lists, state, scratch = ti.static((s.contact, s.model, s.lists, s.state, s.scratch))
    i = tables.owner[p]
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
        if phase != Phase.BOUNCE or scratch.impact[i] != 0:
            ri, inv_mi = of_ball(model.radius, i), 1.0 / of_ball(model.mass, i)
            if stands_firm(s.kinds, state.status[i]):
                inv_mi = 0.0
            j = lists.upper[i, p - lists.first[i]]
            a = body(state.v[i], state.w[i], ri, inv_mi)
            vi, wi, hit = sweep_pair(i, j, p, phase, state.x[i], a, sweep_constants(contact, s.params), s)
            state.v[i], state.w[i] = vi, wi
            if phase == Phase.FIRST and hit != 0:
                scratch.impact[i] = 1


@ti.func
def surface_ball(i, phase, s: ti.template()):
    """Ball i's planes and terrain in a sweep of ``phase`` (:func:`.surfaces.surface_impulses`),
    before the sweep's pairs; the first sweep also clears its mark of the restitution pass, which
    its pairs then set (:func:`colour_pair`)."""
    state, scratch = ti.static((s.state, s.scratch))
    if phase == Phase.FIRST:
        scratch.impact[i] = 0
    firm = stands_firm(s.kinds, state.status[i])
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET and not firm:
        v_inelastic = inelastic_speed(s.contact, s.params)
        vi, wi = surface_impulses(
            i, warm=False, vi=state.v[i], wi=state.w[i], h=s.params.h, v_inelastic=v_inelastic, s=s, phase=phase
        )
        state.v[i], state.w[i] = vi, wi


@kernel
def colour_pass(
    phase: ti.i32,
    c0: ti.i32,
    kinds: ti.template(),
    scalars: float_array,
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
    tables: ColourTables,
    project: ti.template(),
    head: ti.template(),
    span: ti.template(),
    tail: ti.template(),
):
    """Part or all of a sweep of ``phase`` (or, with ``project``, of a pass of the position
    projection): with ``head``, each ball's planes and terrain first (:func:`surface_ball`, a
    thread per ball; not in a projection); the pairs of colours ``c0`` to ``c0 + span − 1``, a
    parallel loop per colour, a thread per pair (:func:`colour_pair` or
    :func:`project_colour_pair`), each loop's bounds read from ``tables.start`` on the device;
    with ``tail``, the overflow set after, one pair after another, and in a projection each
    ball's planes last (:func:`.sequential.project_planes`). ``kinds``: the scene's kinds of code."""
    air, contact, terrain, params = scalars_of(scalars)  # (the air: a surface's inelastic speed, surfaces.air_push)
    s = ti.static(Step(contact, terrain, params, model, lists, state, scratch, kinds=kinds, air=air))
    if ti.static(head and not project):
        for i in range(state.x.shape[0]):
            surface_ball(i, phase, s)
    for c in ti.static(range(span)):
        for m in range(tables.start[c0 + c], tables.start[c0 + c + 1]):
            pair_pass(tables.pairs[m], phase, project, s, tables)
    if ti.static(tail):
        ti.loop_config(serialize=True)
        for m in range(tables.start[OVERFLOW], tables.start[OVERFLOW + 1]):
            pair_pass(tables.pairs[m], phase, project, s, tables)
        if ti.static(project):
            for i in range(state.x.shape[0]):
                moving = state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET
                if moving and state.status[i] != AT_REST:
                    scratch.x_free[i] = project_planes(scratch.x_free[i], of_ball(model.radius, i), contact.k_p, model)


@ti.func
def pair_pass(p, phase, project: ti.template(), s: ti.template(), tables: ti.template()):
    """Pair p's update in a sweep of ``phase`` (:func:`colour_pair`) or, with ``project``, its
    position projection (:func:`project_colour_pair`)."""
    if ti.static(project):
        project_colour_pair(p, s, tables)
    else:
        colour_pair(p, phase, s, tables)


@ti.func
def project_colour_pair(p, s: ti.template(), tables: ti.template()):
    """Pair p's position projection (:func:`.sequential.project_pair`), as
    :func:`.colour.project_ball` makes it for the pairs its ball owns."""
    model, state, scratch = ti.static((s.model, s.state, s.scratch))
    i = tables.owner[p]
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
        inv_mi = 0.0
        if state.status[i] != AT_REST:
            inv_mi = 1.0 / of_ball(model.mass, i)
        j = s.lists.upper[i, p - s.lists.first[i]]
        xi, ri = scratch.x_free[i], of_ball(model.radius, i)
        scratch.x_free[i] = project_pair(j, xi, ri, inv_mi, s.contact.k_p, model, state, scratch)


@dataclass
class ContactColours(PairColouring):
    """The pairs' colours (:class:`.edge_colouring.PairColouring`) and the launches of the sweeps
    over them: each pass takes the colours ``SPAN`` a launch, as far as the colours in use at the
    last build (``_used``, kept with the colours in a saved run)."""

    _used: int = COLOURS

    def saved(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        """The colouring's saved numbers and arrays, with the colours in use."""
        values, arrays = super().saved()
        values["used"] = self._used
        return values, arrays

    def restore(self, values: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
        """Take a saved colouring (:meth:`saved`) back, with the colours in use."""
        super().restore(values, arrays)
        self._used = values["used"]

    def build(self, lists: Any) -> None:
        """Colour the listed pairs anew and note how many colours they use."""
        super().build(lists)
        if colours_per_launch() < COLOURS:  # the launches a pass takes follow the colours in use
            self._used = self.sizes()[0]

    def spans(self, project: bool) -> list[tuple[int, bool, int, bool]]:
        """(first colour, head, colours, tail) of each launch of :func:`colour_pass` in a pass (with
        ``project``, of the projection): one launch with a span of ``COLOURS``; else ``SPAN``
        colours a launch (a sweep's first with the balls' surfaces), then the overflow set (and
        a projection's planes) a launch of its own, so that a pile of more colours compiles no
        more kernels than the warm-up's few colours did."""
        span = colours_per_launch()
        if span == COLOURS:
            return [(0, True, COLOURS, True)]
        chunks = [(c0, c0 == 0 and not project, span, False) for c0 in range(0, max(self._used, 1), span)]
        return chunks + [(0, False, 0, True)]

    def launches(self, n: int, iterations: int) -> list[int]:
        """The work items (balls or pairs, each a thread that no other shares) of each parallel loop
        of a step's sweeps and projections with these colours (:func:`gauss_seidel_step`), in
        order, an empty colour's loop included; the overflow set's serial loop counts one item."""
        _, sizes, _ = self.sizes()
        loops = []
        for project, count in ((False, len(step_phases(iterations))), (True, PROJECTIONS)):
            items = []
            for c0, head, span, tail in self.spans(project):
                items += [n] if head and not project else []
                items += [sizes[c] if c < len(sizes) else 0 for c in range(c0, c0 + span)]
                items += ([1] + ([n] if project else [])) if tail else []
            loops += items * count
        return loops


def gauss_seidel_step(colours: ContactColours, iterations: int, arguments: tuple) -> None:
    """A step's Gauss–Seidel sweeps (``iterations`` of them and the restitution pass,
    :func:`.colour.step_phases`) laid out by contact colours, from the warm start to the end of the
    sweeps (:func:`colour_pass`: one launch a sweep on GPU backends; ``arguments``: those of
    ``collide.collision_step``, ``CollisionSolver._arguments``). The caller finishes the step
    (``collide.collision_step``) and then calls :func:`project`."""
    passes(colours, step_phases(iterations), proj=False, arguments=arguments)


def project(colours: ContactColours, arguments: tuple) -> None:
    """The ``PROJECTIONS`` passes of the position projection at the end of a step, laid out as the
    sweeps are: the colours, the overflow set, then each ball's planes."""
    passes(colours, [Phase.FIRST] * PROJECTIONS, proj=True, arguments=arguments)


def passes(colours: ContactColours, phases: Any, proj: bool, arguments: tuple) -> None:
    """A pass of :func:`colour_pass` for each of ``phases`` (with ``proj``: of the projection),
    with the step's scalars, kinds, model, lists, state and scratch from ``arguments`` (see
    :func:`gauss_seidel_step`)."""
    scalars, _, _, _, kinds, model, lists, state, _, scratch = arguments
    t, spans = colours.tables, colours.spans(proj)
    with plain_compile(vulkan=True):  # see runtime.plain_compile
        for phase in phases:
            for c0, head, span, tail in spans:
                colour_pass(
                    phase,
                    c0,
                    kinds,
                    scalars,
                    model,
                    lists,
                    state,
                    scratch,
                    t,
                    project=proj,
                    head=head,
                    span=span,
                    tail=tail,
                )
