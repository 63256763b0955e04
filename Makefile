# Developer entry points. `make test` runs every test (Rust and Python); `make run` installs
# the package and runs the main job.
PYTHON ?= python3
PIP := $(PYTHON) -m pip
RUST_EXAMPLES := control_loop servo_loop simulation batch
# The property tests of tests/robustness_*.rs (the census, a report, is left out): modules of the
# one integration-test binary (tests/integration.rs), selected by their `NAME::` prefix.
ROBUSTNESS_TESTS := robustness_camera robustness_invariants robustness_control robustness_planning robustness_files \
	robustness_vision robustness_regressions

.PHONY: docs wheels install install-run test test-fast test-rust test-builtins test-embedded test-examples test-python stubtest stubs lint bench bench-quick soak fuzz run

# No -q: the first install compiles the Rust extension in release mode (several minutes on
# 2 cores); -v passes cargo's progress through, so the build is seen to move.
install:
	$(PIP) install -v -e ".[test]"

# `make run`'s install: maturin builds the wheel in the lighter profile `light` (Cargo.toml) on
# the terminal, so cargo's progress shows (pip holds a build's output back until a line ends),
# then pip installs it with what running needs (numpy, matplotlib, tqdm), no extra.
# RUN_MATURIN=maturin where maturin's command is not beside $(PYTHON) (a venv seeing the system's).
RUN_WHEELS := target/wheels-run
RUN_MATURIN ?= $(PYTHON) -m maturin
install-run:
	$(PIP) install "maturin>=1.9.4,<2"
	rm -rf $(RUN_WHEELS)
	$(RUN_MATURIN) build --profile light --interpreter $(PYTHON) --out $(RUN_WHEELS)
	$(PIP) install --force-reinstall --no-deps $(RUN_WHEELS)/vsinv-*.whl
	$(PIP) install $(RUN_WHEELS)/vsinv-*.whl

test: install test-rust test-embedded test-examples test-python stubtest docs

# The unit tests, the integration tests (tests/*.rs, one binary: tests/integration.rs, each file a
# module; one file's tests: cargo test --release --test integration NAME::), the doc tests.
test-rust:
	cargo test --release

# Every built-in scenario gives its recorded result (tests/builtin_results.rs): the guard of
# refactors. VSINV_RECORD_BUILTINS=1 records the table anew.
test-builtins:
	cargo test --release --test integration builtin_results::

# The core alone, as a controller embeds it: a 100 Hz loop and the zero-allocation test.
test-embedded:
	cargo test -p vsinv-embedded
	cargo run -q -p vsinv-embedded

test-examples:
	for ex in $(RUST_EXAMPLES); do cargo run -q --release --example $$ex || exit 1; done

# PYTEST_ARGS narrows or widens the Python tests, e.g. PYTEST_ARGS='-m vision' (one area: core,
# servo, vision, sim, calibration, ros, cli, docs, robustness, package; docs/development.md).
# pytest-xdist (the test extra) runs them in PYTEST_WORKERS processes, an idle one taking tests
# queued on a busy one (worksteal: a MuJoCo closed loop takes minutes, most tests milliseconds);
# PYTEST_WORKERS=0 runs them all in pytest's own process.
PYTEST_WORKERS ?= 2
PYTEST_XDIST = -n $(PYTEST_WORKERS) --dist worksteal
test-python:
	$(PYTHON) -m pytest -q --durations=15 $(PYTEST_XDIST) $(PYTEST_ARGS)

# The Python tests without those marked slow: for the edit-test loop (make test runs them all).
test-fast:
	$(PYTHON) -m pytest -q -m "not slow" $(PYTEST_XDIST) $(PYTEST_ARGS)

stubtest:
	$(PYTHON) -m mypy.stubtest vsinv._core
	$(PYTHON) -m mypy python/vsinv
	$(PYTHON) tools/stub_docs.py --check

# The stub's docstrings (python/vsinv/_core.pyi) written from the extension's, the Rust `///`
# comments of src/python/ (tools/stub_docs.py): the extension is rebuilt first (4 min on the
# shared 2 cores even with nothing to compile), then every docstring of the stub is replaced by
# its text, the rest of the file left as it is. With the extension already rebuilt,
# `$(PYTHON) tools/stub_docs.py` alone does the second part in a second.
stubs:
	$(PIP) install -q -e . --no-deps
	$(PYTHON) tools/stub_docs.py

lint:
	cargo fmt --all --check
	cargo clippy --workspace --all-targets -- -D warnings
	cargo clippy --no-default-features -- -D warnings
	cargo clippy --no-default-features --features servo -- -D warnings
	cargo clippy --features python -- -D warnings
	RUSTDOCFLAGS="-D warnings" cargo doc --no-deps -q

