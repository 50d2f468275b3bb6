"""Study files: a base scene, the keys to vary, the task each point runs and the figures to collect.

A study file is TOML, checked as a scene file is: every key is declared once here (a dataclass
field made with :func:`~ti_golf.scene.keys.key`), from which come the checks, the one-line errors
naming the file and the key, and the JSON Schema (:func:`study_json_schema`). The varied keys are
scene keys: each task's scene is built (and so checked, with the scene loader's errors) when the
study is loaded, before anything runs. Plain Python, no Taichi.

::

    description = "Carry of the PGA bag against altitude and temperature"
    scene = "tour_shot"             # the base scene: a bundled name, or a file beside the study
    set = ["air.humidity=0.5"]      # changes every task makes to it (--set syntax)

    [task]
    kind = "tour"                   # run | sweep | shot | dispersion | tour | pit
    figures = ["carry", "apex"]

    [grid]                          # every combination (or [[points]], or [random])
    "air.altitude" = "0:2000:500"
    "air.temperature" = [5, 15, 25, 35]
"""

from __future__ import annotations

import itertools
import json
import math
import os
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ti_golf.errors import OVERRIDES, ConfigError
from ti_golf.scene.balls import scaled_block_problem
from ti_golf.scene.checks import DURATION, Interval, OneOf, parse_range, raise_config
from ti_golf.scene.document import scene_document
from ti_golf.scene.jsonschema import DIALECT, key_schema
from ti_golf.scene.keys import Key, key, keys_of, read_when_text
from ti_golf.scene.loader import load_scene, read_toml, resolve_scene_path, scenes_dir
from ti_golf.scene.overrides import key_of, parse_override
from ti_golf.scene.values import check_value
from ti_golf.study.figures import FIGURES, KINDS, default_figures
from ti_golf.study.reads import refuse_unread, scene_problem
from ti_golf.study.task_id import task_id

MAX_TASKS = 100_000
"""The most tasks a study may hold (a grid's combinations times the seeds)."""

FigureList = tuple[str, ...]


class _Figures:
    """The figures a study collects: names of :data:`~ti_golf.study.figures.FIGURES`."""

    allowed = " | ".join(FIGURES)

    def __call__(self, v: Sequence[str]) -> str | None:
        if not v:
            return "names no figure (leave it out for every figure of the kind)"
        bad = [name for name in v if name not in FIGURES]
        if bad:
            return f"names no figure {bad[0]!r}; allowed: {', '.join(FIGURES)}"
        return None if len(set(v)) == len(v) else "names a figure twice"

    def json_schema(self) -> dict[str, Any]:
        return {"items": {"type": "string", "enum": list(FIGURES)}, "uniqueItems": True}


@dataclass(frozen=True)
class Study:
    """The top of a study file: what it is and the scene it starts from."""

    description: str = key("text", "", "-", "what the study measures (shown in the plots)")
    scene: str = key(
        "str",
        "",
        "-",
        "the base scene: a scene file (a relative path is taken from the study file's folder) or a bundled "
        "scene's name; the pit benchmark (task.kind = pit) pours the bundled ball_pit",
    )
    set: tuple[str, ...] = key(
        "strs", (), "-", "changes every task makes to the base scene, as `--set KEY=VALUE` writes them"
    )
    seeds: tuple[float, ...] | None = key(
        "range",
        None,
        "-",
        "repetitions: every point runs once per seed (a list, or START:STOP:STEP), the seed taking the place of "
        "every random block's seed (run), the draw's (dispersion) or the pour's (pit); none: once, with the "
        "scene's own seeds",
    )


