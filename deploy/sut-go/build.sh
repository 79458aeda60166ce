#!/usr/bin/env bash
# Build the Go example SUT (deploy/sut-go): OSI 3.7.0 bindings generated with protoc and
# protoc-gen-go from the OSI descriptor set the project already depends on (betterosi ships the
# compiled osi3 .proto files as a FileDescriptorSet), then a static binary.
#
#   bash deploy/sut-go/build.sh                 # prints the binary's path
#   bash deploy/sut-go/build.sh --out DIR       # and copies it to DIR/simtest-sut-go
#
# Cached by content: ~/.cache/simtest/sut-go/<key>/simtest-sut-go, <key> = sha256 of the Go
# sources, go.mod/go.sum, the descriptor set, and the protoc and Go versions; an unchanged
# build returns at once. Needs go, protoc (Debian protobuf-compiler; deploy/setup.sh test
# installs it) and the OSI descriptor set: --descriptor-set FILE, else read from betterosi with
# the project's Python ($PYTHON, default .venv/bin/python).
# protoc-gen-go is built from google.golang.org/protobuf at the version go.mod pins.
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
        *) echo "sut-go/build.sh: error: unknown option '$1'" >&2; exit 2 ;;
    esac
done
die() { echo "sut-go/build.sh: error: $*" >&2; exit 1; }
command -v go >/dev/null || die "go is not installed"
command -v protoc >/dev/null || die "protoc is not installed (apt-get install protobuf-compiler)"

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
PGG_VERSION="$(awk '$1 == "require" && $2 == "google.golang.org/protobuf" {print $3}' "$HERE/go.mod")"
KEY="$( { cat "$HERE"/go.mod "$HERE"/go.sum "$HERE"/*.go "$HERE/build.sh" "$DESCRIPTORS"; protoc --version; go version; } | sha256sum | cut -c1-16)"
DEST="$CACHE_ROOT/sut-go/$KEY"
BIN="$DEST/simtest-sut-go"
if [[ ! -x "$BIN" ]]; then
    export GOMODCACHE="${GOMODCACHE:-$CACHE_ROOT/toolchain/gomodcache}" GOCACHE="${GOCACHE:-$CACHE_ROOT/toolchain/gocache}"
    export GOFLAGS=-mod=mod CGO_ENABLED=0
    GOBIN="$WORK/bin" go install "google.golang.org/protobuf/cmd/protoc-gen-go@$PGG_VERSION" \
        || die "cannot build protoc-gen-go $PGG_VERSION"
    mkdir -p "$WORK/src/osi3"
    cp "$HERE"/go.mod "$HERE"/go.sum "$HERE"/*.go "$WORK/src/"
    # Every OSI file of the set (the SensorView needs most of them), one Go package osi3; protoc
    # lists them itself (the set carries descriptor.proto too).
    mapfile -t FILES < <(protoc --descriptor_set_in="$DESCRIPTORS" \
        --decode=google.protobuf.FileDescriptorSet google/protobuf/descriptor.proto <"$DESCRIPTORS" \
        | sed -n 's/^  name: "\(osi_[a-z_]*\.proto\)"$/\1/p')
    [[ ${#FILES[@]} -gt 0 ]] || die "no osi_*.proto in the descriptor set $DESCRIPTORS"
    MAPS=()
    for f in "${FILES[@]}"; do MAPS+=("--go_opt=M$f=simtest.dev/sut-go/osi3"); done
    PATH="$WORK/bin:$PATH" protoc --descriptor_set_in="$DESCRIPTORS" \
        --go_out="$WORK/src/osi3" --go_opt=paths=source_relative "${MAPS[@]}" "${FILES[@]}" \
        || die "protoc failed"
    (cd "$WORK/src" && go build -trimpath -ldflags="-s -w -X main.buildKey=$KEY" -o "$WORK/simtest-sut-go" .) \
        || die "go build failed"
    mkdir -p "$DEST"
    mv "$WORK/simtest-sut-go" "$BIN"
fi
if [[ -n "$OUT" ]]; then
    mkdir -p "$OUT"
    install -m 0755 "$BIN" "$OUT/simtest-sut-go"
fi
echo "$BIN"
