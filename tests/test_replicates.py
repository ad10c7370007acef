"""The seeds behind a published model (nfarm.study.replicates): written in seed order, read back,
each seed's model the one its sweep cell trains, and a damaged file refused in one line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from nfarm.infra.reading import ParamsError
from nfarm.study import replicates


def test_seeds_are_written_in_order_and_read_back(tmp_path):
    cells = [{"study_file": "s.yaml", "seed": s, "stride": 4} for s in (3, 0, 1)]
    path = replicates.write_seeds(tmp_path, "id_contest", cells)
    assert path == tmp_path / replicates.SEEDS_FILE
    job, read = replicates.read_seeds(tmp_path)
    assert job == "id_contest" and [c["seed"] for c in read] == [0, 1, 3] and read[0]["stride"] == 4


@pytest.mark.parametrize("job, cells, message", [
    ("learned_ik", [{"seed": 0}], "job must be one of ik_contest, learned_id, id_contest"),
    ("learned_id", [], "cells must be one or more"),
    ("learned_id", [{"seed": 0}, {"seed": 0}], r"distinct whole-number seed >= 0, got seeds \[0, 0\]"),
    ("learned_id", [{"seed": True}], "distinct whole-number seed"),
    ("learned_id", [{"stride": 4}], r"got seeds \[None\]"),
])
def test_bad_seeds_are_refused_before_anything_is_written(tmp_path, job, cells, message):
    with pytest.raises(ValueError, match=message):
        replicates.write_seeds(tmp_path, job, cells)
    assert not (tmp_path / replicates.SEEDS_FILE).exists()


@pytest.mark.parametrize("content, message", [
    ({"job": "learned_id"}, r"seeds.json: cells: "),
    ({"job": "forest", "cells": [{"seed": 0}]}, r"seeds.json: job: must be one of"),
    ({"job": "learned_id", "cells": [{"seed": 1}, {"seed": 0}]}, r"seeds.json: cells: must hold distinct seeds in "
                                                                  r"increasing order, got \[1, 0\]"),
    ({"job": "learned_id", "cells": [{"seed": -1}]}, r"seeds.json: cells\[0\].seed: must be >= 0"),
    ({"job": "learned_id", "cells": ["seed 0"]}, r"seeds.json: cells\[0\]: must be a mapping"),
])
def test_a_damaged_seeds_file_is_one_line(tmp_path, content, message):
    (tmp_path / replicates.SEEDS_FILE).write_text(json.dumps(content))
    with pytest.raises(ParamsError, match=message) as caught:
        replicates.read_seeds(tmp_path)
    assert "\n" not in str(caught.value)


def test_each_seeds_model_is_the_one_its_cell_trains(tmp_path):
    """A smoke id_contest finalist over two seeds: seed_models gives each seed's cell's model
    (the fitted one reused: its predictions to rounding, and two readings of it the same bits), and
    the seeds' models differ."""
    from nfarm.study.jobs import id_contest_model

    cell = {"study_file": "params/studies/intelbot5.yaml", "smoke": True, "stride": 4, "learner": "ridge",
            "options": {"residual": True, "alpha": 1.0}, "models_dir": str(tmp_path / "models")}
    cells = [{**cell, "seed": s} for s in (0, 1)]
    fitted = [id_contest_model(c) for c in cells]
    replicates.write_seeds(tmp_path / "published", "id_contest", cells)
    models = replicates.seed_models(tmp_path / "published")
    q = np.zeros((3, 5)) + 0.1
    for s, model in models.items():
        # The same coefficients; read back from JSON they are laid out afresh in memory, and NumPy's AVX-512 kernels
        # (which `make test` does not disable, as `make report` does) may then round a product's last bit otherwise
        # (seen: 2.2e-16 on an Intel Xeon). The chapters compare two models read back alike, bit for bit.
        np.testing.assert_allclose(model.predict(q, q, q), fitted[s].predict(q, q, q), rtol=0, atol=1e-14)
    reread = replicates.seed_models(tmp_path / "published")
    assert all(np.array_equal(reread[s].predict(q, q, q), m.predict(q, q, q)) for s, m in models.items())
    assert not np.array_equal(models[0].predict(q, q, q), models[1].predict(q, q, q))
