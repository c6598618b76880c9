# posefix: `make run` and `make test` are the whole set-up on a fresh machine.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
CORES ?= 2
SNAKEMAKE_ARGS ?=
# `make run` checks one downstream setting (alpha 1, k_b 1e-2) instead of config.yaml's grid of six,
# which costs 2-3 minutes per demo pose on 2 cores; RUN_CONFIG= (empty) runs the whole grid.
RUN_CONFIG ?= downstream={'alphas': [1.0], 'k_bend': [0.01]}
PYTEST_ARGS ?=

.PHONY: run test test-fast bench lint system clean

run: $(VENV)/.installed system
	$(VENV)/bin/snakemake --cores $(CORES) $(if $(RUN_CONFIG),--config "$(RUN_CONFIG)") $(SNAKEMAKE_ARGS)

test: $(VENV)/.installed system
	$(PY) -m pytest $(PYTEST_ARGS)

# The unit tests alone, for your own loop, on $(CORES) processes: no end-to-end pipeline, SLURM or ../shared/data tests.
test-fast: $(VENV)/.installed system
	$(PY) -m pytest -n $(CORES) -m "not pipeline and not cluster and not data" $(PYTEST_ARGS)

bench: $(VENV)/.installed system
	$(PY) benchmarks/run.py --cores $(CORES)

lint: $(VENV)/.installed
	$(VENV)/bin/snakemake --lint

# The virtual environment, rebuilt when the declared dependencies change.
$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,cluster]'
	touch $@

# Debian's PoCL gives an OpenCL CPU device (PyPI's PoCL cannot compile kernels on these CPUs).
# Installed only when root with apt; otherwise the OpenCL stages fall back to numpy and say so.
system:
	@if dpkg-query -W -f='$${Status}' pocl-opencl-icd 2>/dev/null | grep -q 'install ok installed'; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	  echo "posefix: installing pocl-opencl-icd (OpenCL on the CPU)"; \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends pocl-opencl-icd >/dev/null) \
	    || echo "posefix: WARNING: could not install pocl-opencl-icd; OpenCL stages will fall back to numpy"; \
	else echo "posefix: WARNING: not root or no apt-get: pocl-opencl-icd not installed; OpenCL stages will fall back to numpy"; fi

clean:
	rm -rf results data/demo .snakemake
