"""The study: what it declares and the data it makes, the jobs its sweeps run, the contests and
the numbers it compares, and the chapters' sections (06–07) as functions.

What a study declares and makes:

- :mod:`.study_files`: a study file read into a :class:`~.study_files.Study` (and the
  smoke-sized and redrawn studies derived from one); :mod:`.add_arm`: a new arm's robot and
  study files from its URDF;
- :mod:`.regions`: the IK region, its samples and the single-valuedness check;
- :mod:`.id_trajectories`: the ID trajectories and what a measured arm's sensors record;
- :mod:`.datasets`: the data set files, written once and reused while their inputs hold;
  :mod:`.shifted`: the shifted test population, declared before it is drawn.

Its sweeps and contests:

- :mod:`.jobs`, :mod:`.sweep_files` and :mod:`.sweep`: the library jobs a sweep runs, the
  sweep files, and the running of their cells;
- :mod:`.contest`: the learned-IK and learned-ID contests' rules (who competes, with what
  budget, who is pruned); :mod:`.configurations`: a sweep's configurations as a table;
- :mod:`.chosen_models` and :mod:`.replicates`: the chosen models' store and the seeds behind
  each; :mod:`.training_setup`: chapter 6's data and sweeps.

Its numbers:

- :mod:`.statistics`: the spreads of compared numbers; :mod:`.rows`: every method's held-out
  errors as rows with intervals; :mod:`.paired`: paired comparisons; :mod:`.verdicts` and
  :mod:`.verdict_rows`: the verdict and the targets; :mod:`.result_tables`: the published
  tables' files, one reader;
- :mod:`.tested_models`: what chapter 7 tests, loaded once; :mod:`.ablation`: what an
  encoding gives before any learning.

The chapters' sections: :mod:`.ik_contest_report`, :mod:`.ik_chosen_report`,
:mod:`.id_comparison_report`, :mod:`.id_contest_report`, :mod:`.id_chosen_report` and
:mod:`.training_summary` (chapter 6); :mod:`.ik_test_report`, :mod:`.ik_places_report`,
:mod:`.warm_start`, :mod:`.id_test_report` and :mod:`.measured_test` (chapter 7). The prose
the abstract, the index and the conclusion read is :mod:`nfarm.publishing`'s.

Imports every layer below; :mod:`nfarm.publishing` is above it.
"""