@dataclass(frozen=True)
class Task:
    """``[task]``: what each point of the study runs, and the figures it collects."""

    kind: str = key(
        "str",
        "run",
        "-",
        "run (the scene to a time, or until rest), sweep (the scene's [sweep] launches), shot (the scene's "
        "launch flown and rolled out), dispersion (a player's spread of shots), tour (the TrackMan tour "
        "averages in the scene's air) or pit (the pit benchmark)",
        OneOf(KINDS),
    )
    figures: FigureList = key(
        "strs", (), "-", "the figures to collect (default: every figure of the kind; see docs/studies.md)", _Figures()
    )
    t: float | None = key(
        "float",
        None,
        "s",
        "simulated time (default: the scene's world.t_end; the pit: 4 s)",
        DURATION,
        read_when=("kind", ("run", "pit")),
    )
    steps: int | None = key(
        "int", None, "-", "time steps, instead of t", Interval(1, 1_000_000_000), read_when=("kind", ("run",))
    )
    until: str = key(
        "str",
        "",
        "-",
        "stop early once every ball is at rest (rest) or every tracked ball has landed (landed); empty: run on",
        OneOf(("", "rest", "landed")),
        read_when=("kind", ("run",)),
    )
    save: bool = key(
        "bool",
        True,
        "-",
        "save each task's final state in the study folder (runs/ID.npz)",
        read_when=("kind", ("run",)),
    )
    shots: int = key(
        "int", 1000, "-", "shots of the player's spread", Interval(2, 10_000_000), read_when=("kind", ("dispersion",))
    )
    tour: str = key(
        "str",
        "PGA",
        "-",
        "the rows of the TrackMan table flown",
        OneOf(("PGA", "LPGA", "all")),
        read_when=("kind", ("tour",)),
    )
    balls: int | None = key(
        "int",
        None,
        "-",
        "balls of the scene's random block (run; its box widened or narrowed so that it is as tall) or of the "
        "pit (default: the scene's)",
        Interval(16, 50_000_000),
        read_when=("kind", ("run", "pit")),
    )
    gpu: bool = key("bool", False, "-", "run on a worker with a GPU (Dask resource GPU = 1), on CUDA")
    precision: str = key("str", "f64", "-", "float precision of the task's kernels", OneOf(("f32", "f64")))


@dataclass(frozen=True)
class Random:
    """``[random]``: points drawn uniformly from ``[random.uniform]``'s ranges."""

    samples: int = key("int", 10, "-", "points drawn", Interval(1, MAX_TASKS))
    seed: int = key("int", 0, "-", "seed of the draw", Interval(0, 2**63 - 1))


STUDY_KEYS = keys_of(Study)
TASK_KEYS = keys_of(Task)
RANDOM_KEYS = keys_of(Random)
VARY_TABLES = ("grid", "points", "random")
"""The ways of choosing the points: every combination, a list, or random samples."""


@dataclass(frozen=True)
class TaskSpec:
    """One task of a study: the point (varied keys and values), the seed and what it runs.

    ``scene`` is the base scene's path, ``changes`` the ``--set`` texts that make the task's scene
    (the study's ``set``, then the point's keys), so that ``ti-golf run SCENE --set CHANGE ...``
    runs the same scene alone."""

    id: str
    point: dict[str, Any]
    seed: int | None
    scene: str
    changes: tuple[str, ...]
    task: dict[str, Any]
    figures: FigureList

    def as_dict(self) -> dict[str, Any]:
        """Plain data, to send to a worker."""
        lists = {"changes": list(self.changes), "figures": list(self.figures)}
        return {**vars(self), "point": dict(self.point), "task": dict(self.task), **lists}


@dataclass(frozen=True)
class StudySpec:
    """A loaded, checked study: its file, base scene, varied keys and the tasks."""

    path: str
    name: str
    description: str
    scene: str
    keys: tuple[str, ...]
    tasks: tuple[TaskSpec, ...]
    task: Task
    figures: FigureList = field(default=())

    @property
    def gpu(self) -> bool:
        """Whether each task asks for a GPU (the ``[task]`` table's ``gpu``)."""
        return self.task.gpu


def resolve_study_path(name: str | os.PathLike[str]) -> Path:
    """A study file as given, or a bundled study's name (``scenes/studies/NAME.toml``)."""
    return resolve_scene_path(name, bundled_studies_dir())


def bundled_studies_dir() -> Path:
    """The folder of the bundled studies: ``studies/`` in the bundled scenes' folder."""
    return scenes_dir() / "studies"


