"""The seeds behind a published model: a chosen model that chapter 6 copies where chapters 7 and 8
read it (``build/models/<robot>/…``) keeps, beside it, the sweep cells that train its configuration
on every seed the sweep ran (``seeds.json``: each seed a draw of the training and validation data
and of the initialisation). A held-out test then judges every seed's model on the same test
units, and :func:`nfarm.study.statistics.bootstrap_seeds` resamples the seeds as well as the
units, so that an interval covers what varies between trainings, not only the test draw.

The models themselves are not copied: :func:`seed_models` asks each cell's job for its model
(:func:`nfarm.study.jobs.contest_model`, ``id_model``, ``id_contest_model``), which reuses the one
the sweep trained (or trains it the way the cell does, if it is gone).

Example:
    >>> import tempfile
    >>> where = tempfile.mkdtemp()
    >>> cells = [{"study_file": "params/studies/intelbot5.yaml", "seed": s} for s in (0, 1, 2)]
    >>> _ = write_seeds(where, "learned_id", cells)
    >>> job, read = read_seeds(where)
    >>> job, [c["seed"] for c in read]
    ('learned_id', [0, 1, 2])
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..infra.arguments import check_choice, is_integer
from ..infra.paths import atomic_path
from ..infra.reading import ParamsError, Validator, load_json, show
from . import jobs

__all__ = ["SEEDS_FILE", "MODEL_OF", "write_seeds", "read_seeds", "seed_models"]

#: The file beside a published model that lists its configuration's cells over the seeds.
SEEDS_FILE = "seeds.json"
#: The jobs whose cells train a model, and the function that gives a cell's model.
MODEL_OF = {"ik_contest": jobs.contest_model, "learned_id": jobs.id_model, "id_contest": jobs.id_contest_model,
            "id_baseline": jobs.id_baseline_model}


def write_seeds(directory: str | os.PathLike, job: str, cells: Sequence[Mapping[str, Any]]) -> Path:
    """Write ``directory/seeds.json``: the ``job``'s ``cells`` (sweep-cell parameters, one per
    seed, each with a distinct whole-number ``seed``), ordered by seed, atomically.

    Raises:
        ValueError: an unknown job, no cells, a cell without a whole-number seed or two cells of one seed.
    """
    check_choice("job", job, MODEL_OF)
    seeds = [c.get("seed") for c in cells]
    if not cells or not all(is_integer(s, numpy=False) and s >= 0 for s in seeds) \
            or len(set(seeds)) != len(seeds):
        raise ValueError(f"cells must be one or more, each with a distinct whole-number seed >= 0, got seeds {seeds}")
    ordered = sorted((dict(c) for c in cells), key=lambda c: c["seed"])
    path = Path(directory) / SEEDS_FILE
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps({"job": job, "cells": ordered}, indent=1, sort_keys=True, default=str) + "\n",
                       encoding="utf-8")
    return path


def read_seeds(directory: str | os.PathLike) -> tuple[str, list[dict]]:
    """The job and the cells (ordered by seed) of ``directory/seeds.json``.

    Raises:
        ParamsError: the file is missing or damaged (one line, naming the file and the field).
    """
    path = Path(directory) / SEEDS_FILE
    data = load_json(path, what="seeds file")
    v = Validator(str(path))
    v.mapping(data, "", {"job": True, "cells": True})
    job = v.choice(data["job"], "job", tuple(MODEL_OF))
    cells = v.sequence(data["cells"], "cells", min_len=1, max_len=1000)
    for k, cell in enumerate(cells):
        if not isinstance(cell, dict):
            v.fail(f"cells[{k}]", f"must be a mapping of a cell's parameters, got {show(cell)}")
        v.integer(cell.get("seed"), f"cells[{k}].seed", lo=0)
    seeds = [c["seed"] for c in cells]
    if seeds != sorted(set(seeds)):
        v.fail("cells", f"must hold distinct seeds in increasing order, got {seeds}")
    return job, cells


def seed_models(directory: str | os.PathLike) -> dict[int, Any]:
    """The models of ``directory``'s configuration on every seed listed in its ``seeds.json``,
    by seed: the sweep's own (reused), each loadable and predicting as the published one does.

    Raises:
        ParamsError: no or a damaged ``seeds.json``.
    """
    job, cells = read_seeds(directory)
    try:
        return {cell["seed"]: MODEL_OF[job](cell) for cell in cells}
    except ParamsError as exc:
        raise ParamsError(f"{Path(directory) / SEEDS_FILE}: {exc}") from None
