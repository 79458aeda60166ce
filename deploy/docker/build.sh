#!/usr/bin/env bash
# Build the project's container images with buildah, on bases made here (no registry needed),
# cached by content.
#
#   bash deploy/docker/build.sh                    # all: runner operator helmfile device-plugin sut-go pause
#   bash deploy/docker/build.sh runner pause       # a subset (the bases they need come along)
#   bash deploy/docker/build.sh bases              # only the local bases
#   bash deploy/docker/build.sh --cache-dir DIR …  # instead of $SIMTEST_CACHE_DIR
#   bash deploy/docker/build.sh --prune            # then drop the layer cache and stray archives
#
# Idempotent: an image whose content key is unchanged is not rebuilt (a few seconds in all).
# Elsewhere, with a registry, the Dockerfiles build as they are on their public bases
# (`docker build -f deploy/docker/runner.Dockerfile .`); docs/images.md has the details.
#
# Output: ${SIMTEST_CACHE_DIR:-${XDG_CACHE_HOME:-~/.cache}/simtest}/images/
#   images.json              image name -> OCI archive, manifest digest, sizes (a real node
#                            imports the archives: `ctr -n k8s.io images import FILE`)
#   <image>-<key>.oci.tar    one OCI archive per image, <key> = digest of everything it is made of
#   storage/                 buildah's image store: the bases, the images, the layer cache
#   logs/                    the last build log of each image
#
# The images (bases first, each keyed by its own content and its base's image ID):
#   base-debian   localhost/simtest-base/debian:bookworm-slim   debootstrap --variant=minbase
#   base-python   localhost/simtest-base/python:3.11-bookworm   + Debian's python3.11 (for PYTHON_IMAGE)
#   base-uv       localhost/simtest-base/uv:<uv>                /uv from the PyPI wheel (for UV_IMAGE)
#   base-golang   localhost/simtest-base/golang:<go>-bookworm   + this machine's Go (for GO_IMAGE)
#   pause         localhost/simtest/pause:<v>                   deploy/docker/pause/pause.c, FROM scratch
#   runner operator helmfile device-plugin sut-go               deploy/docker/<name>.Dockerfile
#
# What buildah 1.28 (Debian bookworm) needs on this machine kind, found by trying:
#   storage   overlay on the ext4 cache (native overlay diff); vfs would copy every layer in
#             full. A store of our own (--root/--runroot) keeps the project's layers out of
#             /var/lib/containers; drop_stale keeps it to the current images and their cache.
#   isolation oci (runc 1.1, the default; BUILDAH_ISOLATION=chroot works too): each RUN step in
#             its own pid/mount/ipc/uts namespaces as with docker build. The VM's refusal to
#             lower oom_score_adj (real-node.md) does not matter: buildah does not ask.
#   network   --network host for RUN steps: no CNI set-up or iptables needed, and the egress
#             proxy stays transparent. PyPI, the Go proxy and Debian (http) are reached.
#   TLS       egress goes through a TLS-intercepting proxy whose CA is only in the host's bundle.
#             The bundle is bind-mounted read-only over /etc/ssl/certs/ca-certificates.crt for
#             RUN steps only (`bud -v`): never part of a layer (no_proxy_ca checks every image).
#             uv reads it with UV_SYSTEM_CERTS=1 (set in the Dockerfiles' RUN steps, harmless
#             elsewhere); Go reads it as the system pool; apt needs none (http, signed indexes).
#   caches    the host's uv cache ($CACHE_ROOT/uv/cache) and Go caches ($CACHE_ROOT/toolchain/
#             gomodcache, gocache) are bind-mounted into RUN steps (`bud -v`), so an image
#             build reuses what deploy/setup.sh and deploy/devcluster/build.sh fetched and
#             compiled (helm and helmfile link in seconds). Not `RUN --mount=type=cache` in the
#             Dockerfiles: buildah keeps those in /var/tmp/buildah-cache, apart from the host's
#             caches, and which of the two a RUN sees when both name a path is not reliable.
#   layers    --layers caches RUN and COPY-from-context steps by parent and content, but never a
#             `COPY --from=<stage>`: the Python images' final stages therefore start FROM the
#             dependency stage instead of copying the venv (else every build re-copies 1.9 GB).
#   flags     --pull=never, with the `=`: --pull takes an optional value, and `--pull never`
#             leaves "never" as a stray argument ("too many arguments specified").
#   archives  `buildah push … oci:DIR:NAME` plus the io.containerd.image.name annotation, then
#             tar: `ctr images import` names the image from it. zstd layers: containerd 1.6
#             imports and runs them; a third faster to write than gzip and 14 % smaller.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"

CACHE_ROOT="${SIMTEST_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/simtest}"
PRUNE=0
while [[ "${1:-}" == --* ]]; do
    case "$1" in
        --cache-dir)
            [[ -n "${2:-}" ]] || { echo "build.sh: error: --cache-dir needs a directory" >&2; exit 2; }
            CACHE_ROOT="$2"; shift 2 ;;
        --prune) PRUNE=1; shift ;;
        *) echo "build.sh: error: unknown option '$1'" >&2; exit 2 ;;
    esac
