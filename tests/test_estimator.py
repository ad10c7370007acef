"""The learners' shared plumbing (nfarm.learning.estimator): parameters from __init__'s
signature, set_params refusing unknown names, a repr of what differs from the defaults, and
one line for a learner used before it was fitted — the same for every learner."""

from __future__ import annotations

import numpy as np
import pytest

from nfarm.learning.anfis import ANFIS, ANFISMulti
from nfarm.learning.baselines import MLPID
from nfarm.learning.ik_rivals import MLPRival
from nfarm.learning.learned import Baseline, LearnedIK
from nfarm.learning.learned_id import LearnedID

LEARNERS = [(ANFIS, {"n_mfs": 3}), (ANFISMulti, {"n_mfs": 3}), (LearnedIK, {"encoding": "arm_plane", "n_mfs": 3}),
            (LearnedID, {"inputs": "affine", "epochs": 5}), (MLPID, {"hidden": [8]}),
            (Baseline, {"kind": "rbf"}), (MLPRival, {"hidden": [8]})]


@pytest.mark.parametrize("cls, changed", LEARNERS, ids=lambda x: getattr(x, "__name__", ""))
def test_every_learner_has_the_same_plumbing(cls, changed):
    model = cls()
    assert repr(model) == f"{cls.__name__}()"                       # defaults are not shown
    params = model.get_params()
    assert cls(**params).get_params() == params                      # the parameters rebuild it
    assert model.set_params(**changed) is model
    assert all(model.get_params()[k] == v for k, v in changed.items())
    assert repr(model) == f"{cls.__name__}({', '.join(f'{k}={v!r}' for k, v in changed.items())})"
    with pytest.raises(ValueError, match=rf"unknown parameter 'colour' for {cls.__name__}; valid: "):
        model.set_params(colour=1)
    assert all(model.get_params()[k] == v for k, v in changed.items())     # nothing changed
    with pytest.raises(ValueError, match=rf"^this {cls.__name__} is not fitted yet: call fit"):
        model._check_fitted()


def test_options_passed_on_are_checked_against_the_learner_they_go_to():
    with pytest.raises(ValueError, match=r"unknown parameter 'n_mf' for LearnedIK; valid: encoding, joint_options, "
                                         r"max_out_of_plane, .*n_mfs"):
        LearnedIK().set_params(n_mf=3)


def test_a_loadable_learner_says_so_when_not_fitted():
    with pytest.raises(ValueError, match=r"this LearnedIK is not fitted yet: call fit or load"):
        LearnedIK().predict(np.eye(4))
