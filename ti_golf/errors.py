"""Exceptions that reach the user as one clear line (the CLI turns them into exit code 2)."""

from __future__ import annotations

import os


def one_line(text: str) -> str:
    r"""``text`` on one line: line breaks and other control characters (from the user's input,
    quoted back) written as escapes (``\n``)."""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)


class TiGolfError(Exception):
    """Base class of every error ti_golf reports to a user without a traceback."""


class ConfigError(TiGolfError):
    """Bad scene or command-line input.

    Attributes:
        source: where the input came from: a file path, or the Python argument that gave it
            (``OVERRIDES``, ``"angles_deg"``), which the command line names by its option
            (``--set``, ``--angles``).
        key: the dotted scene key (``"air.gamma"``) or option at fault, or ``None`` for the whole file.
        reason: what is wrong and what is allowed.
    """

    def __init__(self, source: str, key: str | None, reason: str) -> None:
        self.source = str(source)
        self.key = key
        self.reason = reason
        where = f"{self.source}: " if self.source else ""
        what = f"key '{key}' " if key else ""
        super().__init__(one_line(f"{where}{what}{reason}"))


OVERRIDES = "overrides"
"""The source of an error about a scene key given beside the scene file rather than in it: the
``overrides`` of ``load_scene``, ``Simulation.from_scene`` and ``run_study``, and the changes of
``Simulation.set`` (``--set`` on the command line, which names it so)."""


class SimulationError(TiGolfError):
    """A simulation left the domain of finite numbers; ``balls`` names the offending ball ids."""

    def __init__(self, message: str, balls: list[int] | None = None) -> None:
        self.balls = list(balls or [])
        super().__init__(message)


def env_switch(name: str) -> bool:
    """Whether the on/off environment variable ``name`` is on: ``1`` on; ``0`` or unset (or empty)
    off; any other value a :class:`ConfigError` naming it, so that a mistyped switch is not quietly off."""
    value = os.environ.get(name, "")
    if value not in ("", "0", "1"):
        raise ConfigError(name, None, f"must be 1 (on) or 0 (off), not {value!r}")
    return value == "1"


def env_count(name: str) -> int | None:
    """The whole number >= 1 in the environment variable ``name``, or ``None`` when it is unset or
    empty; any other value a :class:`ConfigError` naming it."""
    value = os.environ.get(name, "")
    if not value:
        return None
    if not value.strip().isdigit() or int(value) < 1:
        raise ConfigError(name, None, f"must be a whole number >= 1, not {value!r}")
    return int(value)
