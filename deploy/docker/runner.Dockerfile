# syntax=docker/dockerfile:1.7
# The simulator image: `simtest-runner`, the SUMO-backed stand-in (SUMO and netconvert come from
# the eclipse-sumo and libsumo wheels, no system packages), recording and online evaluation.
#
#   docker build -f deploy/docker/runner.Dockerfile -t ghcr.io/simtest-dev/simtest-runner:0.1.0 .
#
# Build context: the repository root. Pin the base by digest with
# --build-arg PYTHON_IMAGE=python:3.11.11-slim-bookworm@sha256:<digest>.
ARG PYTHON_IMAGE=python:3.11.11-slim-bookworm

FROM ${PYTHON_IMAGE} AS build
ENV PIP_NO_CACHE_DIR=1 PIP_DISABLE_PIP_VERSION_CHECK=1 PYTHONDONTWRITEBYTECODE=1
RUN python -m venv /opt/simtest/venv
COPY deploy/docker/constraints.txt /tmp/constraints.txt
COPY pyproject.toml README.md /src/
COPY src /src/src
RUN /opt/simtest/venv/bin/pip install --constraint /tmp/constraints.txt /src \
    && /opt/simtest/venv/bin/python -m compileall -q /opt/simtest/venv \
    # Fail the build, not the first scenario, when the SUMO wheels are unusable.
    && /opt/simtest/venv/bin/python -c "import libsumo, sumo, sumolib; print(sumo.SUMO_HOME)"

FROM ${PYTHON_IMAGE}
LABEL org.opencontainers.image.title="simtest-runner" \
      org.opencontainers.image.description="SUMO-backed OpenSCENARIO simulator stand-in" \
      org.opencontainers.image.source="https://github.com/simtest-dev/simtest-operator" \
      org.opencontainers.image.licenses="Apache-2.0"
COPY --from=build /opt/simtest/venv /opt/simtest/venv
ENV PATH=/opt/simtest/venv/bin:$PATH \
    PYTHONUNBUFFERED=1 \
    PYTHONDONTWRITEBYTECODE=1 \
    HOME=/tmp \
    SIMTEST_CACHE_DIR=/tmp/simtest-cache
# Matches the runAsUser of the rendered simulator pod (restricted Pod Security profile); the pod
# mounts /tmp and /artifacts, the root filesystem stays read-only.
USER 65532:65532
WORKDIR /tmp
ENTRYPOINT ["simtest-runner"]
