# rockslide: common tasks. The paper's records are read from, in this order: an exported
# ROCKSLIDE_RECORDS, else RECORDS (`make table1 RECORDS=/path/to/records`), else ../shared/records
# when that folder exists, else ./records. Every target sees the choice as ROCKSLIDE_RECORDS.
PYTHON ?= python
ifneq ($(strip $(ROCKSLIDE_RECORDS)),)
override RECORDS := $(ROCKSLIDE_RECORDS)
endif
RECORDS ?= $(if $(wildcard ../shared/records/*),../shared/records,records)
export ROCKSLIDE_RECORDS := $(abspath $(RECORDS))

.PHONY: help install test test-fast check lint bench table1 example spectrum records clean

help:
	@echo "make install   install rockslide with its test tools (pip install -e '.[test]')"
	@echo "make test      the whole test suite"
	@echo "make test-fast the inner loop (under 2 minutes): the suite without the tests marked slow,"
	@echo "               which leaves out dask clusters, signals and killed subprocesses, full disks, the docs"
	@echo "               build, the CUDA simulator, the heavier tests that start a Python process, Table 1 at"
	@echo "               the 0.1 ms step (it keeps Table 1 at the auto step), the long reference comparisons"
	@echo "               and resamplings, figures written to files (it keeps each kind rendered to PNG, and"
	@echo "               the layout at 150 dpi only), whole analyses with figures from the command line, and"
	@echo "               the hypothesis fuzzers of 100 to 500 examples; the list with reasons is in"
	@echo "               tests/conftest.py (SLOW_MODULES, SLOW_TESTS) and @pytest.mark.slow. make test runs them all"
	@echo "make check     lint, import contracts, then the tests"
	@echo "make bench     speed and accuracy benchmarks -> results/bench.md, bench_kernel.md, bench_sweep.md, bench_fragility.md, bench_startup.md, bench_overhead.md, bench_gpu_host.md, bench_large.md, bench_auto_step.md, work_precision.png"
	@echo "make table1    the paper's Table 1 and Figures 5-10 -> results/ (needs the paper's records)"
	@echo "make example   run configs/example.yaml"
	@echo "make spectrum  an overturning spectrum under one-sine pulses -> results/spectrum.png"
	@echo "make records   regenerate the synthetic records shipped in records/"

install:
	$(PYTHON) -m pip install -e ".[test]"

test:
	$(PYTHON) -m pytest

test-fast:
	$(PYTHON) -m pytest -m "not slow"

lint:
	ruff check rockslide tests benchmarks
	lint-imports

check: lint test

bench:
	$(PYTHON) benchmarks/bench.py --out results
	$(PYTHON) benchmarks/bench_kernel.py > results/bench_kernel.md
	$(PYTHON) benchmarks/bench_sweep.py > results/bench_sweep.md
	$(PYTHON) benchmarks/bench_fragility.py > results/bench_fragility.md
	$(PYTHON) benchmarks/bench_large.py --out results
	$(PYTHON) benchmarks/bench_auto_step.py --out results
	$(PYTHON) benchmarks/bench_startup.py --cold >> results/bench.md
	$(PYTHON) benchmarks/bench_startup.py > results/bench_startup.md
	$(PYTHON) benchmarks/bench_overhead.py --out results > /dev/null
	$(PYTHON) benchmarks/bench_gpu_host.py --out results > /dev/null

table1:
	$(PYTHON) -m rockslide table1 --records-dir "$(ROCKSLIDE_RECORDS)" --out-dir results

example:
	$(PYTHON) -m rockslide run configs/example.yaml --overwrite

spectrum:
	$(PYTHON) -m rockslide.cli sweep configs/spectrum-one-sine.yaml --amplitude 0.225g:2.5g:0.05g \
		--period 0.14:1.7:0.04 --out-dir out --overwrite --no-plot
	$(PYTHON) -m rockslide.cli plot out/spectrum-one-sine.sweep.h5 -o results/spectrum.png --overwrite

records:
	$(PYTHON) records/make_example_records.py

clean:
	rm -rf out .pytest_cache .hypothesis build *.egg-info

# the documentation site, warnings as errors (needs the docs extra, which the test extra includes)
.PHONY: docs
docs:
	$(PYTHON) -m sphinx -W --keep-going -b html docs docs/_build/html
	@echo "open docs/_build/html/index.html"
