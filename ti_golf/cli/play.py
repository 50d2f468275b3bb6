"""``ti-golf play``: the golf game in the console (report §2.5, ``playGolfC``).

Before each stroke the player is told where the ball lies, how far and in which direction the hole
is, and the wind, and is asked for the stroke's direction, speed, loft and spin; the round goes on
until the ball is holed, goes out of bounds, the scene's ``game.max_strokes`` are played, or the
input ends. ``--shots FILE`` plays the strokes listed in a file instead (one per line:
``direction speed loft spin``, ``hole`` for the direction at the hole, ``#`` starts a comment);
``--gui`` plays in a window (:mod:`.game_gui`).
"""

from __future__ import annotations

import argparse
import csv
import math
import secrets
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

from ti_golf.cli._common import (
    check_plot,
    check_writable,
    given,
    plot_help,
    refuse_unread_keys,
    runtime_options,
    scene_options,
    seed_value,
    set_key,
)
from ti_golf.errors import ConfigError
from ti_golf.files import atomic_path
from ti_golf.game.rules import (
    SHOT_FIELDS,
    Field,
    GolfGame,
    Shot,
    Stroke,
    club,
    club_list,
    describe_round,
    describe_stroke,
    describe_wind,
)
from ti_golf.scene.loader import load_scene, scenes_dir
from ti_golf.scene.schema import Scene

DEFAULT_SCENE = "golf_hole"

GAME_UNREAD = {
    "description": "it is text for `ti-golf scenes`",
    "launch": "each stroke is the launch",
    "sweep": "`ti-golf sweep` reads it",
    "world.t_end": "a stroke runs to rest, at most game.shot_time",
    "world.t_max": "sweeps read it",
}
"""The scene keys (or tables) the game does not read, with why."""

PROMPT_DEFAULTS = {"spin": 0.0}
"""Fields whose prompt takes Enter for a fixed default (the direction's default is at the hole)."""


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``play`` subcommand to ``ti-golf``'s subparsers; returns its parser."""
    p = sub.add_parser("play", help="play golf on a course scene, stroke by stroke, until the ball is holed")
    scene_options(
        p,
        default=DEFAULT_SCENE,
        scene_help=f"a course: a scene with [terrain] and [hole] (default {DEFAULT_SCENE})",
        example="game.wind_max=0",
    )
    p.add_argument(
        "--seed",
        type=seed_value,
        default=None,
        help="seed of the random start (a course without game.start, or with --set game.start=) and of the winds "
        "(default: a new round every time, its seed printed)",
    )
    how = p.add_mutually_exclusive_group()
    how.add_argument(
        "--shots",
        metavar="FILE",
        help="play the strokes in FILE, one per line: 'direction speed loft [spin]' (deg, km/h, deg, rpm) or "
        "'direction club' (a club's speed, loft and spin); 'hole' aims at the hole, # starts a comment; "
        "a bundled round by its name (golf_hole_round, lab_course_round) from any folder",
    )
    how.add_argument(
        "--gui", action="store_true", help="play in a window: the course in 3-D, clubs and sliders, a camera to move"
    )
    p.add_argument("--out", help="write the round as CSV, one row per stroke (rewritten after every stroke)")
    p.add_argument("--plot", help=plot_help("a map of the course with every stroke's path at the end"))
    runtime_options(p)
    return p


def cmd_play(args: argparse.Namespace) -> int:
    """Play a round of ``args.scene``; 0 when it ends (holed, out of bounds, no strokes or input left)."""
    check_writable(args.out, "--out", (".csv",))
    if args.out and args.shots and Path(shots_file(args.shots)).resolve() == Path(args.out).resolve():
        raise ConfigError("--out", None, f"is the --shots file {args.out!r}: the round's CSV would replace its strokes")
    check_plot(args.plot)
    seed = args.seed if args.seed is not None else secrets.randbelow(2**31)  # (said, so a round can be played again)
    refuse_unread_keys(args.overrides, "play", GAME_UNREAD)
    scene = load_scene(args.scene, args.overrides)
    if scene.game.wind_max > 0 and any(set_key(text) == "air.wind" for text in args.overrides):
        raise ConfigError(
            "--set",
            "air.wind",
            "has no effect while game.wind_max > 0, which draws each stroke's wind: set it to 0 too",
        )
    if given(args, "seed") and not random_round(scene):
        raise ConfigError(
            "--seed", None, "has no effect: game.start places the ball and game.wind_max = 0 leaves the wind as it is"
        )
    game = GolfGame(scene, seed=seed)
    if args.gui:
        from ti_golf.game.window import check_display  # (GGUI and matplotlib: only for a window)

        check_display()  # (before the round's seed: no round is played without a window)
        _say_seed(game, seed)
        return _play_in_window(game, args)
    shots = file_shots(args.shots, game) if args.shots else _asked_shots(game, input, sys.stdin.isatty())
    hole = game.hole.position
    print(
        f"{game.scene.name}: a cup {2000 * game.hole.radius:.0f} mm across at x = {hole[0]:g} m, "
        f"z = {hole[1]:g} m; directions are degrees from +x toward +z"
    )
    _say_seed(game, seed)
    if not args.shots:
        print("Clubs: type a club's name at the speed prompt for its speed, loft and spin:")
        print("\n".join(club_list()))
    ended = "no more input"
    try:
        while not game.over:
            print(_lie(game))
            try:
                shot = next(shots)
            except StopIteration:
                break
            stroke = game.play(shot)
            print(describe_stroke(stroke))
            if args.out:
                write_csv(game.strokes, args.out)
    except KeyboardInterrupt:
        ended = "interrupted"
    return _finish(game, ended, args)


