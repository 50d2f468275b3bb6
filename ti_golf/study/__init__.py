"""Parameter studies: a scene's keys varied over a grid, a list or random samples, each point run as a
task on Dask (a local cluster or a scheduler joined), the figures collected into one table.

The command is ``ti-golf study`` (:mod:`ti_golf.cli.study`); the how-to is docs/studies.md. Dask
and pyarrow are the optional extra ``ti-golf[cluster]``: this package imports them only when a
study runs.
"""

from ti_golf.study.runner import StudyResult, run_study
from ti_golf.study.spec import StudySpec, load_study

__all__ = ["StudyResult", "StudySpec", "load_study", "run_study"]
