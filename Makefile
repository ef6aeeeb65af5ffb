# Two commands do all the set-up on a fresh machine:
#   make demo   create .venv, install, run the main job on its embedded default
#   make test   create .venv if needed, install, run the test suite
PYTHON ?= python3
VENV   := .venv
PIP    := $(VENV)/bin/pip
STAMP  := $(VENV)/.installed
OUT    ?= runs/demo
# Index torch is installed from. Empty: pip's configured indexes, where constraints.txt's pin finds a CPU
# wheel only if one is there (PyPI's Linux wheel of torch 2.13.0 is a CUDA build with ~15 nvidia packages).
# On your own machine: make demo TORCH_INDEX=https://download.pytorch.org/whl/cpu
TORCH_INDEX ?=

.PHONY: demo test test-quick bench system-deps clean

$(STAMP): pyproject.toml constraints.txt
	@$(MAKE) --no-print-directory system-deps
	test -x $(VENV)/bin/python || $(PYTHON) -m venv $(VENV)
	$(PIP) install -q --upgrade pip
	# torch first, pinned (CPU wheel from TORCH_INDEX), so nothing later pulls another build.
	$(PIP) install -q -c constraints.txt $(if $(TORCH_INDEX),--index-url $(TORCH_INDEX)) torch
	$(PIP) install -q -c constraints.txt -e '.[test]'
	touch $(STAMP)

# Open3D's CPU wheel needs libusb-1.0 to import; the browser tests of wbsa serve need Debian's chromium and
# chromium-driver (tests/test_serve.py drives the headless browser through selenium).

system-deps:
	@missing=""; \
	ldconfig -p 2>/dev/null | grep -q 'libusb-1.0.so' || missing="$$missing libusb-1.0-0"; \
	command -v chromium >/dev/null 2>&1 || missing="$$missing chromium"; \
	command -v chromedriver >/dev/null 2>&1 || missing="$$missing chromium-driver"; \
	if [ -z "$$missing" ]; then :; \
	elif [ "$$(id -u)" = 0 ]; then \
	  echo "installing$$missing (open3d-cpu needs libusb; the browser tests need chromium)"; \
	  (apt-get install -y -q $$missing >/dev/null 2>&1 || (apt-get update -q >/dev/null && apt-get install -y -q $$missing >/dev/null)); \
	else \
	  echo "error: missing Debian packages:$$missing; run: sudo apt-get install -y$$missing" >&2; exit 2; \
	fi

demo: $(STAMP)
	$(VENV)/bin/wbsa run --out $(OUT)

test: $(STAMP)
	$(VENV)/bin/python -m pytest -q

# The local edit-test loop: everything but the tests marked slow (CI runs `make test`, all of them).
test-quick: $(STAMP)
	$(VENV)/bin/python -m pytest -q -m "not slow"

bench: $(STAMP)
	$(VENV)/bin/python benchmarks/bench_population.py
	$(VENV)/bin/python benchmarks/bench_posture.py --n 300
	OPENBLAS_NUM_THREADS=1 $(VENV)/bin/python benchmarks/bench_raycast.py --anny --accuracy
	$(VENV)/bin/python benchmarks/bench_scan.py --subjects 24 --chunk-size 6
	$(VENV)/bin/python benchmarks/bench_scan_stages.py --subjects 12
	$(VENV)/bin/python benchmarks/bench_reconstruction.py
	$(VENV)/bin/python benchmarks/bench_fit.py 20000 65
	$(VENV)/bin/python benchmarks/bench_survey_match.py --n 500 --seed 0
	$(VENV)/bin/python benchmarks/bench_population_realism.py --n 300 --survey-n 100
	$(VENV)/bin/python benchmarks/bench_paper_scale.py
	$(VENV)/bin/python benchmarks/bench_estimate.py --subjects 300 --workers 2
	$(VENV)/bin/python benchmarks/bench_serve.py --browser

clean:
	rm -rf $(VENV) build src/*.egg-info
