"""Studies: many cases of one model, run in parallel on Dask and resumable (studies/).

- :mod:`flexmvm.studies.runner`: :class:`Case`, :func:`run_cases` (each finished case stored
  at once in ``DIR/cases/<key>.json``; a rerun resumes), :func:`collect`.
- :mod:`flexmvm.studies.search`: :func:`smallest_passing`, the fewest-DOF model that reaches
  a target score, by a search per family (node selection or interface patch set) over its
  mode counts; :func:`brute_force`.
"""

from flexmvm.studies.runner import Case, collect, run_cases
from flexmvm.studies.search import Candidate, brute_force, smallest_passing

__all__ = ["Candidate", "Case", "brute_force", "collect", "run_cases", "smallest_passing"]
