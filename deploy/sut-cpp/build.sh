#!/usr/bin/env bash
# Build the C++ example SUT (deploy/sut-cpp): OSI 3.7.0 bindings generated with protoc from the
# OSI descriptor set the project already depends on (betterosi ships the compiled osi3 .proto
# files as a FileDescriptorSet), compiled with g++ against Debian's libprotobuf and nlohmann/json.
#
#   bash deploy/sut-cpp/build.sh                 # prints the binary's path
#   bash deploy/sut-cpp/build.sh --out DIR       # and copies it to DIR/simtest-sut-cpp
#
# Cached by content: ~/.cache/simtest/sut-cpp/<key>/simtest-sut-cpp, <key> = sha256 of the sources,
# this script, the descriptor set and the protoc and g++ versions; an unchanged build returns at
# once. Needs g++, protoc and libprotobuf-dev (Debian protobuf-compiler, libprotobuf-dev) and
# nlohmann-json3-dev; deploy/setup.sh test installs them. The OSI descriptor set: --descriptor-set
# FILE, else read from betterosi with the project's Python ($PYTHON, default .venv/bin/python).
#
# By hand, the same steps:
#   protoc --descriptor_set_in=osi3_descriptor_set.pb --cpp_out=gen osi_*.proto
#   g++ -O2 -std=c++17 -Igen main.cc gen/osi_*.pb.cc -lprotobuf -pthread -o simtest-sut-cpp
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
CACHE_ROOT="${SIMTEST_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/simtest}"
PYTHON="${PYTHON:-$REPO/.venv/bin/python}"
OUT=""
DESCRIPTORS=""
while [[ "${1:-}" == --* ]]; do
    case "$1" in
        --out) OUT="$2"; shift 2 ;;
        --descriptor-set) DESCRIPTORS="$2"; shift 2 ;;
        *) echo "sut-cpp/build.sh: error: unknown option '$1'" >&2; exit 2 ;;
    esac
done
die() { echo "sut-cpp/build.sh: error: $*" >&2; exit 1; }
command -v g++ >/dev/null || die "g++ is not installed"
command -v protoc >/dev/null || die "protoc is not installed (apt-get install protobuf-compiler)"
[[ -f /usr/include/google/protobuf/message.h ]] || die "libprotobuf-dev is not installed"
[[ -f /usr/include/nlohmann/json.hpp ]] || die "nlohmann-json3-dev is not installed"

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
if [[ -z "$DESCRIPTORS" ]]; then
    DESCRIPTORS="$WORK/osi3.pb"
    "$PYTHON" - "$DESCRIPTORS" <<'PY' || die "cannot read the OSI descriptor set from betterosi ($PYTHON)"
import pathlib, sys
import betterosi
source = pathlib.Path(betterosi.__file__).parent / "generated" / "3.7.0" / "osi3_descriptor_set.pb"
pathlib.Path(sys.argv[1]).write_bytes(source.read_bytes())
PY
fi
KEY="$( { cat "$HERE"/*.cc "$HERE/build.sh" "$DESCRIPTORS"; protoc --version; g++ --version; } | sha256sum | cut -c1-16)"
DEST="$CACHE_ROOT/sut-cpp/$KEY"
BIN="$DEST/simtest-sut-cpp"
if [[ ! -x "$BIN" ]]; then
    mkdir -p "$WORK/gen"
    # Every OSI file of the set (the SensorView needs most of them); protoc lists them itself.
    mapfile -t FILES < <(protoc --descriptor_set_in="$DESCRIPTORS" \
        --decode=google.protobuf.FileDescriptorSet google/protobuf/descriptor.proto <"$DESCRIPTORS" \
        | sed -n 's/^  name: "\(osi_[a-z_]*\.proto\)"$/\1/p')
    [[ ${#FILES[@]} -gt 0 ]] || die "no osi_*.proto in the descriptor set $DESCRIPTORS"
    protoc --descriptor_set_in="$DESCRIPTORS" --cpp_out="$WORK/gen" "${FILES[@]}" \
        || die "protoc failed"
    # One object per file, two at a time (the generated OSI sources are large).
    objects=()
    for source in "$WORK"/gen/*.pb.cc "$HERE"/main.cc; do
        objects+=("$WORK/$(basename "${source%.cc}").o")
    done
    printf '%s\n' "$WORK"/gen/*.pb.cc "$HERE"/main.cc | xargs -P 2 -I{} sh -c \
        'g++ -O2 -std=c++17 -I"$1/gen" -c "$2" -o "$1/$(basename "${2%.cc}").o"' _ "$WORK" {} \
        || die "g++ failed"
    g++ -o "$WORK/simtest-sut-cpp" "${objects[@]}" -lprotobuf -pthread || die "linking failed"
    mkdir -p "$DEST"
    mv "$WORK/simtest-sut-cpp" "$BIN"
fi
if [[ -n "$OUT" ]]; then
    mkdir -p "$OUT"
    install -m 0755 "$BIN" "$OUT/simtest-sut-cpp"
fi
echo "$BIN"