def random_round(scene: Scene) -> bool:
    """Whether a round of ``scene`` draws anything: a random start (no ``game.start``) or winds
    (``game.wind_max`` > 0)."""
    return scene.game.start is None or scene.game.wind_max > 0


def _say_seed(game: GolfGame, seed: int) -> None:
    """The round's seed, which plays its random start (a course without ``game.start``) and its
    winds (``game.wind_max`` > 0) again, and where such a course put the ball; nothing for a
    round that draws neither."""
    if not random_round(game.scene):
        return
    rules = game.scene.game
    drawn = [
        what for what, random in (("this start", rules.start is None), ("these winds", rules.wind_max > 0)) if random
    ]
    print(f"Round seed {seed}: --seed {seed} plays {' and '.join(drawn)} again.")
    if game.scene.game.start is None:
        print(
            f"The ball starts at a random point of the course: x = {_fixed(game.ball[0])} m, z = {_fixed(game.ball[2])} m."
        )


def _play_in_window(game: GolfGame, args: argparse.Namespace) -> int:
    """The round in a window (:mod:`.game_gui`), then the same summary and files as in the console."""
    from ti_golf.game.window import GolfWindow  # (GGUI and matplotlib: only for a window)

    ended = "window closed"
    try:
        GolfWindow(game, on_stroke=lambda _: write_csv(game.strokes, args.out) if args.out else None).run()
    except KeyboardInterrupt:
        ended = "interrupted"
    for stroke in game.strokes:
        print(f"Stroke {stroke.number}: {describe_stroke(stroke).strip()}")
    return _finish(game, ended, args)


def _finish(game: GolfGame, ended: str, args: argparse.Namespace) -> int:
    """The round's last line, then the files asked for; the exit code: 130 for a round that Ctrl-C
    ended unfinished (in the console or in a window), else 0."""
    print(describe_round(game, ended))
    if args.out:
        write_csv(game.strokes, args.out)
        print(f"wrote {args.out}")
    if args.plot:
        from ti_golf.game.course_map import plot_round  # (matplotlib: imported only to plot)

        plot_round(game, args.plot, title=f"{game.scene.name}: {describe_round(game, ended)}")
        print(f"wrote {args.plot}")
    return 130 if ended == "interrupted" and not game.over else 0


def _lie(game: GolfGame) -> str:
    """Where the ball lies, the hole and the wind, before a stroke."""
    dist, bearing = game.to_hole()
    return (
        f"Stroke {len(game.strokes) + 1}: the ball lies at x = {_fixed(game.ball[0])} m, z = {_fixed(game.ball[2])} m, "
        f"{dist:.2f} m from the hole (direction {_fixed(bearing, 1)} deg); {describe_wind(game.wind)}."
    )


def _fixed(value: float, digits: int = 2) -> str:
    """``value`` with ``digits`` decimals, and no "-0.00" for a value that rounds to zero."""
    return f"{round(float(value), digits) + 0.0:.{digits}f}"


def _asked_shots(game: GolfGame, ask: Callable[[str], str], interactive: bool) -> Iterator[Shot]:
    """Shots entered at the prompts, field by field (a club's name at the speed prompt gives its
    speed, loft and spin); a bad value is explained and asked again. Ends at the end of the
    input. Without a terminal (piped input) the answers are echoed."""
    last: dict[str, float] = {}
    while True:
        values: list[float] = []
        for f in SHOT_FIELDS:
            if len(values) == len(SHOT_FIELDS):
                break  # (a club gave the rest)
            default = _default(f.name, game, last)
            hint = f", Enter: {default:g}" if default is not None else ""
            if f.name == "direction" and default is not None:
                hint = f", Enter: at the hole, {default:.1f}"
            words = ", or a club" if f.name == "speed" else ", or 'hole'" if f.name == "direction" else ""
            while True:
                try:
                    text = ask(f"  {f.name} [{f.unit}, {f.low:g} to {f.high:g}{words}{hint}]: ").strip()
                except EOFError:
                    print()  # (the prompt's line)
                    return
                if not interactive:
                    print(text)
                if f.name == "speed" and club(text) is not None:
                    values.extend(club(text) or ())
                    break
                try:
                    values.append(_field_value(f, text, default, game, "input"))
                    break
                except ConfigError as exc:
                    print(f"  {f.name} {exc.reason}; try again")
        last = dict(zip((f.name for f in SHOT_FIELDS), values))
        yield Shot(*values)


