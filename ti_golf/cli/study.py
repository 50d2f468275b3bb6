"""``ti-golf study``: a parameter study of a scene on Dask, one row per task in a results table.

Exit codes: 0 every task finished ok; 1 some task failed (its error is in its row; the others
ran); 2 bad input, or Dask and pyarrow not installed; 130 stopped by Ctrl-C or SIGTERM after the
finished rows were written (a re-run finishes the study).
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from ti_golf.cli._common import check_plot, plot_help, refuse_without, set_option
from ti_golf.errors import ConfigError
from ti_golf.study.cluster import ADDRESS_ENV, check_workers, require_dask

if TYPE_CHECKING:
    from ti_golf.study.spec import StudySpec


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``study`` to ``ti-golf``'s subcommands."""
    p = sub.add_parser(
        "study",
        help="a parameter study on Dask: a scene's keys varied, each point a task, one results table",
        description="Run a study file's tasks on a local Dask cluster (one single-threaded worker per core, on "
        f"127.0.0.1 only) or on a running scheduler (--address or ${ADDRESS_ENV}); the rows go to DIR/results.parquet "
        "and DIR/results.csv. Run again to finish an interrupted study: finished tasks are skipped. Exit code 1 "
        "when a task failed, 2 on bad input, 130 when interrupted. Needs pip install 'ti-golf[cluster]'.",
    )
    p.add_argument("study", help="study file, or the name of a bundled study (scenes/studies/)")
    p.add_argument("--out", metavar="DIR", help="the study's folder (default: NAME_study in the current folder)")
    p.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    p.add_argument("--gpus", type=int, help="local GPU workers (default: one per GPU when the tasks ask for one)")
    p.add_argument(
        "--address",
        help=f"join this Dask scheduler (tcp://HOST:PORT, or a --scheduler-file JSON) instead (default: ${ADDRESS_ENV})",
    )
    set_option(p, "change a key of the base scene in every task, e.g. --set world.t_end=0.5 (repeatable)")
    p.add_argument("--plot", help=plot_help("a figure against the varied keys (lines for one, a heat map for two)"))
    p.add_argument("--figure", help="the column plotted (default: the first figure)")
    p.add_argument("--lines", action="store_true", help="two varied keys: one line per value of the second")


def cmd_study(args: argparse.Namespace) -> int:
    """Run the tasks of the study ``args.study`` not yet finished in its folder, on a Dask cluster,
    print where the table is and plot a figure (``--plot``); 1 when a task failed, else 0."""
    from ti_golf.study.plot import check_plottable, figure_columns, plot_study
    from ti_golf.study.runner import run_study
    from ti_golf.study.spec import load_study

    check_plot(args.plot)
    if not args.plot:
        refuse_without(args, {"figure": "--figure", "lines": "--lines"}, "--plot")
    if args.workers is not None:
        check_workers(args.workers)
    if args.gpus is not None and args.gpus < 0:
        raise ConfigError("--gpus", None, f"must be >= 0 (got {args.gpus})")
    spec = load_study(args.study, args.overrides)  # bad input before anything starts
    if args.gpus is not None and not spec.gpu:
        raise ConfigError("--gpus", None, f"has no effect: the tasks of {spec.name} ask for no GPU (task.gpu = false)")
    if args.lines and len(spec.keys) != 2:
        raise ConfigError(
            "--lines", None, f"draws one line per value of a second varied key; {spec.name} varies {len(spec.keys)}"
        )
    if args.plot:  # (before the tasks run: a long study would find these only at its end)
        check_plottable(spec.keys)
    if args.figure is not None:
        _check_figure(args.figure, spec)
    require_dask()
    result = run_study(spec, out=args.out, workers=args.workers, address=args.address, gpus=args.gpus)
    print(
        f"{spec.name}: {len(result.rows)} of {len(spec.tasks)} tasks in {result.folder}/results.parquet and "
        f"results.csv ({result.ran} run now, {result.skipped} finished before, {result.failed} failed)"
    )
    if args.plot and not any(row["status"] == "ok" for row in result.rows):  # (a failure, not bad input)
        print(f"no plot: no task of {spec.name} finished ok, so there is no figure to draw")
    elif args.plot:
        table = result.table
        column = args.figure or (figure_columns(table, spec.keys) or [""])[0]
        title = spec.description or spec.name
        if args.overrides:  # the plot says what the command changed, e.g. a smaller study's task.balls
            title += "\n" + ", ".join(args.overrides)
        plot_study(table, spec.keys, column, args.plot, title=title, lines=args.lines)
        print(f"wrote {args.plot}")
    return 1 if result.failed else 0


def _check_figure(column: str, spec: StudySpec) -> None:
    """``--figure`` names a column that the study's figures give (a tour's per club: ``carry_m[PGA
    Driver]``); else a :class:`ConfigError` listing them."""
    from ti_golf.golf.trackman import TOURS
    from ti_golf.study.figures import FIGURES

    columns = [FIGURES[f].column for f in spec.figures]
    if spec.task.kind == "tour":  # (a column per club and figure)
        columns = [f"{c}[{row.name}]" for c in columns for row in TOURS[spec.task.tour]]
    if column not in columns:
        raise ConfigError(
            "--figure", None, f"is not a figure of {spec.name} (got {column!r}); its figures: {', '.join(columns)}"
        )
