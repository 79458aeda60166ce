# syntax=docker/dockerfile:1.7
# The operator image: `simtest operator` (kopf) plus the environment templates (helm-templates/).
#
#   docker build -f deploy/docker/operator.Dockerfile -t ghcr.io/simtest-dev/simtest-operator:0.1.0 .
#   bash deploy/docker/build.sh operator   # here: buildah, local bases, cached (docs/images.md)
#
# Build context: the repository root. Python packages are exactly uv.lock (`uv sync --frozen`,
# hashes checked), with the ros2 extra (the ROS 2 bridge runs from the runner image).
# The first two stages are runner.Dockerfile's too (keep them identical: the
# two images then share their dependency layer). Pin the bases by digest with
# --build-arg PYTHON_IMAGE=python:3.11.11-slim-bookworm@sha256:<digest>.
ARG PYTHON_IMAGE=python:3.11.11-slim-bookworm
ARG UV_IMAGE=ghcr.io/astral-sh/uv:0.13.9

FROM ${UV_IMAGE} AS uv

# The base plus the locked dependencies, and nothing else: the final image starts FROM here, so
# this layer changes only with uv.lock or pyproject.toml (a source change never reinstalls SUMO)
# and is the same layer in the runner and operator images. uv is mounted, not copied; uv.lock
# stays in the image at /opt/simtest/uv.lock; uv's cache is /root/.cache/uv (deploy/docker/
# build.sh mounts the host's there). hardlink: eclipse-sumo and libsumo bundle the same 111
# shared libraries (230 MB); identical files become one.
FROM ${PYTHON_IMAGE} AS deps
COPY pyproject.toml uv.lock /opt/simtest/
RUN --mount=from=uv,source=/uv,target=/bin/uv \
    cd /opt/simtest \
    && UV_PROJECT_ENVIRONMENT=/opt/simtest/venv UV_PYTHON=python3.11 UV_PYTHON_DOWNLOADS=never \
       UV_LINK_MODE=copy UV_COMPILE_BYTECODE=1 UV_SYSTEM_CERTS=1 UV_CACHE_DIR=/root/.cache/uv \
       uv sync --frozen --no-dev --no-editable --extra ros2 --no-install-project \
    && hardlink --ignore-time --quiet /opt/simtest/venv

# The project on top; /out holds only its own files (package, metadata, console scripts), which
# the final image gets as a small layer of their own.
FROM deps AS project
COPY pyproject.toml uv.lock README.md LICENSE /src/
COPY src /src/src
RUN --mount=from=uv,source=/uv,target=/bin/uv \
    cd /src \
    && UV_PROJECT_ENVIRONMENT=/opt/simtest/venv UV_PYTHON=python3.11 UV_PYTHON_DOWNLOADS=never \
       UV_LINK_MODE=copy UV_COMPILE_BYTECODE=1 UV_SYSTEM_CERTS=1 UV_CACHE_DIR=/root/.cache/uv \
       uv sync --frozen --no-dev --no-editable --extra ros2 \
    && sp="$(/opt/simtest/venv/bin/python -c 'import sysconfig; print(sysconfig.get_path("purelib"))')" \
    && info="$(echo "$sp"/simtest_operator-*.dist-info)" \
    && mkdir -p "/out$sp" /out/opt/simtest/venv/bin \
    && cp -a "$info" "/out$sp/" \
    && for top in $(cat "$info/top_level.txt"); do cp -a "$sp/$top" "/out$sp/"; done \
    && grep -o '^\.\./\.\./\.\./bin/[^,]*' "$info/RECORD" | xargs -I{} cp -a "$sp/{}" /out/opt/simtest/venv/bin/

FROM deps
LABEL org.opencontainers.image.title="simtest-operator" \
      org.opencontainers.image.description="Kopf operator for scenario-based simulation testing" \
      org.opencontainers.image.source="https://github.com/simtest-dev/simtest-operator" \
      org.opencontainers.image.licenses="Apache-2.0"
COPY --from=project /out/ /
COPY helm-templates /opt/simtest/helm-templates
# SIMTEST_LOCK_FILE: the lock the image was installed from; a run's reproducibility record
# names its digest.
ENV PATH=/opt/simtest/venv/bin:$PATH \
    PYTHONUNBUFFERED=1 \
    PYTHONDONTWRITEBYTECODE=1 \
    HOME=/tmp \
    SIMTEST_OPERATOR_TEMPLATES=/opt/simtest/helm-templates \
    SIMTEST_OPERATOR_CACHE=/tmp/simtest-operator-cache \
    SIMTEST_LOCK_FILE=/opt/simtest/uv.lock
RUN simtest --version >/dev/null
# Numeric, so kubelet can verify runAsNonRoot; matches the chart's podSecurityContext.
USER 65532:65532
WORKDIR /tmp
EXPOSE 8080
ENTRYPOINT ["simtest"]
CMD ["operator"]