# The documentation site in site/: the Rust API (cargo doc, warnings are errors), the pages' code
# run in docs/ (its figures land in docs/figures/; a failing block fails the build), then mkdocs
# in strict mode (a broken link or a docstring it cannot read fails the build). Installs the `docs`
# extra first when mkdocs is missing (after `make run`, which installs only what running needs).
docs:
	$(PYTHON) -c "import mkdocs, mkdocstrings, material" 2>/dev/null || $(PIP) install -v -e ".[docs]"
	$(PYTHON) docs/pages.py rust
	$(PYTHON) docs/pages.py run
	NO_MKDOCS_2_WARNING=1 $(PYTHON) -m mkdocs build --strict

# Every benchmark script of benches/ (each checks that vsinv agrees with its peer, or with itself,
# before it times anything, and exits non-zero when not); the criterion benches in Rust first
# (benches/tracker_mire2.rs runs from tracker_mire2.py). soak.py takes the longest (100,000 runs).
BENCH_SCRIPTS := bench_step compare vision tags_vs_opencv tags_tracked tags_robustness image_servo dots_vs_opencv \
	grey noise_honesty mount_error tracker_mire2 lens_change_accuracy hand_eye_vs_opencv ik hostile_rerun \
	ros_latency soak sweep mujoco_starts mujoco_sweep features_tracking features_matching features_mujoco features_vs_markers
bench: install
	cargo bench --bench vsinv
	for b in $(BENCH_SCRIPTS); do echo "== benches/$$b.py"; $(PYTHON) benches/$$b.py || exit 1; done

# Every bench once in its quick mode, so that a broken bench fails CI (.ci/run): criterion's
# test mode (each benchmark run once, from the release build of `cargo test --release`) and
# each script with --quick (a few rounds on small inputs, the agreement checks as in full).
# A bench whose peer or data is not installed (ViSP's C++ library, roboticstoolbox, rclpy,
# visp-images-data) says so and skips that part. Needs the package installed (make install).
bench-quick:
	cargo test --release --bench vsinv
	for b in $(BENCH_SCRIPTS); do echo "== benches/$$b.py --quick"; s=$$(date +%s); $(PYTHON) benches/$$b.py --quick || exit 1; echo "== benches/$$b.py --quick took $$(( $$(date +%s) - s )) s"; done

# Every built-in scenario with every key mutated (the CI part is tests/test_fuzz_scenarios.py),
# the image decoders and detectors on mutated image files for FUZZ_SECONDS (the CI part replays
# the corpus of tests/fixtures/fuzz and a fixed sequence of mutations), and the property tests
# on new random examples (CI runs a fixed sequence).
FUZZ_SECONDS ?= 120
fuzz: install
	$(PYTHON) tests/scenario_fuzz.py
	VSINV_FUZZ_SECONDS=$(FUZZ_SECONDS) cargo test --release --test integration fuzz_images::mutations -- --nocapture
	VSINV_HYPOTHESIS=explore $(PYTHON) -m pytest -q tests/test_robustness_*.py tests/test_api.py tests/test_se3.py
	VSINV_PROPTEST_RANDOM=1 cargo test --release --test integration -- $(addsuffix ::,$(ROBUSTNESS_TESTS)) invariance::

# 100,000 simulated runs and 1,000,000 controller steps; fails if resident memory grows > 5 MB.
soak: install-run
	$(PYTHON) benches/soak.py

# IBVS does not converge on a lens change: its exit code 1 (not converged) is the point of the comparison.
run: install-run
	$(PYTHON) -m vsinv run lens-12-6 --out results/lens-12-6
	$(PYTHON) -m vsinv run ibvs-12-6 --out results/ibvs-12-6 || test $$? -eq 1

# The wheel and sdist people install: one abi3 wheel (CPython 3.9 and later) tagged manylinux2014
# (glibc 2.17 and later), linked with zig (the `ziglang` package from PyPI, no Docker), then installed
# in a fresh virtual environment per interpreter of WHEEL_PYTHONS, which runs the main job from it.
# The first build took 12.5 minutes on a shared 2-core machine (zig builds every crate again);
# with target/ holding that build, the whole target took 47 s (install and run: ~20 s a Python).
WHEEL_DIR ?= target/dist
WHEEL_PYTHONS ?= $(PYTHON)
WHEEL_FLAGS ?= --zig --compatibility manylinux2014
MATURIN ?= maturin
wheels:
	$(PIP) install -q "maturin>=1.9.4,<2" ziglang
	rm -rf $(WHEEL_DIR)
	PATH="$$($(PYTHON) -c 'import os, ziglang; print(os.path.dirname(ziglang.__file__))'):$$PATH" \
		$(MATURIN) build --release $(WHEEL_FLAGS) -o $(WHEEL_DIR)
	$(MATURIN) sdist -o $(WHEEL_DIR)
	$(PYTHON) tests/wheel_smoke.py $(WHEEL_DIR) $(WHEEL_PYTHONS)
