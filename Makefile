# nfarm — every target builds what it needs; `make report` and `make test` work on a fresh
# machine that has only Python 3.11 and make.

SHELL  := /bin/bash
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
UV     := $(VENV)/bin/uv
STAMP  := $(VENV)/.nfarm-setup
KERNEL := nfarm
# Jupyter looks in JUPYTER_PATH first: the project kernel wins over any kernel of the same
# name the machine happens to have.
export JUPYTER_PATH := $(CURDIR)/$(VENV)/share/jupyter
export MPLBACKEND := Agg
export PYTHONHASHSEED := 0
# glibc malloc: keep freed memory instead of returning it to the system after every large
# numpy temporary. nfarm's batched kernels allocate many 0.1–1 MB arrays; with the defaults each
# one costs fresh pages (page faults), which made fk/jacobian up to 3.5x slower (see README).
export MALLOC_MMAP_THRESHOLD_ := 268435456
export MALLOC_TRIM_THRESHOLD_ := 536870912

.PHONY: setup report test bench lock lab clean distclean

setup: $(STAMP)

# The lock pins uv itself (extra "tools"): bootstrap it from the lock with pip, hash-checked,
# then let uv make the venv match the lock exactly.
$(STAMP): environment.lock pyproject.toml
	@command -v $(PYTHON) >/dev/null || { echo "make setup: $(PYTHON) not found (CPython 3.11 is required; set PYTHON=...)" >&2; exit 2; }
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@mkdir -p build
	@awk '/^uv==/{on=1} on&&/^[^ #]/&&!/^uv==/{on=0} on' environment.lock > build/uv.req
	@$(PY) -m pip install --quiet --disable-pip-version-check --require-hashes --no-deps -r build/uv.req
	VIRTUAL_ENV=$(VENV) $(UV) pip sync --quiet --python $(PY) environment.lock
	VIRTUAL_ENV=$(VENV) $(UV) pip install --quiet --python $(PY) --no-deps --no-build-isolation -e .
	$(PY) -m ipykernel install --sys-prefix --name $(KERNEL) --display-name "Python 3.11 (nfarm)" \
	    --env MALLOC_MMAP_THRESHOLD_ $(MALLOC_MMAP_THRESHOLD_) --env MALLOC_TRIM_THRESHOLD_ $(MALLOC_TRIM_THRESHOLD_) \
	    --env MPLBACKEND module://matplotlib_inline.backend_inline >/dev/null
	@touch $@

report: $(STAMP)
	$(PY) -m nfarm report

test: $(STAMP)
	$(PY) -m pytest

bench: $(STAMP)
	@set -e; for b in benchmarks/bench_*.py; do echo "== $$b"; $(PY) $$b; done

lock: $(STAMP)
	$(UV) pip compile pyproject.toml --extra test --extra tools --generate-hashes \
	    --python-version 3.11 --python-platform x86_64-manylinux_2_28 -o environment.lock

lab: $(STAMP)
	$(VENV)/bin/jupyter lab --notebook-dir=notebooks

clean:
	rm -rf build .pytest_cache .hypothesis
	find . -name __pycache__ -type d -prune -not -path './$(VENV)/*' -exec rm -rf {} +

distclean: clean
	rm -rf $(VENV)
