#!/usr/bin/env bash
# Set up this machine for simtest-operator, from the lock file (uv.lock) and Debian packages.
#
#   bash deploy/setup.sh run    # what running needs: git, the project and its runtime deps
#   bash deploy/setup.sh test   # plus the test/lint tools, PostgreSQL, Chromium and the real
#                               # node's container stack (containerd, runc, CNI plugins, iproute2)
#                               # and image build (buildah, debootstrap, gcc for the pause image)
#
# Python packages come only from uv.lock (`uv sync --frozen`: exact versions, hashes checked);
# uv itself is pinned below and installed from PyPI into the cache. Idempotent and quiet: a
# second run only checks (well under a second) and prints one line. Upgrade the lock with
# `make lock-upgrade` (docs/install.md).
set -euo pipefail
cd "$(dirname "$0")/.."

MODE=${1:-run}
VENV=${VENV:-.venv}
PYTHON=${PYTHON:-python3}
UV_VERSION=0.13.9
CACHE_ROOT="${SIMTEST_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/simtest}"

case "$MODE" in
  run) APT_PACKAGES=(git) ;;
  # protobuf-compiler: protoc for the example SUTs' OSI bindings (deploy/sut-go, deploy/sut-cpp);
  # g++, libprotobuf-dev, nlohmann-json3-dev: the C++ example SUT (deploy/sut-cpp/build.sh)
  test) APT_PACKAGES=(git postgresql chromium containerd runc containernetworking-plugins buildah
        debootstrap iproute2 gcc libc6-dev protobuf-compiler g++ libprotobuf-dev
        nlohmann-json3-dev) ;;
  *) echo "setup.sh: error: unknown mode '$MODE' (run or test)" >&2; exit 2 ;;
esac

# --- system packages ---------------------------------------------------------------------------
missing=()
for pkg in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing system packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  log="$(mktemp)"
  if ! { $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq \
      --no-install-recommends "${missing[@]}"; } >"$log" 2>&1; then
    cat "$log" >&2; rm -f "$log"; echo "setup: error: apt-get failed (output above)" >&2; exit 1
  fi
  rm -f "$log"
  # The tests start their own throw-away PostgreSQL and containerd; the packaged services need
  # not run (on machines with systemd they would start at install).
  $SUDO systemctl disable --now postgresql containerd >/dev/null 2>&1 || true
fi

# --- uv, pinned, from PyPI ---------------------------------------------------------------------
UV="$CACHE_ROOT/uv/$UV_VERSION/bin/uv"
if [ ! -x "$UV" ]; then
  echo "setup: installing uv $UV_VERSION"
  "$PYTHON" -m pip install -q --disable-pip-version-check --no-warn-script-location \
    --target "$CACHE_ROOT/uv/$UV_VERSION" "uv==$UV_VERSION"
fi

# --- the project, from the lock ----------------------------------------------------------------
# --frozen: install exactly uv.lock (never re-resolve); `make lint` checks the lock is current.
# run mode is --inexact so that it keeps the dev tools a `test` set-up installed. The ros2 extra
# (Cyclone DDS, rosbags: the ROS 2 bridge, docs/sut-interface.md) is part of every set-up, as of
# the images; only a plain `pip install simtest-operator` leaves it out.
export UV_PROJECT_ENVIRONMENT="$VENV" UV_PYTHON_DOWNLOADS=never UV_CACHE_DIR="$CACHE_ROOT/uv/cache"
# --compile-bytecode: this machine sets PYTHONDONTWRITEBYTECODE=1, so without it every Python
# process (CLI, operator, runner workers, each test's subprocess) compiled every module it imports
# from source again — scikit-learn alone took 9 s of CPU per process. Done once per set-up.
sync=("$UV" sync --frozen --quiet --compile-bytecode --extra ros2 --python "$PYTHON")
if [ "$MODE" = run ]; then sync+=(--no-dev --inexact); fi
if ! out="$("${sync[@]}" 2>&1)"; then
  echo "$out" >&2; echo "setup: error: uv sync failed (output above)" >&2; exit 1
fi
# The project itself is installed editable (its modules stay in src/): compiled the same way.
"$VENV/bin/python" -m compileall -q -j 0 src >/dev/null
echo "setup: ready ($("$VENV/bin/simtest" --version), $MODE, from uv.lock)"
