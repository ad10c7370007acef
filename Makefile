# nfarm — every target builds what it needs; `make report` and `make test` work on a fresh
# machine that has only Python 3.11 and make.

SHELL  := /bin/bash
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
UV     := $(VENV)/bin/uv
STAMP  := $(VENV)/.nfarm-setup
# The project's modules compiled to bytecode before a run (only those changed since; half a second):
# an editable install is not compiled by the set-up, and Python may be told to write no bytecode.
BYTECODE = $(PY) -m compileall -q lib >/dev/null
KERNEL := nfarm
# Jupyter looks in JUPYTER_PATH first: the project kernel wins over any kernel of the same
# name the machine happens to have.
export JUPYTER_PATH := $(CURDIR)/$(VENV)/share/jupyter
export MPLBACKEND := Agg
export PYTHONHASHSEED := 0

# The report's numbers and pictures must be the same bits on any x86-64 machine. numpy picks
# SIMD kernels (AVX-512 SVML for tan, pow, exp, …) and OpenBLAS picks GEMM kernels by CPU, and
# their last bits differ; chaotic quantities (ANFIS step-size oscillations, Jacobian-transpose
# iteration counts) then differ in the published tables. `make report` pins both to what every
# x86-64 machine since 2013 (Haswell, Zen) runs natively; measured, see docs/reproducibility.md and docs/performance.md.
# NUMPY_MADVISE_HUGEPAGE=0: numpy asks the kernel for transparent huge pages for every large array, and where the
# kernel compacts memory to serve them on the fault (defrag "madvise", as on this project's machines) a large,
# short-lived design spends seconds in the kernel: the rigid-body span's ridge fits took 4.5-7.5 s of system time with
# them and 1.9 s without, the same 5.6 s of user time. Over the clean build the gain is small — system time 310 → 171 s,
# user time 1 912 → 2 037 s (small pages cost the arithmetic more), 14 CPU-s in all; the cells whose cost had swung
# most between builds, the rigid-body span's ridge fits (31 and 50 CPU-s over their seed-0 cells), took 20 (measured
# 2026-12-07, docs/performance.md). The numbers do not depend on it.
REPORT_ENV := OPENBLAS_CORETYPE=Haswell OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 NUMPY_MADVISE_HUGEPAGE=0 \
	NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL AVX512_SPR"

.PHONY: setup arm report test bench sweep course lock lab panel verify clean distclean worker

setup: $(STAMP)

# The lock pins uv itself (extra "tools"): bootstrap it from the lock with pip, hash-checked,
# then let uv make the venv match the lock exactly.
$(STAMP): environment.lock pyproject.toml jupyter/lab-overrides.json
	@command -v $(PYTHON) >/dev/null || { echo "make setup: $(PYTHON) not found (CPython 3.11 is required; set PYTHON=...)" >&2; exit 2; }
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@mkdir -p build
	@awk '/^uv==/{on=1} on&&/^[^ #]/&&!/^uv==/{on=0} on' environment.lock > build/uv.req
	@$(PY) -m pip install --quiet --disable-pip-version-check --require-hashes --no-deps -r build/uv.req
	@# Bytecode compiled once here: where PYTHONDONTWRITEBYTECODE is set (as on the machines measured), every
	@# kernel, worker and test process would compile numpy, scipy, matplotlib … from source again (docs/performance.md, "Bytecode").
	VIRTUAL_ENV=$(VENV) $(UV) pip sync --quiet --compile-bytecode --python $(PY) environment.lock
	VIRTUAL_ENV=$(VENV) $(UV) pip install --quiet --python $(PY) --no-deps --no-build-isolation -e .
	$(PY) -m ipykernel install --sys-prefix --name $(KERNEL) --display-name "Python 3.11 (nfarm)" \
	    --env MPLBACKEND module://matplotlib_inline.backend_inline >/dev/null
	@# JupyterLab asks nothing of the internet: no news, no update check (jupyter/lab-overrides.json).
	@install -D -m 644 jupyter/lab-overrides.json $(VENV)/share/jupyter/lab/settings/overrides.json
	@touch $@

