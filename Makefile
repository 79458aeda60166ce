# The two README commands: `make run` (the main job on its embedded default) and `make test`.
# Both set up a fresh machine first from the lock file (uv.lock): `run` only what running needs,
# `test` also the test tools, the Debian packages the tests start, and the Kubernetes control
# plane built from Go modules (cached in ~/.cache/simtest).
VENV ?= .venv
SIMTEST := $(VENV)/bin/simtest
UV = $${SIMTEST_CACHE_DIR:-$$HOME/.cache/simtest}/uv/$$(sed -n 's/^UV_VERSION=//p' deploy/setup.sh)/bin/uv

.PHONY: setup setup-run toolchain images run test lint crds lock-upgrade

setup-run:
	@bash deploy/setup.sh run

setup:
	@bash deploy/setup.sh test

toolchain:
	bash deploy/devcluster/build.sh

# The container images (runner, operator, helmfile, device plugin, pause), built with buildah on
# locally made bases and cached by content; the dev cluster's real node imports them.
images: setup toolchain
	bash deploy/docker/build.sh

# simtest run exits 1 when a scenario fails; the smoke campaign has one deliberately failing
# cut-in, so 0 and 1 both mean the run worked (2 means errors or invalid input).
run: setup-run
	$(SIMTEST) run scenarios/smoke-campaign.yaml --output out/smoke; rc=$$?; \
	if [ $$rc -le 1 ]; then echo "open out/smoke/report.html for the report"; fi; \
	[ $$rc -le 1 ]

# pytest's exit code 5 (no tests collected) is a failure here, not a pass.
test: setup toolchain images
	$(VENV)/bin/python -m pytest $(PYTEST_ARGS); rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "pytest collected no tests" >&2; exit 1; fi; exit $$rc

lint: setup
	$(UV) lock --check --quiet
	$(VENV)/bin/ruff check src tests bench scenarios
	$(VENV)/bin/ruff format --check src tests bench scenarios
	$(VENV)/bin/mypy
	$(VENV)/bin/lint-imports

# Regenerate everything derived from the API models: CRDs and their reference, the chart's
# copies, and the rendered chart goldens (the kustomize base is one of them).
crds: setup toolchain
	$(SIMTEST) crds
	$(SIMTEST) package sync
	$(VENV)/bin/python -m pytest -q tests/charts/test_chart_golden.py --update-golden

# Move every locked Python package to the newest version pyproject.toml allows, then run the tests.
lock-upgrade: setup
	$(UV) lock --upgrade
	@echo "uv.lock upgraded; review 'git diff uv.lock', then run make test"
