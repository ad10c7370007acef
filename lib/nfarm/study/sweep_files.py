"""Sweep files: a grid of runs of a library job or a notebook, read and validated into a
:class:`Sweep` of complete, identified cells (:mod:`nfarm.study.sweep` runs them).

A sweep file (YAML, ``params/sweeps/``; README "Running sweeps on a cluster") says what
runs — ``job:`` a library job of :mod:`nfarm.study.jobs`, or ``notebook:`` a notebook executed by
papermill — and over which parameters::

    name: smoke                    # the results' directory: build/sweeps/<name>/
    job: anfis_benchmark
    fixed: {problem: sinc, epochs: 5}
    grid: {n_mfs: [2, 3]}          # cartesian product of the lists ...
    cells:                         # ... with each of these cells (optional)
      - {mf: gbell}
      - {mf: gauss}
    seeds: [0]                     # one more axis, the parameter "seed"
    metrics: [check_rmse, rules]
    smoke: {fixed: {epochs: 2}}    # a smaller version (--smoke), replacing these fields

A file is read as study files are: the generic reader (:func:`nfarm.infra.typed.read_typed`)
reads it into a :class:`SweepFile` (every field's type and rule, unknown keys refused, the
``smoke`` section's fields too), then :func:`sweep_from_dict` checks the rules between fields and
against the job or notebook and expands the cells.

A cell's parameters are ``fixed``, then the cell's own, then the grid's and the seed (a grid
parameter may not be set anywhere else). A cell is identified by the SHA-256 of its job (or
notebook) and its complete parameters (:meth:`nfarm.study.jobs.Job.complete`: the job's
defaults filled in), so the same run is never done twice; at most :data:`MAX_CELLS` cells.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, replace
from typing import Annotated, Any, Optional

from ..infra.paths import PARAMS, project_path, shown_path
from ..infra.reading import ParamsError, Validator, json_ready, load_yaml, show
from ..infra.typed import CELL_TIMEOUT_S, TEXT, Length, Range, ReadBy, read_typed, section_keys
from .jobs import JOBS

__all__ = ["Sweep", "Cell", "SweepFile", "SmokeSection", "load_sweep", "sweep_from_dict", "SWEEPS", "MAX_CELLS"]

SWEEPS = PARAMS / "sweeps"
MAX_CELLS = 100_000

_RUNNER_SET = ("out_dir",)      # a notebook's parameters the runner sets itself



@dataclass(frozen=True)
class Cell:
    """One point of a sweep: its complete parameters and its key (the directory name)."""

    params: Mapping[str, Any]
    key: str


@dataclass(frozen=True)
class Sweep:
    """A validated sweep file (:func:`load_sweep`): what runs, its cells and metrics."""

    name: str
    source: str
    job: str | None
    notebook: str | None            # project-relative path
    metrics: tuple[str, ...]
    cells: tuple[Cell, ...]
    description: str = ""
    #: Seconds each cell may run (the file's ``cell_timeout_s``); ``None``: the runner's.
    timeout: float | None = None

    @property
    def target(self) -> str:
        return f"job {self.job}" if self.job else f"notebook {self.notebook}"

    @property
    def varying(self) -> list[str]:
        """The parameters whose values differ between cells, in the order of the first cell."""
        if not self.cells:
            return []
        first = self.cells[0].params
        return [k for k in first if any(canonical(c.params.get(k)) != canonical(first[k])
                                        for c in self.cells)]

    def restrict(self, **params) -> "Sweep":
        """The same sweep with ``params`` set in every cell (cells made equal merge): a chapter
        takes its own arm's cells, or sets a run's directories."""
        v = Validator(self.source)
        cells = _make_cells(v, self, [{**c.params, **params} for c in self.cells],
                            "restrict(...)")
        return replace(self, cells=cells)

    def select(self, keep: Callable[[Mapping[str, Any]], bool]) -> "Sweep":
        """The cells whose parameters ``keep`` accepts."""
        return replace(self, cells=tuple(c for c in self.cells if keep(c.params)))

    def with_cells(self, params: Iterable[Mapping[str, Any]], name: str | None = None) -> "Sweep":
        """The same sweep's job with these cells instead, each completed by the job's defaults
        and checked as a file's cells are, and every metric the job returns: a chapter's cells
        that no file lists (a model chosen on validation, trained over the seeds). ``name``: the
        results' directory (default: this sweep's)."""
        v = Validator(self.source)
        if name is not None:
            _check_sweep_name(v, name)
        sweep = replace(self, name=self.name if name is None else name,
                        metrics=JOBS[self.job].metrics if self.job else self.metrics)
        return replace(sweep, cells=_make_cells(v, sweep, list(params), "with_cells(...)"))


def canonical(value: Any) -> str:
    """``value`` as canonical JSON (keys sorted, no spaces): equal parameters, equal text."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"))


