"""Learners: fuzzy partitions (:mod:`.fuzzy`), ANFIS with Jang's hybrid rule (:mod:`.anfis`)
and Jang's benchmark problems (:mod:`.jang`), learned inverse kinematics (:mod:`.learned`) and
dynamics (:mod:`.learned_id`) behind one estimator per task, what both share
(:mod:`.per_joint`) and the cache of fitted models (:mod:`.model_cache`), the pose encodings the learned IK and its baselines
share (:mod:`.encoding`), the feature bases a model-free learner may use (:mod:`.bases`), the
learned IK's rivals (:mod:`.ik_rivals`, on :mod:`.ik_rival_base`) and the scikit-learn baselines of
the learned ID (:mod:`.baselines`, on :mod:`.id_baseline_base` and :mod:`.baseline_parts`): one class
per learner, registered under the name sweep files give it. Every learner has the plumbing of
:mod:`.estimator` (parameters, ``repr``, the fitted check, saving into a directory, the registries).

Imports :mod:`nfarm.solvers`, :mod:`nfarm.model` and :mod:`nfarm.infra` only.
"""