def load_study(path: str | os.PathLike[str], overrides: Sequence[str] = ()) -> StudySpec:
    """Read and check a study file (a path or a bundled study's name), with ``overrides``
    (``--set``-style texts: ``task.KEY=VALUE`` changes the ``[task]`` table, any other is added to
    the study's ``set``), and expand it into its tasks; a ConfigError names the file (or
    ``--set``), the key and what is allowed."""
    p = resolve_study_path(path)
    doc = read_toml(p)
    source = str(p)
    top = {k: v for k, v in doc.items() if k not in ("task", *VARY_TABLES)}
    for name in top:
        if name not in STUDY_KEYS:
            raise_config(source, name, f"is not a study key; allowed: {', '.join([*STUDY_KEYS, 'task', *VARY_TABLES])}")
    study = Study(**_checked(top, STUDY_KEYS, source, ""))
    task_doc = doc.get("task", {})
    if not isinstance(task_doc, dict):
        raise_config(source, "task", "must be a table [task]")
    task_doc = dict(task_doc)
    scene_overrides, cli_task = [], set()
    for text in overrides:
        dotted, value = parse_override(text)
        if dotted.startswith("task."):
            if dotted[5:] not in TASK_KEYS:
                raise_config(OVERRIDES, dotted, f"is not a task key; allowed: {', '.join(TASK_KEYS)}")
            task_doc[dotted[5:]] = value
            cli_task.add(dotted[5:])
        else:
            scene_overrides.append(text)
    task = _task(task_doc, source, cli_task)
    given = [name for name in VARY_TABLES if name in doc]
    if len(given) > 1:
        raise_config(source, given[1], f"give one of [grid], [[points]] and [random], not {given[0]} and {given[1]}")
    base = _base_scene(study, task, p)
    fixed, file_keys, cli_keys = _fixed_changes(study.set, scene_overrides, source)
    how = given[0] if given else None
    points = _points(doc, how, source)
    timed = task.t is not None or task.steps is not None
    refuse_unread(task.kind, timed, points, how, file_keys, cli_keys, source)
    seeds = _seeds(study, task, source)
    n = len(points) * len(seeds)
    if n > MAX_TASKS:
        raise_config(source, given[0] if given else "seeds", f"gives {n:,} tasks; at most {MAX_TASKS:,} are allowed")
    figures = task.figures or default_figures(task.kind)
    for name in figures:
        if task.kind not in FIGURES[name].kinds:
            kinds = ", ".join(FIGURES[name].kinds)
            raise_config(
                source, "task.figures", f"{name!r} is not a figure of task.kind = {task.kind!r} (it is of {kinds})"
            )
    task_dict = {k: getattr(task, k) for k in TASK_KEYS if k != "figures"}
    tasks = []
    keys: list[str] = []
    fixed_keys = {parse_override(text)[0] for text in fixed}
    for point in points:
        for dotted in point:
            if dotted in fixed_keys:  # the point's value would replace it: the set value would have no effect
                where = (source, f"set: {dotted}") if dotted in file_keys - cli_keys else (OVERRIDES, dotted)
                raise_config(
                    *where, f"is varied by the study's [{given[0]}]: a value set for every task would have no effect"
                )
            if dotted not in keys:
                keys.append(dotted)
        changes = fixed + tuple(f"{k}={_toml(v)}" for k, v in point.items())
        how = given[0] if given else "set"
        scene_doc = _check_scene(base, changes, source, point, how, task, file_keys, seeded=study.seeds is not None)
        for seed in seeds:
            ident = task_id(scene_doc, seed, task_dict, figures)
            tasks.append(TaskSpec(ident, dict(point), seed, base, changes, task_dict, tuple(figures)))
    return StudySpec(
        path=source,
        name=p.stem,
        description=study.description,
        scene=base,
        keys=tuple(keys),
        tasks=tuple(tasks),
        task=task,
        figures=tuple(figures),
    )


def _checked(values: Mapping[str, Any], keys: Mapping[str, Key], source: str, table: str) -> dict[str, Any]:
    out = {}
    for name, value in values.items():
        dotted = f"{table}.{name}" if table else name
        out[name] = check_value(value, keys[name], source, dotted)
    return out


