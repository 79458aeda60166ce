# The two README commands: `make run` (the main job on its embedded default) and `make test`.
# Both set up a fresh machine first (system packages, virtualenv, and for the tests the
# Kubernetes control plane built from Go modules, cached in ~/.cache/simtest).
VENV ?= .venv
SIMTEST := $(VENV)/bin/simtest

.PHONY: setup toolchain run test lint crds

setup:
	bash deploy/setup.sh

toolchain:
	bash deploy/devcluster/build.sh

# simtest run exits 1 when a scenario fails; the smoke campaign has one deliberately failing
# cut-in, so 0 and 1 both mean the run worked (2 means errors or invalid input).
run: setup
	$(SIMTEST) run scenarios/smoke-campaign.yaml --output out/smoke; rc=$$?; \
	if [ $$rc -le 1 ]; then echo "open out/smoke/report.html for the report"; fi; \
	[ $$rc -le 1 ]

# pytest's exit code 5 (no tests collected) is a failure here, not a pass.
test: setup toolchain
	$(VENV)/bin/python -m pytest $(PYTEST_ARGS); rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "pytest collected no tests" >&2; exit 1; fi; exit $$rc

lint: setup
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
