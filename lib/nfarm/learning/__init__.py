"""Learners: fuzzy partitions (:mod:`.fuzzy`), ANFIS with Jang's hybrid rule (:mod:`.anfis`)
and Jang's benchmark problems (:mod:`.jang`), learned inverse kinematics and dynamics behind
one estimator per task (:mod:`.learned`), the pose encodings the learned IK and its baselines
share (:mod:`.encoding`), the feature bases a model-free learner may use (:mod:`.bases`), and
the scikit-learn baselines it is compared with (:mod:`.baselines`). Every learner has the
plumbing of :mod:`.estimator` (parameters, ``repr``, the fitted check, saving into a directory).

Imports :mod:`nfarm.solvers`, :mod:`nfarm.model` and :mod:`nfarm.infra` only.
"""