def _task(doc: Mapping[str, Any], source: str, from_cli: set[str]) -> Task:
    """The ``[task]`` table ``doc`` checked; an error names ``--set`` for the keys ``from_cli``."""
    for name in doc:
        if name not in TASK_KEYS:
            raise_config(source, f"task.{name}", f"is not a task key; allowed: {', '.join(TASK_KEYS)}")
    _checked({name: doc[name] for name in from_cli}, TASK_KEYS, OVERRIDES, "task")
    task = Task(**_checked(doc, TASK_KEYS, source, "task"))
    for name in doc:
        k = TASK_KEYS[name]
        if k.read_when is not None and getattr(task, k.read_when[0]) not in k.read_when[1]:
            where = OVERRIDES if name in from_cli else source
            raise_config(where, f"task.{name}", f"is read only when {read_when_text(k, 'task')}")
    if task.t is not None and task.steps is not None:
        where = OVERRIDES if {"t", "steps"} & from_cli else source
        raise_config(where, "task.steps", "give task.t or task.steps, not both")
    return task


def _base_scene(study: Study, task: Task, path: Path) -> str:
    """The base scene's path (a file beside the study, or a bundled scene)."""
    if task.kind == "pit":
        if study.scene not in ("", "ball_pit"):
            raise_config(str(path), "scene", f"the pit benchmark pours the bundled ball_pit (got {study.scene!r})")
        return "ball_pit"
    if not study.scene:
        raise_config(str(path), "scene", "is required: a scene file or a bundled scene's name")
    beside = path.parent / study.scene
    if beside.exists() and beside.is_file():
        return str(beside.resolve())
    try:
        found = resolve_scene_path(study.scene)
    except ConfigError as exc:  # (a bare name that no bundled scene has: the reason hints at the closest)
        raise_config(str(path), "scene", f"no scene file {study.scene!r} beside the study: {exc.reason}")
    if not found.is_file():
        raise_config(
            str(path), "scene", f"no scene file {study.scene!r} beside the study, nor a bundled scene of that name"
        )
    return str(found.resolve())


def _grid_points(table: Any, source: str) -> list[dict[str, Any]]:
    """The points of a ``[grid]``: every combination of its keys' values, each value once."""
    if not isinstance(table, dict) or not table:
        raise_config(source, "grid", "must be a table of scene keys, each with its values (a list or START:STOP:STEP)")
    axes = {name: _values(name, value, source) for name, value in table.items()}
    n = math.prod(len(values) for values in axes.values())
    if n > MAX_TASKS:  # (before the combinations are made)
        raise_config(source, "grid", f"gives {n:,} tasks; at most {MAX_TASKS:,} are allowed")
    for name, values in axes.items():
        seen: set[str] = set()  # (a set: an axis may hold 100,000 values)
        for v in values:
            if repr(v) in seen:
                raise_config(source, f"grid.{name}", f"holds the value {_toml(v)} twice")
            seen.add(repr(v))
    return [dict(zip(axes, combo)) for combo in itertools.product(*axes.values())]


def _listed_points(table: Any, source: str) -> list[dict[str, Any]]:
    """The points of ``[[points]]``, each given once (a point given again is the same task twice)."""
    if not isinstance(table, list) or not table or not all(isinstance(t, dict) for t in table):
        raise_config(source, "points", "must be an array of tables [[points]], each a scene key = value per key")
    out: list[dict[str, Any]] = []
    for i, point in enumerate(table):
        if not point:
            raise_config(source, f"points[{i}]", "names no scene key")
        out.append({name: _one(name, value, source, f"points[{i}].{name}") for name, value in point.items()})
        if out[-1] in out[:-1]:
            raise_config(source, f"points[{i}]", f"is points[{out.index(out[-1])}] again")
    return out