def _plain(v: Validator, value: Any, at: str) -> Any:
    """A parameter value: JSON types (numbers finite; mapping keys texts)."""
    try:
        value = json_ready(value)
    except ValueError:
        v.fail(at, f"must be a finite number, got {show(value)}")
    if isinstance(value, dict):
        for key, item in value.items():
            v.string(key, f"{at}: key")
            _plain(v, item, f"{at}.{key}")
    elif isinstance(value, list):
        for k, item in enumerate(value):
            _plain(v, item, f"{at}[{k}]")
    elif value is not None and not isinstance(value, (bool, int, float, str)):
        v.fail(at, f"must be a number, text, list or mapping, got {show(value)}")
    return value


def _parameters(v: Validator, value: Any, at: str) -> Mapping[str, Any]:
    """A mapping of parameter names (texts) to values."""
    if not isinstance(value, Mapping):
        v.fail(at, f"must be a mapping of parameters, got {show(value)}")
    for key in value:
        if not isinstance(key, str) or not key.isidentifier():
            v.fail(at, f"parameter names must be identifiers, got {show(key)}")
    return value


def _allowed(v: Validator, sweep: Sweep) -> Mapping[str, Any] | list[str]:
    if sweep.job:
        return JOBS[sweep.job].params
    from ..infra.notebook_runs import declared_parameters

    try:
        names = declared_parameters(project_path(sweep.notebook))
    except Exception as exc:  # noqa: BLE001 — ReportError: not a valid notebook
        v.fail("notebook", str(exc))
    return [n for n in names if n not in _RUNNER_SET]


def _check_name(v: Validator, sweep: Sweep, allowed, name: str, where: str) -> None:
    if name in _RUNNER_SET and not sweep.job:
        v.fail(f"{where}.{name}", "is set by the sweep runner (each cell writes to its own "
                                  "directory)")
    if name not in allowed:
        v.fail(f"{where}.{name}", f"unknown parameter of {sweep.target} (allowed: "
                                  f"{', '.join(allowed)})")


def _make_cells(v: Validator, sweep: Sweep, params: Iterable[Mapping], at: str,
                origin: Callable[[int, str], str] | None = None) -> tuple[Cell, ...]:
    """The cells of these parameter mappings, each completed by its job (:meth:`Job.complete`:
    defaults, kinds, normal form); equal completed parameters make one cell. ``origin(k,
    name)``: where in the file cell k's parameter ``name`` was given, for messages."""
    allowed = _allowed(v, sweep)
    cells: dict[str, Cell] = {}
    for k, given in enumerate(params):
        where = f"{at}[{k}]" if at.endswith("cells") else at
        for name in given:
            _check_name(v, sweep, allowed, name, where)
        if sweep.job:
            try:
                complete = JOBS[sweep.job].complete(given)
            except KeyError as exc:
                v.fail(where, f"{sweep.target} needs the parameter(s) {exc.args[0]}")
            except ParamsError as exc:          # "<name>: <rule>", a value of the wrong kind
                name, rule = str(exc).split(": ", 1)
                v.fail(origin(k, name) if origin and name in given else f"{where}.{name}", rule)
        else:
            complete = dict(given)
        target = {"job": sweep.job} if sweep.job else {"notebook": sweep.notebook}
        key = hashlib.sha256(canonical({**target, "params": complete}).encode()).hexdigest()[:16]
        cells.setdefault(key, Cell(complete, key))
    return tuple(cells.values())


