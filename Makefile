# Two commands do all the set-up on a fresh machine:
#   make demo   create .venv, install, run the main job on its embedded default
#   make test   create .venv if needed, install, run the test suite
PYTHON ?= python3
VENV   := .venv
PIP    := $(VENV)/bin/pip
STAMP  := $(VENV)/.installed
OUT    ?= runs/demo

.PHONY: demo test bench system-deps clean

$(STAMP): pyproject.toml constraints.txt
	@$(MAKE) --no-print-directory system-deps
	test -x $(VENV)/bin/python || $(PYTHON) -m venv $(VENV)
	$(PIP) install -q --upgrade pip
	# torch first, pinned to the CPU wheel, so nothing later pulls CUDA packages.
	$(PIP) install -q -c constraints.txt torch
	$(PIP) install -q -c constraints.txt -e '.[test]'
	touch $(STAMP)

# Open3D's CPU wheel needs libusb-1.0 to import.
system-deps:
	@if ldconfig -p 2>/dev/null | grep -q 'libusb-1.0.so'; then :; \
	elif [ "$$(id -u)" = 0 ]; then \
	  echo "installing libusb-1.0-0 (needed by open3d-cpu)"; \
	  (apt-get install -y -q libusb-1.0-0 >/dev/null 2>&1 || (apt-get update -q >/dev/null && apt-get install -y -q libusb-1.0-0 >/dev/null)); \
	else \
	  echo "error: open3d-cpu needs libusb-1.0; run: sudo apt-get install -y libusb-1.0-0" >&2; exit 2; \
	fi

demo: $(STAMP)
	$(VENV)/bin/wbsa run --out $(OUT)

test: $(STAMP)
	$(VENV)/bin/python -m pytest -q

bench: $(STAMP)
	$(VENV)/bin/python benchmarks/bench_population.py
	OPENBLAS_NUM_THREADS=1 $(VENV)/bin/python benchmarks/bench_raycast.py --anny --accuracy
	$(VENV)/bin/python benchmarks/bench_scan.py --subjects 24 --chunk-size 6
	$(VENV)/bin/python benchmarks/bench_reconstruction.py
	$(VENV)/bin/python benchmarks/bench_fit.py 20000 65
	$(VENV)/bin/python benchmarks/bench_survey_match.py --n 500 --seed 0
	$(VENV)/bin/python benchmarks/bench_paper_scale.py --subjects 60,240

clean:
	rm -rf $(VENV) build src/*.egg-info