def _points(doc: Mapping[str, Any], how: str | None, source: str) -> list[dict[str, Any]]:
    """The points of the study: dicts of dotted scene key -> value."""
    if how is None:
        return [{}]
    table = doc[how]
    if how == "grid":
        return _grid_points(table, source)
    if how == "points":
        return _listed_points(table, source)
    if not isinstance(table, dict):
        raise_config(source, "random", "must be a table [random] with samples, seed and [random.uniform]")
    uniform = table.get("uniform")
    for name in table:
        if name != "uniform" and name not in RANDOM_KEYS:
            raise_config(
                source, f"random.{name}", f"is not a key of [random]; allowed: {', '.join(RANDOM_KEYS)}, uniform"
            )
    settings = Random(**_checked({k: v for k, v in table.items() if k != "uniform"}, RANDOM_KEYS, source, "random"))
    if not isinstance(uniform, dict) or not uniform:
        raise_config(source, "random.uniform", "must be a table of scene keys, each with its range [low, high]")
    ranges = {}
    for name, value in uniform.items():
        _scene_key(name, source, f"random.uniform.{name}")
        if (
            not isinstance(value, list)
            or len(value) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)
            or value[0] > value[1]
        ):
            raise_config(
                source, f"random.uniform.{name}", f"must be [low, high], two numbers with low <= high (got {value!r})"
            )
        ranges[name] = (float(value[0]), float(value[1]))
    if settings.samples > 1 and all(lo == hi for lo, hi in ranges.values()):
        raise_config(source, "random.uniform", "draws the same task every time: each of its ranges is one value")
    rng = random.Random(settings.seed)
    return [{name: rng.uniform(lo, hi) for name, (lo, hi) in ranges.items()} for _ in range(settings.samples)]


def _scene_key(dotted: str, source: str, where: str) -> Key:
    """The scene key ``dotted`` names (a study varies only keys of the scene's tables, and of its
    ``[[...]]`` tables by index: ``blocks[0].number``)."""
    key = key_of(dotted)
    if key is None:
        raise_config(source, where, "is not a scene key (see `ti-golf keys`)")
    return key


def _values(name: str, value: Any, source: str) -> list[Any]:
    """The values of one grid axis: a list of values, or a START:STOP:STEP / a,b,c string of numbers."""
    k = _scene_key(name, source, f"grid.{name}")
    if isinstance(value, str) and k.kind in ("float", "int"):
        return [_one(name, v, source, f"grid.{name}") for v in parse_range(value, source, f"grid.{name}")]
    if not isinstance(value, list) or not value:
        raise_config(source, f"grid.{name}", f"must be a list of values or START:STOP:STEP (got {value!r})")
    return [_one(name, v, source, f"grid.{name}") for v in value]


def _one(name: str, value: Any, source: str, where: str) -> Any:
    """One value of a varied key, checked as a scene file's value is, as plain data."""
    k = _scene_key(name, source, where)
    if k.kind == "int" and isinstance(value, float) and value.is_integer():
        value = int(value)
    checked = check_value(value, k, source, where)
    return list(checked) if isinstance(checked, tuple) else checked


def _fixed_changes(
    file_set: Sequence[str], cli_set: Sequence[str], source: str
) -> tuple[tuple[str, ...], frozenset[str], frozenset[str]]:
    """The changes every task makes (the study file's ``set``, each key once, then the command
    line's ``--set``, which replaces the file's value of a key it gives), with the keys each gave."""
    file_keys = [_file_override(text, source)[0] for text in file_set]
    twice = next((key for i, key in enumerate(file_keys) if key in file_keys[:i]), None)
    if twice is not None:
        raise_config(source, f"set: {twice}", "is given twice: give it once")
    cli_keys = frozenset(parse_override(text)[0] for text in cli_set)
    fixed = tuple(t for t, key in zip(file_set, file_keys) if key not in cli_keys) + tuple(cli_set)
    return fixed, frozenset(file_keys), cli_keys


def _file_override(text: str, source: str) -> tuple[str, Any]:
    """:func:`parse_override` of one text of the study file's ``set``, its errors naming the file
    and ``set`` (they named ``--set``, which the command line was not given)."""
    try:
        return parse_override(text)
    except ConfigError as exc:
        raise_config(source, f"set: {text}", exc.reason)