def _check_sweep_name(v: Validator, name: Any) -> str:
    name = v.string(name, "name")
    if not all(c.isalnum() or c in "-_." for c in name) or name.startswith("."):
        v.fail("name", f"must be letters, digits, '-', '_' or '.' (a directory name), got {show(name)}")
    return name


# --------------------------------------------------------------------------------------------
# A sweep file as written: the schema :func:`sweep_from_dict` reads through the generic reader.
# A field whose rule no annotation says (a parameter mapping, a name that names a directory, one
# of the library's jobs) is read by a function of its own (``ReadBy``).


def _name(v: Validator, value: Any, at: str) -> str:
    return _check_sweep_name(v, value)


def _job(v: Validator, value: Any, at: str) -> str:
    """One of the library's jobs (:data:`nfarm.study.jobs.JOBS`)."""
    return v.choice(value, at, sorted(JOBS))


def _fixed(v: Validator, value: Any, at: str) -> dict[str, Any]:
    """``fixed``: parameter names to plain values."""
    return {k: _plain(v, x, f"{at}.{k}") for k, x in _parameters(v, value, at).items()}


def _grid(v: Validator, value: Any, at: str) -> dict[str, list]:
    """``grid``: parameter names to non-empty lists of plain values (the axes)."""
    axes = {}
    for key, values in _parameters(v, value, at).items():
        values = v.sequence(values, f"{at}.{key}", min_len=1)
        axes[key] = [_plain(v, x, f"{at}.{key}[{k}]") for k, x in enumerate(values)]
    return axes


def _cells(v: Validator, value: Any, at: str) -> list[dict[str, Any]]:
    """``cells``: a non-empty list of parameter mappings."""
    cells = v.sequence(value, at, min_len=1)
    return [{key: _plain(v, x, f"{at}[{k}].{key}") for key, x in _parameters(v, cell, f"{at}[{k}]").items()}
            for k, cell in enumerate(cells)]


#: ``seeds``: whole numbers in [0, 2³² − 1], at least one (left out: no seed axis).
Seeds = Annotated[list[Annotated[int, Range(lo=0, hi=2**32 - 1)]], Length(lo=1)]


@dataclass(frozen=True, kw_only=True)
class SmokeSection:
    """``smoke``: the smaller version's fields, each replacing the file's own where given."""

    fixed: Annotated[dict, ReadBy(_fixed)] = field(default_factory=dict)
    grid: Annotated[dict, ReadBy(_grid)] = field(default_factory=dict)
    cells: Annotated[list, ReadBy(_cells)] = field(default_factory=lambda: [{}])
    seeds: Seeds = field(default_factory=list)


@dataclass(frozen=True, kw_only=True)
class SweepFile:
    """A sweep file as written (module docstring), typed and checked field by field; ``job``
    or ``notebook`` is ``""`` when left out (the file names one of them), ``seeds`` ``[]``."""

    name: Annotated[str, ReadBy(_name)]
    description: Annotated[str, TEXT] = ""
    job: Annotated[str, ReadBy(_job)] = ""
    notebook: str = ""
    fixed: Annotated[dict, ReadBy(_fixed)] = field(default_factory=dict)
    grid: Annotated[dict, ReadBy(_grid)] = field(default_factory=dict)
    cells: Annotated[list, ReadBy(_cells)] = field(default_factory=lambda: [{}])
    seeds: Seeds = field(default_factory=list)
    metrics: Annotated[list[str], Length(lo=1)]
    smoke: SmokeSection = field(default_factory=SmokeSection)
    cell_timeout_s: Optional[Annotated[float, CELL_TIMEOUT_S]] = None


