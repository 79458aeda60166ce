# syntax=docker/dockerfile:1.7
# The Go example SUT (deploy/sut-go): a system under test in another language speaking the OSI SUT
# protocol (docs/sut-interface.md). Run it as the sidecar of a campaign:
# spec.environment.sut.external.image. The binary is built by the one recipe the tests use
# (deploy/sut-go/build.sh: protoc + protoc-gen-go on the OSI 3.7.0 descriptor set, static,
# -trimpath), so the image runs exactly what the tests ran.
#
#   docker build -f deploy/docker/sut-go.Dockerfile -t ghcr.io/simtest-dev/simtest-sut-go:0.1.0 .
#   bash deploy/docker/build.sh sut-go     # here: buildah, local bases, cached (docs/images.md)
#
# Build context: the repository root. The OSI descriptor set comes from betterosi as uv.lock pins
# it: the first two stages are runner.Dockerfile's (keep them identical: the layer is shared).
ARG PYTHON_IMAGE=python:3.11.11-slim-bookworm
ARG UV_IMAGE=ghcr.io/astral-sh/uv:0.13.9
ARG GO_IMAGE=golang:1.26.8-bookworm
ARG RUNTIME_IMAGE=scratch

FROM ${UV_IMAGE} AS uv

FROM ${PYTHON_IMAGE} AS deps
COPY pyproject.toml uv.lock /opt/simtest/
RUN --mount=from=uv,source=/uv,target=/bin/uv \
    cd /opt/simtest \
    && UV_PROJECT_ENVIRONMENT=/opt/simtest/venv UV_PYTHON=python3.11 UV_PYTHON_DOWNLOADS=never \
       UV_LINK_MODE=copy UV_COMPILE_BYTECODE=1 UV_SYSTEM_CERTS=1 UV_CACHE_DIR=/root/.cache/uv \
       uv sync --frozen --no-dev --no-editable --no-install-project \
    && hardlink --ignore-time --quiet /opt/simtest/venv

FROM deps AS descriptors
RUN /opt/simtest/venv/bin/python -c "import betterosi, pathlib, shutil; shutil.copy(pathlib.Path(betterosi.__file__).parent / 'generated/3.7.0/osi3_descriptor_set.pb', '/osi3.pb')"

FROM ${GO_IMAGE} AS build
RUN apt-get update -qq \
    && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends protobuf-compiler >/dev/null \
    && rm -rf /var/lib/apt/lists/*
COPY --from=descriptors /osi3.pb /osi3.pb
COPY deploy/sut-go /src/deploy/sut-go
RUN SIMTEST_CACHE_DIR=/build bash /src/deploy/sut-go/build.sh --descriptor-set /osi3.pb --out /out

# A static binary needs nothing else.
FROM ${RUNTIME_IMAGE}
LABEL org.opencontainers.image.title="simtest-sut-go" \
      org.opencontainers.image.description="Example system under test in Go for the simtest OSI SUT protocol" \
      org.opencontainers.image.source="https://github.com/simtest-dev/simtest-operator" \
      org.opencontainers.image.licenses="Apache-2.0"
COPY --from=build /out/simtest-sut-go /simtest-sut-go
# Matches the restricted profile of the simulator pod (non-root, read-only root file system).
USER 65532:65532
ENTRYPOINT ["/simtest-sut-go"]
