# syntax=docker/dockerfile:1.7
# The simulator image: `simtest-runner`, the SUMO-backed stand-in (SUMO and netconvert come from
# the eclipse-sumo and libsumo wheels; Debian adds only the X11/GL client libraries they link),
# recording and online evaluation, plus git for `git+` scenario sources.
#
#   docker build -f deploy/docker/runner.Dockerfile -t ghcr.io/simtest-dev/simtest-runner:0.1.0 .
#   bash deploy/docker/build.sh runner     # here: buildah, local bases, cached (docs/images.md)
#
# Build context: the repository root. Python packages are exactly uv.lock (`uv sync --frozen`,
# hashes checked), with the ros2 extra (the ROS 2 bridge runs from the runner image).
# The first two stages are operator.Dockerfile's too (keep them identical: the
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
LABEL org.opencontainers.image.title="simtest-runner" \
      org.opencontainers.image.description="SUMO-backed OpenSCENARIO simulator stand-in" \
      org.opencontainers.image.source="https://github.com/simtest-dev/simtest-operator" \
      org.opencontainers.image.licenses="Apache-2.0"
# git for git+ scenario sources. The SUMO binaries and libsumo link X11 and libGL although they
# never draw: the X11 client libraries and glvnd's libGL come from Debian, Mesa's drivers
# (about 200 MB with LLVM) do not; an empty package stands in for libglx-mesa0.
RUN mkdir -p /tmp/headless-gl/DEBIAN \
    && printf '%s\n' 'Package: simtest-headless-gl' 'Version: 1.0' 'Architecture: all' \
        'Maintainer: simtest <noreply@simtest.dev>' 'Provides: libglx-mesa0' \
        'Description: headless stand-in for Mesa (SUMO links libGL but never draws)' \
        >/tmp/headless-gl/DEBIAN/control \
    && dpkg-deb --build /tmp/headless-gl /tmp/headless-gl.deb >/dev/null \
    && dpkg -i /tmp/headless-gl.deb >/dev/null \
    && apt-get update -qq \
    && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        git libgl1 libx11-6 libxext6 libxrender1 libatomic1 >/dev/null \
    && apt-get clean \
    && rm -rf /tmp/headless-gl* /var/lib/apt/lists/* /var/log/apt/* /var/log/dpkg.log \
        /var/cache/ldconfig/aux-cache
COPY --from=project /out/ /
# SIMTEST_LOCK_FILE: the lock the image was installed from; a run's reproducibility record
# names its digest.
ENV PATH=/opt/simtest/venv/bin:$PATH \
    PYTHONUNBUFFERED=1 \
    PYTHONDONTWRITEBYTECODE=1 \
    HOME=/tmp \
    SIMTEST_CACHE_DIR=/tmp/simtest-cache \
    SIMTEST_LOCK_FILE=/opt/simtest/uv.lock
# Fail the build, not the first scenario, when SUMO cannot load (writes nothing).
RUN python -c "import libsumo, sumolib, traci" \
    && sumo --version >/dev/null && netconvert --version >/dev/null \
    && simtest-runner --help >/dev/null && simtest-ros2-bridge --help >/dev/null
# Matches the runAsUser of the rendered simulator pod (restricted Pod Security profile); the pod
# mounts /tmp and /artifacts, the root filesystem stays read-only.
USER 65532:65532
WORKDIR /tmp
ENTRYPOINT ["simtest-runner"]
