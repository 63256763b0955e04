# Developer entry points. `make test` runs every test (Rust and Python); `make run` installs
# the package and runs the main job.
PYTHON ?= python3
PIP := $(PYTHON) -m pip

.PHONY: install test test-rust test-python stubtest lint bench run

install:
	$(PIP) install -q -e ".[test]"

test: install test-rust test-python stubtest

test-rust:
	cargo test

test-python:
	$(PYTHON) -m pytest -q

stubtest:
	$(PYTHON) -m mypy.stubtest vsinv._core
	$(PYTHON) -m mypy python/vsinv

lint:
	cargo fmt --check
	cargo clippy --all-targets -- -D warnings
	cargo clippy --features python -- -D warnings

bench: install
	cargo bench --bench vsinv
	$(PYTHON) benches/bench_step.py
	$(PYTHON) benches/compare.py

run: install
	$(PYTHON) -m vsinv run lens-12-6 --out results/lens-12-6
	$(PYTHON) -m vsinv run ibvs-12-6 --out results/ibvs-12-6