done
IMG="$CACHE_ROOT/images"
STORE="$IMG/storage"
# Run-time state (locks, mount counts) must not outlive a reboot: /run, one per store.
RUNROOT="/run/simtest-buildah/$(printf '%s' "$STORE" | sha256sum | cut -c1-12)"
TC="$CACHE_ROOT/toolchain"
UV_CACHE="$CACHE_ROOT/uv/cache"
ALL_TARGETS=(runner operator helmfile device-plugin sut-go pause)
ISOLATION="${BUILDAH_ISOLATION:-oci}"
CA_BUNDLE="${SSL_CERT_FILE:-/etc/ssl/certs/ca-certificates.crt}"
KEY_LABEL=dev.simtest.build-key

# --- versions: each read from the one place it is pinned -------------------------------------
PROJECT_VERSION="$(sed -n 's/^version = "\(.*\)"$/\1/p' "$REPO/pyproject.toml" | head -n 1)"
UV_VERSION="$(sed -n 's/^UV_VERSION=//p' "$REPO/deploy/setup.sh")"
PAUSE_VERSION="$(sed -n 's/^#define PAUSE_VERSION "\(.*\)"$/\1/p' "$HERE/pause/pause.c")"
# Debian: the bookworm suite as the mirror serves it. deb.debian.org keeps only the current point
# release, so the base records the one it was made from (labels, below) and the build warns when
# the suite has moved past DEBIAN_POINT_RELEASE. For a bit-for-bit rebuild point
# SIMTEST_DEBIAN_MIRROR at a snapshot (http://snapshot.debian.org/archive/debian/<timestamp>);
# snapshot.debian.org is not reachable from this machine.
DEBIAN_SUITE=bookworm
DEBIAN_POINT_RELEASE=12.15
DEBIAN_MIRROR="${SIMTEST_DEBIAN_MIRROR:-http://deb.debian.org/debian}"

REGISTRY=ghcr.io/simtest-dev
BASE_DEBIAN=localhost/simtest-base/debian:bookworm-slim
BASE_PYTHON=localhost/simtest-base/python:3.11-bookworm
BASE_UV="localhost/simtest-base/uv:$UV_VERSION"
PAUSE_IMAGE="localhost/simtest/pause:$PAUSE_VERSION"
BASE_GO=""   # set by need_go (from `go env GOVERSION`)

START=$(date +%s)
log() { printf '[docker/build.sh %4ss] %s\n' "$(($(date +%s) - START))" "$*" >&2; }
die() { printf 'docker/build.sh: error: %s\n' "$*" >&2; exit 1; }

bah() { buildah --root "$STORE" --runroot "$RUNROOT" --storage-driver overlay "$@"; }

sha() { sha256sum | cut -c1-16; }

