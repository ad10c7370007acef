"""Learners: fuzzy partitions (:mod:`.fuzzy`), ANFIS with Jang's hybrid rule (:mod:`.anfis`)
and Jang's benchmark problems (:mod:`.jang`), learned inverse kinematics (:mod:`.learned`) and
dynamics (:mod:`.learned_id`) behind one estimator per task, what both share
(:mod:`.per_joint`) and the cache of fitted models (:mod:`.model_cache`), the pose encodings the learned IK and its baselines
share (:mod:`.encoding`), the feature bases a model-free learner may use (:mod:`.bases`), and
the scikit-learn baselines it is compared with (:mod:`.baselines`). Every learner has the
plumbing of :mod:`.estimator` (parameters, ``repr``, the fitted check, saving into a directory).

Imports :mod:`nfarm.solvers`, :mod:`nfarm.model` and :mod:`nfarm.infra` only.
"""