def sweep_from_dict(data: Any, source: str = "<dict>", *, smoke: bool = False) -> Sweep:
    """Validate a sweep mapping (as read from YAML) and expand its cells; ``smoke`` applies its
    ``smoke`` section. The mapping is read into a :class:`SweepFile` by the generic reader,
    then the rules between fields, against the job or notebook and on the cells are checked;
    the first broken rule is one :class:`ParamsError` line naming the file and the field."""
    v = Validator(source)
    v.mapping(data, "", section_keys(SweepFile))
    if ("job" in data) == ("notebook" in data):       # which fields are given: before their values
        v.fail("", "must name either a job or a notebook")
    file = read_typed(SweepFile, data, v)
    name, description = file.name, file.description
    job = file.job or None
    notebook = None
    if job is None:
        path = project_path(file.notebook)
        if path.suffix != ".ipynb" or not path.is_file():
            v.fail("notebook", f"must be an existing .ipynb file, got {show(data['notebook'])}")
        notebook = shown_path(path)
    metrics = file.metrics
    for k, metric in enumerate(metrics):
        if job and metric not in JOBS[job].metrics:
            v.fail(f"metrics[{k}]", f"job {job} returns no metric {metric!r} "
                                    f"(it returns {', '.join(JOBS[job].metrics)})")
    if len(set(metrics)) != len(metrics):
        v.fail("metrics", "lists a metric twice")
    replaced = set(data.get("smoke", {})) if smoke else set()       # the smoke section's fields given
    if "smoke" in data and not smoke:       # the smaller version must be valid too
        sweep_from_dict(data, source, smoke=True)
    at = lambda key: f"smoke.{key}" if key in replaced else key  # noqa: E731
    fixed, axes, own, seeds = (getattr(file.smoke if key in replaced else file, key)
                               for key in ("fixed", "grid", "cells", "seeds"))
    axes = dict(axes)
    if seeds:
        if "seed" in axes:
            v.fail(at("seeds"), "the grid sets seed too: give the seeds in one place")
        axes["seed"] = seeds
    for key in axes:
        if key in fixed:
            v.fail(f"{at('grid')}.{key}", "is also in fixed: a parameter is fixed or varied, not both")
        for k, cell in enumerate(own):
            if key in cell:
                v.fail(f"{at('cells')}[{k}].{key}", "is also a grid parameter")
    count = len(own) * math.prod(len(x) for x in axes.values())
    if count > MAX_CELLS:
        v.fail(at("grid"), f"makes {count:,} cells; at most {MAX_CELLS:,}")
    sweep = Sweep(name, source, job, notebook, tuple(metrics), (), description, file.cell_timeout_s)
    allowed = _allowed(v, sweep)
    for where, names in [(at("fixed"), fixed), (at("grid"), axes),
                         *((f"{at('cells')}[{k}]", cell) for k, cell in enumerate(own))]:
        for key in names:
            _check_name(v, sweep, allowed, key, where if key != "seed" or not seeds
                        else at("seeds"))
    points = [{**fixed, **cell, **dict(zip(axes, values))}
              for cell in own for values in itertools.product(*axes.values())]
    per_cell = math.prod(len(x) for x in axes.values())

    def origin(k: int, name: str) -> str:
        if name in fixed:
            return f"{at('fixed')}.{name}"
        if name == "seed" and seeds:
            return at("seeds")
        if name in axes:
            return f"{at('grid')}.{name}"
        return f"{at('cells')}[{k // per_cell}].{name}"

    listed = "cells" in data or "cells" in replaced        # the cells are the file's own, or the grid's
    return replace(sweep, cells=_make_cells(v, sweep, points, at("cells") if listed else at("grid"), origin))


def load_sweep(path: str | os.PathLike, *, smoke: bool = False) -> Sweep:
    """Read and validate a sweep file (module docstring); :class:`ParamsError` in one line."""
    path = project_path(path)
    return sweep_from_dict(load_yaml(path), shown_path(path), smoke=smoke)
