"""The study: what it declares and the data it makes, the jobs its sweeps run, and the numbers
it compares.

- :mod:`.study_files`: a study file read into a :class:`~.study_files.Study` (and the
  smoke-sized and redrawn studies derived from one);
- :mod:`.regions`: the IK region, its samples and the single-valuedness check;
- :mod:`.id_trajectories`: the ID trajectories and what a measured arm's sensors record;
- :mod:`.datasets`: the data set files, written once and reused while their inputs hold;
- :mod:`.jobs`, :mod:`.sweep_files` and :mod:`.sweep`: the library jobs a sweep runs, the
  sweep files, and the running of their cells;
- :mod:`.statistics`: the spreads of compared numbers; :mod:`.summary`: every method's
  held-out errors; :mod:`.configurations`: reading a sweep's configurations (chapter 06).

Imports every layer below; :mod:`nfarm.publishing` is above it.
"""
