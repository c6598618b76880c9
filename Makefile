# posefix: `make run` and `make test` are the whole set-up on a fresh machine.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
CORES ?= 2
# `make run` repairs the built-in demo library with the posefix command (its progress lines; Snakemake's output goes
# to posefix-logs/); POSEFIX_ARGS="path/to/library --config poses=a,b" repairs another.
POSEFIX_ARGS ?=
PYTEST_ARGS ?=

BLENDER_VENV ?= .venv-blender

.PHONY: run test test-fast bench lint system clean blender-addon

run: $(VENV)/.installed system
	$(VENV)/bin/posefix repair --cores $(CORES) $(POSEFIX_ARGS)

# The whole suite on $(CORES) processes, one test file each at a time (a file's fixtures are made once): the end-to-end
# runs are chains of single-threaded stages, so two processes keep 2 cores busy (three were no faster). The end-to-end
# files go first, longest first (tests/conftest.py LONGEST_FIRST; --no-loadscope-reorder keeps that order).
test: $(VENV)/.installed $(BLENDER_VENV)/.installed system
	$(PY) -m pytest -n $(CORES) --dist loadfile --no-loadscope-reorder $(PYTEST_ARGS)

# The unit tests alone, for your own loop, on $(CORES) processes: no end-to-end pipeline, SLURM or ../shared/data tests.
test-fast: $(VENV)/.installed system
	$(PY) -m pytest -n $(CORES) -m "not pipeline and not cluster and not data" $(PYTEST_ARGS)

bench: $(VENV)/.installed system
	$(PY) benchmarks/run.py --cores $(CORES)

lint: $(VENV)/.installed
	$(VENV)/bin/snakemake --lint

# The virtual environment, rebuilt when the declared dependencies change. CHOLMOD (scikit-sparse, built against
# the system's SuiteSparse) factorizes the contact solver's large Newton systems; without it SuperLU does, slower.
$(VENV)/.installed: pyproject.toml | system
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,cluster]'
	$(PY) -m pip install --quiet -e '.[cholmod]' \
	  || echo "posefix: WARNING: scikit-sparse (CHOLMOD) did not build; the contact solver falls back to SuperLU"
	touch $@

# bpy 4.5 LTS (Blender as a Python module, from PyPI) runs the Blender add-on's tests headless (tests/blender/). It gets
# an environment of its own: it pins numpy < 2 (posefix runs on numpy 2; pandas 3 needs it) and needs Python 3.11, as
# Blender's own Python is apart from posefix's. Without it (another Python) the Blender tests are skipped.
$(BLENDER_VENV)/.installed:
	($(PYTHON) -m venv $(BLENDER_VENV) && $(BLENDER_VENV)/bin/python -m pip install --quiet 'bpy==4.5.*' && touch $@) \
	  || echo "posefix: WARNING: bpy 4.5 could not be installed (it needs Python 3.11); the Blender tests are skipped"

# The Blender extension's zip (dist/posefix-blender-<version>.zip), for Blender's Preferences > Get Extensions >
# Install from Disk (docs/blender.md).
blender-addon: $(VENV)/.installed
	$(PY) -m posefix.workflow.blender_addon dist

# Debian's PoCL gives an OpenCL CPU device (PyPI's PoCL cannot compile kernels on these CPUs); SuiteSparse's headers
# build CHOLMOD; OpenBLAS (threaded) makes its supernodal factorization 3x faster than the reference BLAS.
# Chromium (headless, software WebGL) runs the tests of the 3D viewer page (tests/report/test_viewer.py).
# Installed only when root with apt; otherwise the OpenCL stages fall back to numpy, the contact solver to SuperLU
# and the viewer's browser tests are skipped.
SYSTEM_PACKAGES := pocl-opencl-icd libsuitesparse-dev libopenblas0-pthread chromium
system:
	@if dpkg-query -W -f='$${Status}\n' $(SYSTEM_PACKAGES) 2>/dev/null | grep -c 'install ok installed' \
	    | grep -qx "$(words $(SYSTEM_PACKAGES))"; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	  echo "posefix: installing $(SYSTEM_PACKAGES)"; \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
	    $(SYSTEM_PACKAGES) >/dev/null) \
	    || echo "posefix: WARNING: could not install $(SYSTEM_PACKAGES); OpenCL stages fall back to numpy," \
	      "the viewer's browser tests are skipped"; \
	else echo "posefix: WARNING: not root or no apt-get: $(SYSTEM_PACKAGES) not installed;" \
	  "OpenCL stages fall back to numpy, the contact solver to SuperLU, the viewer's browser tests are skipped"; fi

clean:
	rm -rf results data/demo .snakemake dist