# --- preconditions ---------------------------------------------------------------------------
check_host() {
    [[ "$(uname -s)" == Linux ]] || die "images are built on Linux (buildah); this is $(uname -s)"
    [[ "$(id -u)" == 0 ]] || die "building images needs root here (buildah, debootstrap, chroot); rerun as root"
    local tool dir missing=()
    for tool in buildah:buildah debootstrap:debootstrap gcc:gcc git:git python3:python3 tar:tar; do
        command -v "${tool%%:*}" >/dev/null 2>&1 || missing+=("${tool#*:}")
    done
    [[ -e /usr/lib/x86_64-linux-gnu/libc.a || -n "$(gcc -print-file-name=libc.a | grep /)" ]] \
        || missing+=(libc6-dev)
    [[ ${#missing[@]} == 0 ]] || die "missing: ${missing[*]}; install them (bash deploy/setup.sh test) and retry"
    [[ -n "$PROJECT_VERSION" && -n "$UV_VERSION" && -n "$PAUSE_VERSION" ]] \
        || die "cannot read a version (pyproject.toml version, deploy/setup.sh UV_VERSION, pause.c PAUSE_VERSION)"
    [[ -r "$CA_BUNDLE" ]] || die "no CA bundle at $CA_BUNDLE (set SSL_CERT_FILE)"
    for dir in "$IMG" "$IMG/logs" "$IMG/work" "$STORE" "$RUNROOT" "$UV_CACHE" "$TC/gomodcache" "$TC/gocache"; do
        mkdir -p "$dir"
    done
    # A persistent /run keeps stale mount counts across a reboot: start those afresh.
    local boot; boot="$(cat /proc/sys/kernel/random/boot_id)"
    if [[ "$(cat "$RUNROOT/boot_id" 2>/dev/null)" != "$boot" ]]; then
        rm -rf "$RUNROOT"; mkdir -p "$RUNROOT"; echo "$boot" >"$RUNROOT/boot_id"
    fi
}

# --- the store -------------------------------------------------------------------------------
# label_of <image>: the build key the image in the store was made from ("" when absent).
label_of() {
    bah inspect --type image --format "{{index .OCIv1.Config.Labels \"$KEY_LABEL\"}}" "$1" 2>/dev/null || true
}

image_id() { bah inspect --type image --format '{{.FromImageID}}' "$1"; }

# export_archive <image> <file>: an OCI archive (image layout in a tar) whose index names the
# image twice: the OCI ref name annotation and containerd's io.containerd.image.name, which
# `ctr images import` uses as the image's name.
export_archive() {
    local name="$1" archive="$2" tmp="$IMG/work/export"
    rm -rf "$tmp"
    bah push --quiet --compression-format zstd "$name" "oci:$tmp:$name" >/dev/null
    python3 - "$tmp/index.json" "$name" <<'EOF'
import json, sys
path, name = sys.argv[1:]
with open(path) as f:
    index = json.load(f)
(manifest,) = index["manifests"]
manifest.setdefault("annotations", {})["io.containerd.image.name"] = name
manifest["annotations"]["org.opencontainers.image.ref.name"] = name
with open(path, "w") as f:
    json.dump(index, f, separators=(",", ":"))
EOF
    tar -C "$tmp" --numeric-owner --owner=0 --group=0 -cf "$archive.tmp" oci-layout index.json blobs
    mv -f "$archive.tmp" "$archive"
    rm -rf "$tmp"
}

# restore <archive> <image>: load an archive made by export_archive back into the store.
restore() {
    local id
    id="$(bah pull --quiet --policy never "oci-archive:$1" 2>/dev/null || bah pull --quiet "oci-archive:$1")"
    bah tag "$id" "$2"
}

# record <short> <image> <key> <archive> [section]: what a real node needs to know about the
# archive (manifest digest as containerd will list it, image ID, sizes) in <archive>.json, which
# write_index gathers into images.json. The unpacked size is the sum of the image's layers in the
# store (what `buildah images` shows); the archive's layers are zstd-compressed.
record() {
    python3 - "$STORE" "$@" <<'EOF'
import json, os, sys, tarfile
store, short, name, key, archive, section = (sys.argv[1:] + ["images"])[:6]
with tarfile.open(archive) as tar:
    blob = lambda digest: tar.extractfile("blobs/" + digest.replace(":", "/"))
    index = json.load(tar.extractfile("index.json"))
    (descriptor,) = index["manifests"]
    manifest = json.load(blob(descriptor["digest"]))
with open(os.path.join(store, "overlay-layers", "layers.json")) as f:
    layers = {layer["id"]: layer for layer in json.load(f)}
with open(os.path.join(store, "overlay-images", "images.json")) as f:
    (image,) = [i for i in json.load(f) if name in (i.get("names") or [])]
unpacked, layer = 0, image.get("layer")
while layer:
    unpacked += layers[layer].get("diff-size", 0)
    layer = layers[layer].get("parent")
entry = {
    "section": section,
    "name": name,
    "archive": archive,
    "digest": descriptor["digest"],
    "id": manifest["config"]["digest"],
    "size": unpacked,
    "archiveSize": os.path.getsize(archive),
    "layers": len(manifest["layers"]),
    "key": key,
}
with open(archive.removesuffix(".oci.tar") + ".json", "w") as f:
    json.dump(entry, f, indent=2)
EOF
}

declare -A ENSURED=()
BUILT=0
# ensure <short> <image> <key> <builder> [section]: <image>, made from content <key>, is in the
# store and in <short>-<key>.oci.tar; whatever is missing is built (<builder> <image> <key>),
# restored from the archive or exported. Older archives of <short> are deleted.
ensure() {
    local short="$1" name="$2" key="$3" builder="$4" section="${5:-images}"
    local archive="$IMG/$short-$key.oci.tar" t0=$SECONDS
    [[ -z "${ENSURED[$short]:-}" ]] || return 0
    ENSURED[$short]=1
    if [[ "$(label_of "$name")" == "$key" && -s "$archive" && -s "${archive%.oci.tar}.json" ]]; then
        log "$short: cached ($name, key $key)"
        return
    fi
    if [[ "$(label_of "$name")" != "$key" ]]; then
        if [[ -s "$archive" ]]; then
            log "$short: restoring $name from $(basename "$archive")"
            restore "$archive" "$name"
        else
            log "$short: building $name (key $key)"
            "$builder" "$name" "$key"
            BUILT=1
        fi
        [[ "$(label_of "$name")" == "$key" ]] || die "$short: $name was made but does not carry $KEY_LABEL=$key"
    fi
    if [[ ! -s "$archive" ]]; then
        log "$short: exporting $(basename "$archive")"
        export_archive "$name" "$archive"
    fi
    record "$short" "$name" "$key" "$archive" "$section"
    local old
    for old in "$IMG/$short"-????????????????.oci.tar; do
        [[ -e "$old" && "$old" != "$archive" ]] && rm -f "$old" "${old%.oci.tar}.json"
    done
    log "$short: ready in $((SECONDS - t0)) s: $name, $(du -m "$archive" | cut -f1) MiB archive"
}

# commit <container> <image> <key> [buildah-config args...]: set config and labels, commit.
commit() {
    local ctr="$1" name="$2" key="$3"; shift 3
    bah config --label "$KEY_LABEL=$key" \
        --label org.opencontainers.image.source=https://github.com/simtest-dev/simtest-operator \
        "$@" "$ctr"
    bah commit --quiet --rm --format oci "$ctr" "$name" >/dev/null
}

# --- base: Debian bookworm, minbase ----------------------------------------------------------
DEBIAN_PACKAGES=ca-certificates,netbase,tzdata
key_base_debian() {
    { declare -f key_base_debian build_base_debian; echo "$DEBIAN_SUITE $DEBIAN_POINT_RELEASE $DEBIAN_MIRROR $DEBIAN_PACKAGES"
      dpkg --print-architecture; } | sha
}

build_base_debian() {
    local name="$1" key="$2" work="$IMG/work/debian" rootfs arch
    rootfs="$work/rootfs"; arch="$(dpkg --print-architecture)"
    rm -rf "$work"; mkdir -p "$work"
    log "  debootstrap --variant=minbase $DEBIAN_SUITE from $DEBIAN_MIRROR"
    debootstrap --variant=minbase --arch="$arch" --components=main --include="$DEBIAN_PACKAGES" \
        --keyring=/usr/share/keyrings/debian-archive-keyring.gpg \
        "$DEBIAN_SUITE" "$rootfs" "$DEBIAN_MIRROR" >"$IMG/logs/base-debian.log" 2>&1 \
        || die "debootstrap failed: $(tail -n 3 "$IMG/logs/base-debian.log") (log: $IMG/logs/base-debian.log)"
    # The Release file debootstrap verified names the point release and its date.
    local release version date epoch
    release="$(ls "$rootfs"/var/lib/apt/lists/*_dists_"${DEBIAN_SUITE}"_*Release | head -n 1)"
    version="$(sed -n 's/^Version: //p' "$release")"
    date="$(sed -n 's/^Date: //p' "$release")"
    epoch="$(date -d "$date" +%s)"
    [[ "$version" == "$DEBIAN_POINT_RELEASE" ]] \
        || log "  warning: $DEBIAN_SUITE is at $version now, not $DEBIAN_POINT_RELEASE: update DEBIAN_POINT_RELEASE"
    # Slim like debian:*-slim: no docs (copyright files stay), man pages, locales; apt in
    # images keeps no lists or packages; no service starts during a build.
    cat >"$rootfs/etc/dpkg/dpkg.cfg.d/simtest-slim" <<'EOF'
path-exclude /usr/share/doc/*
path-include /usr/share/doc/*/copyright
path-exclude /usr/share/man/*
path-exclude /usr/share/info/*
path-exclude /usr/share/groff/*
path-exclude /usr/share/lintian/*
path-exclude /usr/share/locale/*
EOF
    cat >"$rootfs/etc/apt/apt.conf.d/simtest-container" <<'EOF'
Acquire::Languages "none";
APT::Install-Recommends "false";
APT::Install-Suggests "false";
DPkg::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/*.bin || true"; };
EOF
    printf '#!/bin/sh\nexit 101\n' >"$rootfs/usr/sbin/policy-rc.d"; chmod 0755 "$rootfs/usr/sbin/policy-rc.d"
    echo "deb $DEBIAN_MIRROR $DEBIAN_SUITE main" >"$rootfs/etc/apt/sources.list"
    find "$rootfs/usr/share/doc" -mindepth 1 ! -type d ! -name copyright -delete
    find "$rootfs/usr/share/doc" -mindepth 1 -type d -empty -delete
    rm -rf "$rootfs"/usr/share/{man,info,groff,lintian,locale}/* "$rootfs"/var/lib/apt/lists/* \
        "$rootfs"/var/cache/apt/* "$rootfs"/var/cache/ldconfig/aux-cache "$rootfs"/var/log/* \
        "$rootfs"/var/lib/dpkg/*-old "$rootfs"/tmp/* "$rootfs"/var/tmp/* \
        "$rootfs"/etc/resolv.conf "$rootfs"/etc/hostname "$rootfs"/debootstrap
    printf '127.0.0.1\tlocalhost\n::1\tlocalhost ip6-localhost ip6-loopback\n' >"$rootfs/etc/hosts"
    : >"$rootfs/etc/resolv.conf"
    # Every file dated at the release, so the layer depends on the packages, not on the day.
    find "$rootfs" -newermt "@$epoch" -print0 | xargs -0r touch --no-dereference --date="@$epoch"
    local ctr mnt
    ctr="$(bah from --quiet scratch)"
    mnt="$(bah mount "$ctr")"
    tar -C "$rootfs" --numeric-owner --xattrs -cf - . | tar -C "$mnt" --numeric-owner --xattrs -xpf -
    bah umount "$ctr" >/dev/null
    commit "$ctr" "$name" "$key" \
        --env PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin --env LANG=C.UTF-8 \
        --cmd '["bash"]' --created-by "debootstrap --variant=minbase --include=$DEBIAN_PACKAGES $DEBIAN_SUITE $DEBIAN_MIRROR" \
        --label "org.opencontainers.image.title=simtest-base/debian" \
        --label "org.opencontainers.image.version=$version" \
        --label "dev.simtest.debian.release=$version" --label "dev.simtest.debian.date=$date" \
        --label "dev.simtest.debian.mirror=$DEBIAN_MIRROR"
    rm -rf "$work"
}

# --- base: Python 3.11 (Debian's) for PYTHON_IMAGE --------------------------------------------
# What a python:3.11-slim user relies on: python/python3/python3.11 on PATH, venv + ensurepip,
# ssl/sqlite3/ctypes/…, ca-certificates, tzdata, LANG=C.UTF-8, CMD python3. Not there: pip as a
# command (images install with uv) and /usr/local/bin/python (Debian's is /usr/bin/python3).
PYTHON_PACKAGES="python3 python3-venv python-is-python3"
key_base_python() {
    { declare -f key_base_python build_base_python; echo "$PYTHON_PACKAGES"; image_id "$BASE_DEBIAN"; } | sha
}

build_base_python() {
    local name="$1" key="$2" ctr version
    ctr="$(bah from --quiet --pull=never "$BASE_DEBIAN")"
    # shellcheck disable=SC2086
    bah run --isolation "$ISOLATION" --network host "$ctr" -- sh -ec "
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $PYTHON_PACKAGES >/dev/null
        apt-get clean; rm -rf /var/lib/apt/lists/* /var/log/apt/* /var/log/dpkg.log /var/cache/ldconfig/aux-cache
        python3 -c 'import ssl, sqlite3, ctypes, venv, zoneinfo, lzma, bz2, readline'
    " >"$IMG/logs/base-python.log" 2>&1 \
        || die "installing Python into the base failed: $(tail -n 3 "$IMG/logs/base-python.log")"
    version="$(bah run --isolation "$ISOLATION" "$ctr" -- python3 -c 'import platform; print(platform.python_version())')"
    commit "$ctr" "$name" "$key" --env "PYTHON_VERSION=$version" --cmd '["python3"]' \
        --created-by "apt-get install $PYTHON_PACKAGES" \
        --label "org.opencontainers.image.title=simtest-base/python" \
        --label "org.opencontainers.image.version=$version"
}

# --- base: uv for UV_IMAGE (like ghcr.io/astral-sh/uv: /uv and /uvx in an empty image) ---------
# The binaries of the PyPI wheel deploy/setup.sh installs (same version, same place); their
# digests are checked against the wheel's RECORD.
UV_HOME="$CACHE_ROOT/uv/$UV_VERSION"
uv_binaries() {
    if [[ ! -x "$UV_HOME/bin/uv" ]]; then
        log "  uv $UV_VERSION: installing the PyPI wheel into $UV_HOME (as deploy/setup.sh does)"
        python3 -m pip install -q --disable-pip-version-check --no-warn-script-location \
            --target "$UV_HOME" "uv==$UV_VERSION" || die "cannot install uv $UV_VERSION from PyPI"
    fi
    python3 - "$UV_HOME" "$UV_VERSION" <<'EOF' || die "uv binaries in $UV_HOME do not match the wheel's RECORD"
import base64, csv, hashlib, pathlib, sys
home, version = pathlib.Path(sys.argv[1]), sys.argv[2]
record = home / f"uv-{version}.dist-info" / "RECORD"
for row in csv.reader(record.read_text().splitlines()):
    if row[0].endswith(("bin/uv", "bin/uvx")):
        algo, _, want = row[1].partition("=")
        path = home / "bin" / pathlib.Path(row[0]).name
        got = base64.urlsafe_b64encode(hashlib.new(algo, path.read_bytes()).digest()).rstrip(b"=")
        assert got.decode() == want, path
        print(path.name, want)
EOF
}

key_base_uv() { { declare -f key_base_uv build_base_uv; uv_binaries; } | sha; }

build_base_uv() {
    local name="$1" key="$2" ctr
    ctr="$(bah from --quiet scratch)"
    bah copy --quiet --chmod 0755 "$ctr" "$UV_HOME/bin/uv" "$UV_HOME/bin/uvx" / >/dev/null
    commit "$ctr" "$name" "$key" --entrypoint '["/uv"]' --created-by "uv $UV_VERSION from its PyPI wheel" \
        --label "org.opencontainers.image.title=simtest-base/uv" \
        --label "org.opencontainers.image.version=$UV_VERSION"
}

# --- base: Go for GO_IMAGE (Debian base + this machine's toolchain, like golang:<v>-bookworm) ----
GOROOT_HOST=""
need_go() {
    [[ -n "$BASE_GO" ]] && return
    command -v go >/dev/null 2>&1 || die "no Go toolchain on PATH; the Go images need one (deploy/devcluster/build.sh does too)"
    local v; v="$(go env GOVERSION)"; v="${v#go}"
    [[ "$v" =~ ^[0-9]+\.[0-9]+(\.[0-9]+)?$ ]] || die "unexpected Go version '$v' (a release is needed)"
    GOROOT_HOST="$(go env GOROOT)"
    BASE_GO="localhost/simtest-base/golang:$v-bookworm"
}

key_base_golang() {
    { declare -f key_base_golang build_base_golang; go version; cat "$GOROOT_HOST/VERSION" "$GOROOT_HOST/go.env"
      sha256sum "$GOROOT_HOST/bin/go" "$GOROOT_HOST/bin/gofmt" | cut -d' ' -f1; image_id "$BASE_DEBIAN"; } | sha
}

build_base_golang() {
    local name="$1" key="$2" ctr v="${BASE_GO#*:}"; v="${v%-bookworm}"
    ctr="$(bah from --quiet --pull=never "$BASE_DEBIAN")"
    bah copy --quiet "$ctr" "$GOROOT_HOST" /usr/local/go >/dev/null
    bah run --isolation "$ISOLATION" "$ctr" -- sh -ec 'mkdir -p /go/src /go/bin && chmod -R 1777 /go && /usr/local/go/bin/go version' \
        >"$IMG/logs/base-golang.log" 2>&1 || die "the Go base does not run go: $(tail -n 3 "$IMG/logs/base-golang.log")"
    commit "$ctr" "$name" "$key" --env "GOLANG_VERSION=$v" --env GOTOOLCHAIN=local --env GOPATH=/go \
        --env PATH=/go/bin:/usr/local/go/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
        --workingdir /go --created-by "COPY $GOROOT_HOST (go $v) /usr/local/go" \
        --label "org.opencontainers.image.title=simtest-base/golang" \
        --label "org.opencontainers.image.version=$v"
}

# --- pause: the pod sandbox, our own static program FROM scratch -----------------------------
key_pause() {
    { declare -f key_pause build_pause; sha256sum <"$HERE/pause/pause.c"; gcc --version | head -n 1
      dpkg-query -W libc6-dev 2>/dev/null || true; } | sha
}

build_pause() {
    local name="$1" key="$2" work="$IMG/work/pause" ctr
    rm -rf "$work"; mkdir -p "$work"
    gcc -static -Os -s -Wall -Wextra -Werror -o "$work/pause" "$HERE/pause/pause.c" \
        || die "compiling deploy/docker/pause/pause.c failed (gcc -static needs libc6-dev)"
    "$work/pause" -v >/dev/null || die "the pause binary does not run"
    ctr="$(bah from --quiet scratch)"
    bah copy --quiet --chmod 0755 "$ctr" "$work/pause" /pause >/dev/null
    # 65535 as the upstream pause image: the sandbox holds namespaces and needs no privilege.
    commit "$ctr" "$name" "$key" --entrypoint '["/pause"]' --cmd '[]' --user 65535:65535 \
        --created-by "gcc -static pause.c" \
        --label "org.opencontainers.image.title=simtest-pause" \
        --label "org.opencontainers.image.version=$PAUSE_VERSION"
    rm -rf "$work"
}

# --- the Dockerfile images -------------------------------------------------------------------
# copy_sources <dockerfile>: the build-context paths its COPY lines read (not COPY --from).
copy_sources() {
    awk '
        /^[[:space:]]*#/ { next }
        { line = line " " $0 }
        /\\$/ { sub(/\\$/, "", line); next }
        {
            n = split(line, w, /[[:space:]]+/); line = ""
            i = (w[1] == "") ? 2 : 1
            if (toupper(w[i]) != "COPY") next
            for (j = i + 1; j <= n; j++) if (w[j] ~ /^--from=/) next
            last = n; while (last > i && w[last] == "") last--
            for (j = i + 1; j < last; j++) if (w[j] !~ /^--/) print w[j]
        }' "$1"
}

# stage_context <dockerfile> <dir>: copy exactly the files its COPY lines read into <dir> (as git
# sees the work tree: tracked and untracked-but-not-ignored, so .venv, __pycache__ or build
# output never reach an image), dated at one fixed time (reproducible layers), and print one
# "<sha256> <mode> <path>" line per file: the context part of the image's key.
CONTEXT_EPOCH=1577836800   # 2020-01-01; wheels (zip) cannot store times before 1980
stage_context() {
    local df="$1" dir="$2" src list="$2.files"
    rm -rf "$dir" "$list"; mkdir -p "$dir"
    while read -r src; do
        [[ -e "$REPO/$src" ]] || die "$(basename "$df"): COPY source $src does not exist"
        git -C "$REPO" ls-files -z --cached --others --exclude-standard -- "$src"
    done < <(copy_sources "$df") | sort -zu | (cd "$REPO" && while IFS= read -r -d '' f; do
        [[ -f "$f" || -L "$f" ]] && printf '%s\0' "$f"; done) >"$list"
    [[ -s "$list" ]] || die "$(basename "$df"): its COPY lines name no files"
    (cd "$REPO" && tar --null -T "$list" -cf -) | tar -C "$dir" -xf -
    find "$dir" -exec touch --no-dereference --date="@$CONTEXT_EPOCH" {} +
    (cd "$dir" && xargs -0 -a "$list" stat -c '%a %n' | paste -d' ' <(xargs -0 -a "$list" sha256sum | cut -d' ' -f1) -)
}

# The FROM arguments a Dockerfile may declare and the local base each one is pointed at.
declare -A BASE_OF_ARG=([PYTHON_IMAGE]=python [UV_IMAGE]=uv [GO_IMAGE]=golang [DEBIAN_IMAGE]=debian)

# ensure_base <debian|python|uv|golang>: the base is ready; its name in BASE_REF.
BASE_REF=""
ensure_base() {
    case "$1" in
        debian) ensure base-debian "$BASE_DEBIAN" "$(key_base_debian)" build_base_debian bases
                BASE_REF="$BASE_DEBIAN" ;;
        python) ensure_base debian
                ensure base-python "$BASE_PYTHON" "$(key_base_python)" build_base_python bases
                BASE_REF="$BASE_PYTHON" ;;
        uv)     ensure base-uv "$BASE_UV" "$(key_base_uv)" build_base_uv bases
                BASE_REF="$BASE_UV" ;;
        golang) need_go; ensure_base debian
                ensure base-golang "$BASE_GO" "$(key_base_golang)" build_base_golang bases
                BASE_REF="$BASE_GO" ;;
    esac
}

# Set by image_target for build_dockerfile (ensure calls builders with <image> <key> only).
DF="" CTX="" BUD_ARGS=()

image_target() {
    local short="$1" df="$HERE/$1.Dockerfile" name="$REGISTRY/simtest-$1:$PROJECT_VERSION"
    if [[ ! -f "$df" ]]; then
        log "$short: skipped, $(realpath --relative-to="$REPO" "$df") does not exist (yet)"
        return
    fi
    local arg base ids=() uses_go=0
    BUD_ARGS=()
    for arg in $(sed -n 's/^ARG \([A-Z_]*_IMAGE\)=.*/\1/p' "$df"); do
        # An empty image needs no local base.
        grep -q "^ARG $arg=scratch\$" "$df" && continue
        [[ -n "${BASE_OF_ARG[$arg]:-}" ]] \
            || die "$short: $(basename "$df") takes a base in ARG $arg, for which build.sh has no local base (one of: ${!BASE_OF_ARG[*]})"
        ensure_base "${BASE_OF_ARG[$arg]}"; base="$BASE_REF"
        BUD_ARGS+=(--build-arg "$arg=$base")
        ids+=("$arg=$base@$(image_id "$base")")
        [[ "$arg" == GO_IMAGE ]] && uses_go=1
    done
    # Caches of the host, mounted into RUN steps: uv's for the Python images, Go's (modules and
    # builds) at the places both Go recipes use: GOPATH's default of the golang images and
    # deploy/devcluster/build.sh --cache-dir /build.
    if [[ $uses_go == 1 ]]; then
        BUD_ARGS+=(-v "$TC/gomodcache:/go/pkg/mod" -v "$TC/gocache:/root/.cache/go-build"
                   -v "$TC/gomodcache:/build/toolchain/gomodcache" -v "$TC/gocache:/build/toolchain/gocache")
    fi
    if grep -q 'UV_IMAGE' "$df"; then BUD_ARGS+=(-v "$UV_CACHE:/root/.cache/uv"); fi
    DF="$df"; CTX="$IMG/work/context-$short"
    local key
    key="$({ declare -f image_target build_dockerfile stage_context copy_sources; sha256sum <"$df"
             stage_context "$df" "$CTX"; printf '%s\n' "${ids[@]}" "$PROJECT_VERSION"; buildah --version; } | sha)"
    ensure "$short" "$name" "$key" build_dockerfile
    rm -rf "$CTX" "$CTX.files"
}

build_dockerfile() {
    local name="$1" key="$2" short log rc
    short="$(basename "$DF" .Dockerfile)"; log="$IMG/logs/$short.log"
    set +e
    bah bud --layers --force-rm --pull=never --isolation "$ISOLATION" --network host --format oci \
        -v "$CA_BUNDLE:/etc/ssl/certs/ca-certificates.crt:ro" "${BUD_ARGS[@]}" \
        --label "$KEY_LABEL=$key" -f "$DF" -t "$name" "$CTX" 2>&1 \
        | tee "$log" | while IFS= read -r line; do
            [[ "$line" =~ ^(\[[0-9]+/[0-9]+\]\ )?STEP ]] && log "  $short: ${line:0:100}"
        done
    rc=${PIPESTATUS[0]}
    set -e
    [[ $rc == 0 ]] || die "$short: buildah bud failed (exit $rc): $(grep -v '^\s*$' "$log" | tail -n 3 | tr '\n' ' ') (log: $log)"
    no_proxy_ca "$name"
}

# no_proxy_ca <image>: the CAs this host adds to its bundle (/usr/local/share/ca-certificates,
# e.g. an egress proxy's) did not end up in the image.
no_proxy_ca() {
    local extra=(/usr/local/share/ca-certificates/*.crt) ctr mnt crt line bad=""
    [[ -e "${extra[0]}" ]] || return 0
    ctr="$(bah from --quiet --pull=never "$1")"; mnt="$(bah mount "$ctr")"
    for crt in "${extra[@]}"; do
        line="$(sed -n '2p' "$crt")"
        [[ -n "$line" ]] || continue
        if grep -rqsF -- "$line" "$mnt/etc/ssl" "$mnt/usr/local/share/ca-certificates" "$mnt/opt" 2>/dev/null; then
            bad+=" $(basename "$crt")"
        fi
    done
    bah umount "$ctr" >/dev/null; bah rm "$ctr" >/dev/null
    [[ -z "$bad" ]] || { bah rmi -f "$1" >/dev/null 2>&1 || true; die "$1 contains the host's extra CA(s)$bad; not exported"; }
}

# --- images.json -----------------------------------------------------------------------------
write_index() {
    python3 - "$IMG" "$STORE" "$RUNROOT" <<'EOF'
import glob, json, os, sys
img, store, runroot = sys.argv[1:]
index = {"format": 1, "storage": {"driver": "overlay", "root": store, "runroot": runroot},
         "images": {}, "bases": {}}
for path in sorted(glob.glob(os.path.join(img, "*.json"))):
    if os.path.basename(path) == "images.json":
        continue
    with open(path) as f:
        entry = json.load(f)
    if not os.path.exists(entry["archive"]):
        continue
    section, name = entry.pop("section"), entry.pop("name")
    index[section][name] = entry
tmp = os.path.join(img, "images.json.tmp")
with open(tmp, "w") as f:
    json.dump(index, f, indent=2, sort_keys=True)
    f.write("\n")
os.replace(tmp, os.path.join(img, "images.json"))
EOF
}

# drop_stale: remove every image of the store that no named image is built on, i.e. the layer
# cache of earlier builds. The cache of the current ones stays (the steps the named images were
# made from, e.g. the dependency layer); so does anything a container still uses.
drop_stale() {
    local ids
    ids="$(python3 - "$STORE" <<'EOF'
import json, os, sys
store = sys.argv[1]
with open(os.path.join(store, "overlay-layers", "layers.json")) as f:
    parents = {layer["id"]: layer.get("parent") for layer in json.load(f)}
with open(os.path.join(store, "overlay-images", "images.json")) as f:
    images = json.load(f)
kept = set()
for image in images:
    if image.get("names"):
        layer = image.get("layer")
        while layer and layer not in kept:
            kept.add(layer)
            layer = parents.get(layer)
for image in images:
    if not image.get("names") and image.get("layer") not in kept:
        print(image["id"])
EOF
)"
    [[ -n "$ids" ]] || return 0
    # shellcheck disable=SC2086
    bah rmi $ids >/dev/null 2>&1 || true
    log "store: dropped $(wc -w <<<"$ids") stale cache image(s); $(du -sh "$STORE" | cut -f1) now"
}

# prune: also the layer cache of the current images, and archives images.json does not name.
prune() {
    log "prune: removing the layer cache and archives images.json does not name"
    bah rmi --prune >/dev/null 2>&1 || true
    local f
    for f in "$IMG"/*.oci.tar; do
        [[ -e "$f" ]] || continue
        grep -qF "\"$f\"" "$IMG/images.json" || { rm -f "$f" "${f%.oci.tar}.json"; log "prune: removed $(basename "$f")"; }
    done
    rm -rf "$IMG/work"
}

# --- main ------------------------------------------------------------------------------------
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=("${ALL_TARGETS[@]}")
for t in "${targets[@]}"; do
    [[ " ${ALL_TARGETS[*]} bases " == *" $t "* ]] || die "unknown image '$t' (one of: ${ALL_TARGETS[*]} bases)"
done

check_host
# One build at a time per cache (a test session and a shell may both call this).
exec 9>"$IMG/.build.lock"
flock -n 9 || { log "another build holds $IMG/.build.lock; waiting"; flock 9; }

log "image cache: $IMG (isolation $ISOLATION, storage overlay)"
for t in "${targets[@]}"; do
    case "$t" in
        pause) ensure pause "$PAUSE_IMAGE" "$(key_pause)" build_pause ;;
        bases) for b in debian python uv golang; do ensure_base "$b"; done ;;
        *) image_target "$t" ;;
    esac
done
write_index
[[ $BUILT == 0 ]] || drop_stale
[[ $PRUNE == 0 ]] || prune
log "ready: $IMG/images.json ($(du -sh "$IMG" --exclude=storage 2>/dev/null | cut -f1) in archives, store $(du -sh "$STORE" 2>/dev/null | cut -f1))"
