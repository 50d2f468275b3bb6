# ti_golf: `make demo` and `make test` work on a fresh machine (they create .venv and install).
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
TIGOLF := $(VENV)/bin/ti-golf
STAMP  := $(VENV)/.installed
OUT    ?= out

.PHONY: setup demo test test-fast test-slow bench gpu-check gpu-test lint docs docs-keys wheel-check system-deps clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test,bench,cluster]"
	touch $(STAMP)

# The package's bytecode, compiled as pip compiles a wheel's: Python does it at import unless
# PYTHONDONTWRITEBYTECODE forbids it, and then every command would compile the package again (0.15 s).
setup: $(STAMP)
	@$(PY) -m compileall -q ti_golf > /dev/null || true

# Linters, type checker and docs tools, installed on first use of lint or docs.
DEVSTAMP := $(VENV)/.installed-dev
$(DEVSTAMP): $(STAMP)
	$(PY) -m pip install --quiet -e ".[test,bench,cluster,dev,docs]"
	touch $(DEVSTAMP)

# The software Vulkan driver for off-screen GGUI rendering (needs root and apt-get; skipped otherwise).
system-deps:
	@if command -v apt-get >/dev/null 2>&1 && [ "$$(id -u)" = 0 ]; then \
	  dpkg -s mesa-vulkan-drivers >/dev/null 2>&1 || \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null; } \
	  || echo "system-deps: could not install mesa-vulkan-drivers; rendering tests will be skipped"; \
	else echo "system-deps: not root or no apt-get; skipping mesa-vulkan-drivers"; fi

demo: setup system-deps
	mkdir -p $(OUT)
	$(TIGOLF) table --plot $(OUT)/lab_table.png
	$(TIGOLF) tour --plot $(OUT)/tour_table.png
	$(TIGOLF) sweep lab_turbulent --angles 32:42:0.5 --out $(OUT)/sweep_turbulent.csv --plot $(OUT)/sweep_turbulent.png
	$(TIGOLF) dispersion tour_shot --seed 1 --plot $(OUT)/dispersion.png
	$(TIGOLF) run lab_spin_decay --until rest --out $(OUT)/spin_decay.npz --plot $(OUT)/spin_decay.png
	$(TIGOLF) run break_shot --until rest --out $(OUT)/break_shot.npz --plot $(OUT)/break_shot.png
	$(TIGOLF) render break_shot --steps 400 --camera iso --trails --out $(OUT)/break_shot_3d.png
	$(TIGOLF) run ball_pit --t 0.4 --frames-every 20 --gif $(OUT)/ball_pit.gif --out $(OUT)/ball_pit.npz
	$(TIGOLF) render --resume $(OUT)/ball_pit.npz --out $(OUT)/ball_pit.png
	$(TIGOLF) play golf_hole --seed 3 --shots scenes/golf_hole_round.txt --out $(OUT)/golf_round.csv --plot $(OUT)/golf_round.png

# The test suite on two pytest-xdist workers, a test file at a time, the files of slow tests (pours,
# processes that compile their own kernels, renders in subprocesses) handed out first.
PYTEST := $(PY) -m pytest -q -n 2 --dist loadfile --no-loadscope-reorder

test: setup system-deps
	$(PYTEST) --durations=15

# The fast tier, before a commit: every test not marked slow (tests/conftest.py says what is).
test-fast: setup
	$(PYTEST) -m "not slow" --durations=10

# The rest: the slow tests alone (.ci/run runs the fast tier first, then these).
test-slow: setup system-deps
	$(PYTEST) -m slow --durations=15

# ruff (lint and format), mypy over the package (strict on the public API), and the import layers (pyproject.toml).
lint: $(DEVSTAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	$(VENV)/bin/mypy
	$(VENV)/bin/lint-imports

# The documentation site, warnings as errors, into site/.
docs: $(DEVSTAMP)
	$(VENV)/bin/mkdocs build --strict --site-dir site

# The scene key reference of docs/scenes.md, made anew from the key declarations (a test checks it).
docs-keys: setup
	$(PY) docs/_hooks/generate.py

# The wheel, installed into a fresh venv outside the checkout, runs its commands and bundled scenes.
wheel-check: setup
	PYTHON=$(PY) bash .ci/wheel_check.sh

bench: setup
	$(TIGOLF) bench sweep --json

# On a machine with an NVIDIA GPU: every GPU figure of docs/performance.md, each under a time limit,
# into $(OUT)/gpu_check.json (see .ci/gpu_check.sh); gpu-test runs the flight-physics tests on CUDA.
gpu-check: setup
	PY=$(PY) GPU_CHECK_OUT=$(OUT) bash .ci/gpu_check.sh

gpu-test: setup
	TI_GOLF_TEST_ARCH=cuda $(PY) -m pytest -q -x tests/test_physics_verification.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache site
