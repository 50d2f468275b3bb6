"""Writing output files whole or not at all; the formats a plot is written in."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ti_golf.errors import ConfigError


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path beside ``path`` to write to; renamed onto ``path`` when the block ends
    without an error, removed otherwise, so ``path`` is never left half-written. An OSError that
    names no file, or only the temporary one (a full disk), is raised again naming ``path``."""
    target = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=target.suffix, dir=target.parent or ".")
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # as a file opened for writing gets, not mkstemp's 0600
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and exc.errno is not None and exc.filename in (None, tmp, Path(tmp)):
            raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from exc
        raise


def write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def _umask() -> int:
    """The process's file-creation mask (read by setting it and putting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


PLOT_FORMATS = ("png", "svg", "pdf", "eps")
"""The formats a plot is written in, chosen by the file's suffix (the report's figures are EPS)."""

PLOT_FORMATS_HELP = "PNG, SVG, PDF or EPS by the file's extension (.png, .svg, .pdf, .eps)"
"""How the ``--plot`` options' help names the formats."""


def plot_format(path: str | os.PathLike[str], option: str = "plot") -> str:
    """The format of a plot written to ``path``: its suffix, lower case (``png`` without one);
    a :class:`ConfigError` naming ``option`` and the allowed extensions for any other suffix."""
    suffix = Path(path).suffix.lower()
    fmt = suffix[1:] if suffix else "png"
    if fmt not in PLOT_FORMATS:
        allowed = ", ".join(f".{f}" for f in PLOT_FORMATS)
        raise ConfigError(option, None, f"cannot write a plot as {suffix!r} ({str(path)!r}): use {allowed}")
    return fmt


def write_problem(folder: str | os.PathLike[str]) -> str | None:
    """Why no file can be made in ``folder`` (the OS's words), or None: a temporary file made
    and removed there is the one sure test (permission bits say yes to root where the file system,
    read-only or immutable, says no)."""
    try:
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".ti-golf-check-"):
            pass
    except OSError as exc:
        return exc.strerror or str(exc)
    return None