def _default(name: str, game: GolfGame, last: dict[str, float]) -> float | None:
    """What Enter means at a prompt: at the hole for the direction (exactly, as 'hole' does; the
    prompt shows it rounded), no spin, else the last stroke's."""
    if name == "direction":
        return game.to_hole()[1]
    return last.get(name, PROMPT_DEFAULTS.get(name))


def _field_value(f: Field, text: str, default: float | None, game: GolfGame, source: str) -> float:
    """A field's value from its text, checked: Enter for its ``default``, ``hole`` for the direction
    at the hole, else a number in the field's range (the same error for any other text)."""
    if text == "" and default is not None:
        return default
    if f.name == "direction" and text.lower() == "hole":
        return game.to_hole()[1]
    return f.parse(text, source)


def shots_file(path: str) -> str:
    """A ``--shots`` file as given, or a bundled round's name (``golf_hole_round`` or
    ``golf_hole_round.txt``) looked up in the bundled scenes' folder (an installed copy has no
    ``scenes/`` of its own)."""
    p = Path(path)
    if p.exists() or p.parent != Path("."):
        return path
    for candidate in (scenes_dir() / p, scenes_dir() / f"{p}.txt"):
        if candidate.is_file():
            return str(candidate)
    return path


def file_shots(path: str, game: GolfGame) -> Iterator[Shot]:
    """The shots of a ``--shots`` file (a path, or a bundled round's name: :func:`shots_file`),
    checked line by line (errors name the file, line and field)."""
    path = shots_file(path)
    if Path(path).exists() and not Path(path).is_file() and not Path(path).is_dir():
        raise ConfigError(path, None, "is not a regular file")  # (a FIFO or a device: it could wait for ever)
    try:  # (worded as for the other files read: scenes, saved runs, studies)
        lines = Path(path).read_text(encoding="utf-8-sig").splitlines()
    except FileNotFoundError:
        rounds = ", ".join(sorted(f.stem for f in scenes_dir().glob("*_round.txt")))
        bare = Path(path).parent == Path(".")  # (a name: perhaps a bundled round's, misspelled)
        raise ConfigError(path, None, "file not found" + (f" (the bundled rounds: {rounds})" if bare else "")) from None
    except IsADirectoryError:
        raise ConfigError(path, None, "is a directory, not a file of shots") from None
    except OSError as exc:
        raise ConfigError(path, None, f"cannot be read ({exc.strerror or exc})") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(path, None, f"is not UTF-8 text (byte {exc.start})") from None
    parsed = []
    for number, line in enumerate(lines, 1):
        text = line.split("#", 1)[0].replace(",", " ").split()
        if not text:
            continue
        source = f"{path}:{number}"
        clubbed = club(text[1]) if len(text) >= 2 else None
        if clubbed is not None and len(text) > 2:
            raise ConfigError(
                source, None, f"a club gives speed, loft and spin: 'direction club', no more (got {line.strip()!r})"
            )
        if clubbed is not None:
            text = [text[0], *(f"{v:g}" for v in clubbed)]
        if len(text) not in (3, 4):
            raise ConfigError(
                source, None, f"a stroke is 'direction speed loft [spin]' or 'direction club' (got {line.strip()!r})"
            )
        for f, word in zip(SHOT_FIELDS, text):
            _field_value(f, word, None, game, source)  # (checked now: 'hole' is taken when the stroke is played)
        parsed.append(text + ["0"] * (4 - len(text)))

    def shots() -> Iterator[Shot]:  # (a direction 'hole' is taken from where the ball lies by then)
        for text in parsed:
            print("  " + " ".join(text))
            yield Shot(*(_field_value(f, word, None, game, path) for f, word in zip(SHOT_FIELDS, text)))

    return shots()


CSV_COLUMNS = (
    "stroke",
    "direction_deg",
    "speed_kmh",
    "loft_deg",
    "spin_rpm",
    "wind_x_mps",
    "wind_z_mps",
    "start_x_m",
    "start_z_m",
    "end_x_m",
    "end_y_m",
    "end_z_m",
    "carry_m",
    "distance_m",
    "outcome",
    "to_hole_m",
)


def write_csv(strokes: list[Stroke], path: str) -> None:
    """The round as CSV, one row per stroke (:data:`CSV_COLUMNS`), written whole or not at all."""
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as f:
        out = csv.writer(f, lineterminator="\n")
        out.writerow(CSV_COLUMNS)
        for s in strokes:
            out.writerow(
                [
                    s.number,
                    f"{s.shot.direction:g}",
                    f"{s.shot.speed:g}",
                    f"{s.shot.loft:g}",
                    f"{s.shot.spin:g}",
                    f"{s.wind[0]:.3f}",
                    f"{s.wind[2]:.3f}",
                    f"{s.start[0]:.3f}",
                    f"{s.start[2]:.3f}",
                    f"{s.end[0]:.3f}",
                    f"{s.end[1]:.3f}",
                    f"{s.end[2]:.3f}",
                    f"{s.carry:.3f}" if math.isfinite(s.carry) else "",  # (never came down: no carry)
                    f"{s.distance:.3f}",
                    s.outcome,
                    f"{s.to_hole:.3f}",
                ]
            )
