# syntax=docker/dockerfile:1.7
# The operator image: `simtest operator` (kopf) plus the environment templates (helm-templates/).
#
#   docker build -f deploy/docker/operator.Dockerfile -t ghcr.io/simtest-dev/simtest-operator:0.1.0 .
#
# Build context: the repository root. Base images are pinned by version; pin them by digest too
# with --build-arg PYTHON_IMAGE=python:3.11.11-slim-bookworm@sha256:<digest>.
# Python packages are pinned by deploy/docker/constraints.txt (the tested set).
ARG PYTHON_IMAGE=python:3.11.11-slim-bookworm

FROM ${PYTHON_IMAGE} AS build
ENV PIP_NO_CACHE_DIR=1 PIP_DISABLE_PIP_VERSION_CHECK=1 PYTHONDONTWRITEBYTECODE=1
RUN python -m venv /opt/simtest/venv
COPY deploy/docker/constraints.txt /tmp/constraints.txt
COPY pyproject.toml README.md /src/
COPY src /src/src
RUN /opt/simtest/venv/bin/pip install --constraint /tmp/constraints.txt /src \
    && /opt/simtest/venv/bin/python -m compileall -q /opt/simtest/venv

FROM ${PYTHON_IMAGE}
LABEL org.opencontainers.image.title="simtest-operator" \
      org.opencontainers.image.description="Kopf operator for scenario-based simulation testing" \
      org.opencontainers.image.source="https://github.com/simtest-dev/simtest-operator" \
      org.opencontainers.image.licenses="Apache-2.0"
COPY --from=build /opt/simtest/venv /opt/simtest/venv
COPY helm-templates /opt/simtest/helm-templates
ENV PATH=/opt/simtest/venv/bin:$PATH \
    PYTHONUNBUFFERED=1 \
    PYTHONDONTWRITEBYTECODE=1 \
    HOME=/tmp \
    SIMTEST_OPERATOR_TEMPLATES=/opt/simtest/helm-templates \
    SIMTEST_OPERATOR_CACHE=/tmp/simtest-operator-cache
# Numeric, so kubelet can verify runAsNonRoot; matches the chart's podSecurityContext.
USER 65532:65532
WORKDIR /tmp
EXPOSE 8080
ENTRYPOINT ["simtest"]
CMD ["operator"]