def _seeds(study: Study, task: Task, source: str) -> list[int | None]:
    if study.seeds is None:
        return [None]
    if task.kind not in ("run", "dispersion", "pit"):
        raise_config(
            source, "seeds", f"task.kind = {task.kind!r} draws nothing at random; seeds are for run, dispersion, pit"
        )
    out: list[int | None] = []
    for s in study.seeds:
        if not (s.is_integer() and 0 <= s < 2**31):
            raise_config(source, "seeds", f"must be whole numbers in [0, 2147483647] (got {s:g})")
        out.append(int(s))
    if len(set(out)) != len(out):
        raise_config(source, "seeds", "lists a seed twice")
    return out


def _check_scene(
    base: str,
    changes: tuple[str, ...],
    source: str,
    point: Mapping[str, Any],
    how: str,
    task: Task,
    file_keys: frozenset[str] = frozenset(),
    seeded: bool = False,
):
    """The task's scene as a document (for its id), built now so that a bad value fails before
    anything runs; a loader's error names the study file and its table, or ``--set``."""
    try:
        scene = load_scene(base, changes)
    except ConfigError as exc:
        if exc.key in point:
            table = {"grid": "grid", "points": "points", "random": "random.uniform"}[how]
            raise ConfigError(source, f"{table}.{exc.key}", f"{exc.reason} (at {_point_text(point)})") from None
        if exc.source == OVERRIDES:
            in_file = exc.key in file_keys
            raise ConfigError(
                source if in_file else OVERRIDES, f"set: {exc.key}" if in_file else exc.key, exc.reason
            ) from None
        raise ConfigError(source, "scene", str(exc)) from None
    needs = scene_problem(task.kind, task.until, scene)
    if needs is not None:
        raise_config(source, *needs)
    random_blocks = sum(b.kind == "random" for b in scene.blocks)
    problem = scaled_block_problem(scene, task.balls) if task.kind == "run" and task.balls is not None else None
    if problem is not None:
        raise_config(source, "task.balls", problem)
    if task.kind == "run" and seeded and not random_blocks:
        raise_config(source, "seeds", f"replace the seeds of the scene's random blocks; {scene.name!r} has none")
    return scene_document(scene)


def _point_text(point: Mapping[str, Any]) -> str:
    return ", ".join(f"{k} = {_toml(v)}" for k, v in point.items())


def _toml(value: Any) -> str:
    """A value as `--set` reads it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(_toml(v) for v in value) + "]"
    return str(value)


def study_json_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a study file."""
    value = {"description": "a scene key's value (see the scene schema)"}
    axis = {"anyOf": [{"type": "string"}, {"type": "array", "minItems": 1}]}
    props: dict[str, Any] = {name: key_schema(k) for name, k in STUDY_KEYS.items()}
    props["task"] = {
        "type": "object",
        "additionalProperties": False,
        "properties": {name: key_schema(k) for name, k in TASK_KEYS.items()},
    }
    props["grid"] = {
        "type": "object",
        "minProperties": 1,
        "description": "every combination: scene key -> a list of values or START:STOP:STEP",
        "additionalProperties": axis,
    }
    props["points"] = {
        "type": "array",
        "minItems": 1,
        "description": "a list of points: each a table of scene key -> value",
        "items": {"type": "object", "minProperties": 1, "additionalProperties": value},
    }
    random_props: dict[str, Any] = {name: key_schema(k) for name, k in RANDOM_KEYS.items()}
    random_props["uniform"] = {
        "type": "object",
        "minProperties": 1,
        "description": "scene key -> [low, high]: drawn uniformly",
        "additionalProperties": {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
    }
    props["random"] = {
        "type": "object",
        "additionalProperties": False,
        "required": ["uniform"],
        "properties": random_props,
    }
    return {
        "$schema": DIALECT,
        "$id": "https://ti-golf.invalid/study.schema.json",
        "title": "ti_golf study",
        "description": "A ti_golf study file (TOML): a base scene, the keys to vary, the task and its figures.",
        "type": "object",
        "additionalProperties": False,
        "not": {
            "anyOf": [
                {"required": ["grid", "points"]},
                {"required": ["grid", "random"]},
                {"required": ["points", "random"]},
            ]
        },
        "properties": props,
    }