# make report [ARM=name] [SCHEDULER=tcp://host:8786]: ARM runs one arm's edition (and the chapters comparing
# the arms) without the others'; SCHEDULER sends chapter 6's missing sweep cells to a running Dask
# cluster (its workers: this checkout and `make setup`); the published files are the same.
report: $(STAMP)
	@$(BYTECODE)
	$(REPORT_ENV) $(PY) -m nfarm report $(if $(SCHEDULER),--scheduler "$(SCHEDULER)") $(if $(ARM),--arm "$(ARM)")

# make arm URDF=path/to/arm.urdf [NAME=n] [ARM_ARGS="--tip LINK --lock JOINT=VALUE"]: a new arm's
# robot and study files in params/, with defaults derived from its URDF (docs/adding-an-arm.md).
arm: $(STAMP)
	@test -n "$(URDF)" || { echo "make arm: name a URDF, e.g. make arm URDF=path/to/arm.urdf [NAME=myarm]" >&2; exit 2; }
	$(PY) -m nfarm add-arm "$(URDF)" $(if $(NAME),--name "$(NAME)") $(ARM_ARGS)

# Checks the checkout's figures/ against figures/MANIFEST.sha256 without regenerating anything.
verify: $(STAMP)
	$(PY) -m nfarm verify

# Two pytest-xdist workers: the notebooks' kernels and the unit tests share the two cores;
# tests that share a chain of chapters' data stay in one worker (--dist loadgroup). One BLAS
# thread per worker: two workers already use both cores (two threads each would thrash them).
test: $(STAMP)
	@$(BYTECODE)
	OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 NUMPY_MADVISE_HUGEPAGE=0 $(PY) -m pytest -n 2 --dist loadgroup

bench: $(STAMP)
	@set -e; for b in benchmarks/bench_*.py; do echo "== $$b"; $(PY) $$b; done

# The course (docs/teaching.md): build/course/student/ (no solutions, no outputs),
# build/course/teacher/ (executed with the worked solutions, HTML) and build/course/index.html.
# The teacher's notebooks reuse the data sets and models `make report` made.
course: $(STAMP)
	@$(BYTECODE)
	$(REPORT_ENV) $(PY) -m nfarm course

# make sweep SWEEP=params/sweeps/smoke.yaml [SWEEP_ARGS="--scheduler tcp://host:8786"]: the
# cells run with the report's numerics, so a chapter reuses them (docs/sweeps.md).
sweep: $(STAMP)
	@test -n "$(SWEEP)" || { echo "make sweep: name a sweep file, e.g. make sweep SWEEP=params/sweeps/smoke.yaml" >&2; exit 2; }
	@$(BYTECODE)
	$(REPORT_ENV) $(PY) -m nfarm sweep $(SWEEP) $(SWEEP_ARGS)

# make worker SCHEDULER=tcp://host:8786 [WORKERS=N]: Dask workers for `make report SCHEDULER=…` and
# `make sweep`, on any machine with this checkout: the report's numerics, one thread per cell, so
# that the cells they run are the bits a local run makes (and the chapters reuse their models).
worker: $(STAMP)
	@test -n "$(SCHEDULER)" || { echo "make worker: name the scheduler, e.g. make worker SCHEDULER=tcp://host:8786" >&2; exit 2; }
	@$(BYTECODE)
	$(REPORT_ENV) $(VENV)/bin/dask worker "$(SCHEDULER)" --nthreads 1 --nworkers $(or $(WORKERS),$(shell nproc))

lock: $(STAMP)
	$(UV) pip compile pyproject.toml --extra test --extra tools --generate-hashes \
	    --python-version 3.11 --python-platform x86_64-manylinux_2_28 -o environment.lock

lab: $(STAMP)
	$(VENV)/bin/jupyter lab --notebook-dir=notebooks

# The arm panel (notebooks/arm_panel.ipynb) as a local web page, offline: make panel [PORT=8866].
PORT ?= 8866
panel: $(STAMP)
	@$(PY) -m nfarm panel --port "$(PORT)"

clean:
	rm -rf build .pytest_cache .hypothesis
	find . -name __pycache__ -type d -prune -not -path './$(VENV)/*' -exec rm -rf {} +

distclean: clean
	rm -rf $(VENV)
