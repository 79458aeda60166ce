#!/usr/bin/env bash
# Build the dev-cluster toolchain from Go modules only (no release downloads, no containers):
# the control plane, the kubelet of the dev cluster's real node, kwok, helm and helmfile, and the
# simulator-slot device plugin of deploy/deviceplugin (the project's own Go module), and Kueue
# (`simtest dev-cluster up --kueue`; its CRDs ship in the module source, copied beside the binary).
#
#   bash deploy/devcluster/build.sh            # everything (idempotent; seconds when cached)
#   bash deploy/devcluster/build.sh etcd kwok  # a subset: etcd kubernetes kwok crictl helm helmfile kueue
#   bash deploy/devcluster/build.sh --cache-dir DIR ...   # instead of $SIMTEST_CACHE_DIR
#
# Versions: deploy/devcluster/versions.env (the one place they are pinned).
# Output:   ${SIMTEST_CACHE_DIR:-${XDG_CACHE_HOME:-~/.cache}/simtest}/toolchain/
#             <tool>-<version>/bin/*   the binaries, keyed by version
#             deviceplugin-<hash>/bin/ simtest-device-plugin, keyed by the content of its sources
#             kueue-<version>/crd/     Kueue's CRDs (config/components/crd/bases of the module)
#             bin/                     symlinks to the versions pinned now (put it on PATH)
#             gomodcache/ gocache/     Go module and build caches (shared by all versions)
#             work/                    generated wrapper modules
# A binary is rebuilt only if it is missing or its --version output does not match the pin.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck source=versions.env
source "$HERE/versions.env"

CACHE_ROOT="${SIMTEST_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/simtest}"
if [[ "${1:-}" == --cache-dir ]]; then
    [[ -n "${2:-}" ]] || { echo "build.sh: error: --cache-dir needs a directory" >&2; exit 2; }
    CACHE_ROOT="$2"; shift 2
fi
TC="$CACHE_ROOT/toolchain"
ALL_COMPONENTS=(etcd kwok kubernetes crictl helm helmfile deviceplugin kueue)
JOBS="${SIMTEST_BUILD_JOBS:-2}"

START=$(date +%s)
log() { printf '[build.sh %4ss] %s\n' "$(($(date +%s) - START))" "$*" >&2; }
die() { printf 'build.sh: error: %s\n' "$*" >&2; exit 1; }
# Said once, by the first component that must be built (a cached run never calls it, so the
# cached path does no extra work): how long the wait is. Measured cold on 2 cores: about 13 min
# for everything, most of it kubernetes.
estimated=0
estimate() {
    [[ $estimated == 0 ]] || return 0
    estimated=1
    if [[ " ${components[*]} " == *" kubernetes "* && ! -x "$TC/kubernetes-$KUBERNETES_VERSION/bin/kube-apiserver" ]]; then
        local also=" (kubernetes $KUBERNETES_VERSION among it)"
        [[ $1 != kubernetes* ]] || also=""
        log "building $1 and what else is missing from Go modules$also: ~10-15 min on 2 cores, cached afterwards in $TC"
    else
        log "building $1 (and what else is missing) from Go modules: a few minutes on 2 cores, cached afterwards in $TC"
    fi
}

# --- the Go environment: local toolchain, static binaries, caches outside the repo -------------
export GOTOOLCHAIN=local CGO_ENABLED=0 GO111MODULE=on GOWORK=off
export GOMODCACHE="$TC/gomodcache" GOCACHE="$TC/gocache"
export GOFLAGS="-buildvcs=false -modcacherw"
GO_BUILD=(go build -trimpath -p "$JOBS")

# --- helpers ---------------------------------------------------------------------------------
# version_matches <want> <command...>: the command's output names exactly that version.
version_matches() {
    local want="$1"; shift
    [[ -x "$1" ]] || return 1
    local out
    out="$("$@" 2>&1)" || return 1
    grep -Eq "(^|[^0-9.])${want//./\\.}([^0-9]|$)" <<<"$out"
}

proxy_checked=0
require_go() {
    command -v go >/dev/null 2>&1 \
        || die "no Go toolchain on PATH; install Go >= 1.26 (https://go.dev/dl/) and retry"
    local gov
    gov="$(go env GOVERSION)"
    [[ "$gov" =~ ^go1\.(2[6-9]|[3-9][0-9]) ]] \
        || die "Go $gov is too old; kubernetes $KUBERNETES_VERSION and kwok $KWOK_VERSION need Go >= 1.26"
    if [[ $proxy_checked == 0 ]]; then
        # One cheap request that must reach the module proxy (or hit the module cache).
        go list -m -json "k8s.io/kubernetes@v$KUBERNETES_VERSION" >/dev/null 2>"$TC/proxy-check.err" \
            || die "cannot reach the Go module proxy ($(go env GOPROXY)): $(tail -n 2 "$TC/proxy-check.err")"
        proxy_checked=1
    fi
}

# go_get <module@version>...: add tools to the wrapper module in the current directory; keep the
# output short (no per-module "added" lines) and turn a failure into one clear message.
go_get() {
    local out rc=0
    out="$(go get -tool "$@" 2>&1)" || rc=$?
    grep -v '^go: \(added\|upgraded\|downgraded\|downloading\) ' <<<"$out" >&2 || true
    if [[ $rc != 0 ]]; then
        if grep -q 'verifying module.*404' <<<"$out"; then
            die "the checksum database ($(go env GOSUMDB)) does not know a version above; pin a released one in versions.env"
        fi
        die "go get $* failed (exit $rc); output above"
    fi
    log "  resolved $(grep -c '^go: added ' <<<"$out" || true) modules for $*"
}

# new_wrapper <dir> <module>: a fresh throw-away main module.
new_wrapper() {
    rm -rf "$1"; mkdir -p "$1"
    (cd "$1" && go mod init "$2" >/dev/null 2>&1)
}

# install_bins <srcdir> <destdir>: atomically move freshly built binaries into place.
install_bins() {
    mkdir -p "$2"
    local f
    for f in "$1"/*; do mv -f "$f" "$2/"; done
    rmdir "$1"
}

# --- components ------------------------------------------------------------------------------
build_etcd() {
    local v="$ETCD_VERSION" dir="$TC/etcd-$ETCD_VERSION/bin"
    if version_matches "$v" "$dir/etcd" --version; then log "etcd $v: cached"; return; fi
    estimate "etcd $v"
    require_go
    log "etcd $v: building (own wrapper module, go.etcd.io/etcd/server/v3)"
    local w="$TC/work/etcd-$v"
    new_wrapper "$w" local/etcdbin
    (
        cd "$w"
        go_get "go.etcd.io/etcd/server/v3@v$v"
        "${GO_BUILD[@]}" -ldflags "-s -w" -o "$w/out/etcd" go.etcd.io/etcd/server/v3
    )
    install_bins "$w/out" "$dir"
    version_matches "$v" "$dir/etcd" --version || die "etcd built but '$dir/etcd --version' does not say $v"
    log "etcd $v: done"
}

build_kwok() {
    local v="$KWOK_VERSION" dir="$TC/kwok-$KWOK_VERSION/bin"
    if version_matches "$v" "$dir/kwok" --version && version_matches "$v" "$dir/kwokctl" --version; then
        log "kwok $v: cached"; return
    fi
    estimate "kwok $v"
    require_go
    log "kwok $v: building kwok + kwokctl"
    local w="$TC/work/kwok-$v"
    new_wrapper "$w" local/kwokbin
    (
        cd "$w"
        go_get "sigs.k8s.io/kwok/cmd/kwok@v$v" "sigs.k8s.io/kwok/cmd/kwokctl@v$v"
        "${GO_BUILD[@]}" -ldflags "-s -w" -o "$w/out/" sigs.k8s.io/kwok/cmd/kwok sigs.k8s.io/kwok/cmd/kwokctl
    )
    install_bins "$w/out" "$dir"
    version_matches "$v" "$dir/kwok" --version || die "kwok built but '$dir/kwok --version' does not say $v"
    log "kwok $v: done"
}

# Staging modules of k8s.io/kubernetes 1.36 (its go.mod replaces each with ./staging/src/...).
# A missing one fails with "k8s.io/<x>@v0.0.0: unknown revision", which names it.
K8S_STAGING="api apiextensions-apiserver apimachinery apiserver cli-runtime client-go cloud-provider
 cluster-bootstrap code-generator component-base component-helpers controller-manager cri-api cri-client
 cri-streaming csi-translation-lib dynamic-resource-allocation endpointslice externaljwt kms kube-aggregator
 kube-controller-manager kube-proxy kube-scheduler kubectl kubelet metrics mount-utils pod-security-admission
 sample-apiserver sample-cli-plugin sample-controller streaming"
K8S_CMDS="kube-apiserver kube-controller-manager kube-scheduler kubelet kubectl"

k8s_cached() {
    local v="v$KUBERNETES_VERSION" dir="$TC/kubernetes-$KUBERNETES_VERSION/bin" c
    for c in kube-apiserver kube-controller-manager kube-scheduler kubelet; do
        version_matches "$v" "$dir/$c" --version || return 1
    done
    version_matches "$v" "$dir/kubectl" version --client
}

build_kubernetes() {
    local v="$KUBERNETES_VERSION" dir="$TC/kubernetes-$KUBERNETES_VERSION/bin"
    if k8s_cached; then log "kubernetes $v: cached"; return; fi
    estimate "kubernetes $v"
    require_go
    local minor="${v#1.}"; minor="${minor%%.*}"
    log "kubernetes $v: building $K8S_CMDS (wrapper module, staging modules -> v0.${v#1.}; the long one)"
    local w="$TC/work/kubernetes-$v"
    new_wrapper "$w" local/k8sbins
    local ldf="-s -w" kv m p pkgs=() gets=()
    for kv in "gitVersion=v$v" gitMajor=1 "gitMinor=$minor" gitTreeState=clean \
        "buildDate=$(date -u +%Y-%m-%dT%H:%M:%SZ)"; do
        ldf+=" -X k8s.io/component-base/version.$kv -X k8s.io/client-go/pkg/version.$kv"
    done
    for p in $K8S_CMDS; do pkgs+=("k8s.io/kubernetes/cmd/$p"); gets+=("k8s.io/kubernetes/cmd/$p@v$v"); done
    (
        cd "$w"
        go mod edit -go=1.26.0 -godebug="default=$KUBERNETES_GODEBUG"
        for m in $K8S_STAGING; do go mod edit -replace="k8s.io/$m=k8s.io/$m@v0.${v#1.}"; done
        log "kubernetes $v: resolving modules"
        go_get "${gets[@]}"
        log "kubernetes $v: compiling (most of the ~10-15 min on 2 cores)"
        "${GO_BUILD[@]}" -ldflags "$ldf" -o "$w/out/" "${pkgs[@]}"
    )
    install_bins "$w/out" "$dir"
    k8s_cached || die "kubernetes built but a binary's --version does not say v$v"
    log "kubernetes $v: done"
}

build_crictl() {
    local v="$CRI_TOOLS_VERSION" dir="$TC/crictl-$CRI_TOOLS_VERSION/bin"
    if version_matches "v$v" "$dir/crictl" --version; then log "crictl $v: cached"; return; fi
    estimate "crictl $v"
    require_go
    log "crictl $v: building"
    local w="$TC/work/crictl-$v"
    new_wrapper "$w" local/crictlbin
    (
        cd "$w"
        go_get "sigs.k8s.io/cri-tools/cmd/crictl@v$v"
        "${GO_BUILD[@]}" -ldflags "-s -w -X sigs.k8s.io/cri-tools/pkg/version.Version=v$v" \
            -o "$w/out/crictl" sigs.k8s.io/cri-tools/cmd/crictl
    )
    install_bins "$w/out" "$dir"
    version_matches "v$v" "$dir/crictl" --version || die "crictl built but 'crictl --version' does not say v$v"
    log "crictl $v: done"
}

build_helm() {
    local v="$HELM_VERSION" dir="$TC/helm-$HELM_VERSION/bin"
    if version_matches "v$v" "$dir/helm" version --short; then log "helm $v: cached"; return; fi
    estimate "helm $v"
    require_go
    log "helm $v: building"
    local w="$TC/work/helm-$v" kminor="${KUBERNETES_VERSION#1.}"; kminor="${kminor%%.*}"
    new_wrapper "$w" local/helmbin
    local ldf="-s -w -X helm.sh/helm/v3/internal/version.version=v$v"
    ldf+=" -X helm.sh/helm/v3/internal/version.gitTreeState=clean"
    ldf+=" -X helm.sh/helm/v3/pkg/chartutil.k8sVersionMajor=1 -X helm.sh/helm/v3/pkg/chartutil.k8sVersionMinor=$kminor"
    ldf+=" -X helm.sh/helm/v3/pkg/lint/rules.k8sVersionMajor=1 -X helm.sh/helm/v3/pkg/lint/rules.k8sVersionMinor=$kminor"
    (
        cd "$w"
        go_get "helm.sh/helm/v3/cmd/helm@v$v"
        "${GO_BUILD[@]}" -ldflags "$ldf" -o "$w/out/helm" helm.sh/helm/v3/cmd/helm
    )
    install_bins "$w/out" "$dir"
    version_matches "v$v" "$dir/helm" version --short || die "helm built but 'helm version' does not say v$v"
    log "helm $v: done"
}

build_helmfile() {
    local v="$HELMFILE_VERSION" dir="$TC/helmfile-$HELMFILE_VERSION/bin"
    if version_matches "v$v" "$dir/helmfile" --version; then log "helmfile $v: cached"; return; fi
    estimate "helmfile $v"
    require_go
    log "helmfile $v: building"
    local w="$TC/work/helmfile-$v"
    new_wrapper "$w" local/helmfilebin
    (
        cd "$w"
        # helmfile >= 1.4.5 carries `replace` lines (k8s.io/api etc.), which `go install` refuses
        # and a dependent module ignores: copy them from helmfile's own go.mod into the wrapper.
        local gomod r
        gomod="$(go mod download -json "github.com/helmfile/helmfile@v$v" \
            | sed -n 's/^[[:space:]]*"GoMod": "\(.*\)",*$/\1/p')"
        [[ -f "$gomod" ]] || die "cannot download github.com/helmfile/helmfile@v$v"
        while read -r r; do
            [[ -n "$r" ]] && go mod edit -replace="$r"
        done < <(sed -n '/^replace (/,/^)/{/=>/{s/[[:space:]]*\/\/.*//;s/^[[:space:]]*//;s/ => /=/;s/ v/@v/g;p}}' "$gomod")
        go_get "github.com/helmfile/helmfile@v$v"
        "${GO_BUILD[@]}" -ldflags "-s -w -X go.szostok.io/version.version=v$v -X go.szostok.io/version.dirtyBuild=false" \
            -o "$w/out/helmfile" github.com/helmfile/helmfile
    )
    install_bins "$w/out" "$dir"
    version_matches "v$v" "$dir/helmfile" --version || die "helmfile built but 'helmfile --version' does not say v$v"
    log "helmfile $v: done"
}

# The device plugin is our own module, so it is keyed by the content of its build inputs (go.mod,
# go.sum and the non-test .go files, by relative path) instead of a pinned version.
DP_SRC="$HERE/../deviceplugin"
deviceplugin_hash() {
    [[ -f "$DP_SRC/go.mod" ]] || return 1
    (cd "$DP_SRC" && find . -type f \( -name '*.go' ! -name '*_test.go' -o -name go.mod -o -name go.sum \) -print0 \
        | LC_ALL=C sort -z | xargs -0 sha256sum | sha256sum | cut -c1-12)
}

build_deviceplugin() {
    local h
    h="$(deviceplugin_hash)" || die "no Go module at $DP_SRC (deploy/deviceplugin of the checkout)"
    local dir="$TC/deviceplugin-$h/bin"
    if version_matches "$h" "$dir/simtest-device-plugin" --version; then log "deviceplugin $h: cached"; return; fi
    estimate "deviceplugin $h"
    require_go
    log "deviceplugin $h: building simtest-device-plugin"
    local out="$TC/work/deviceplugin-$h/out"
    rm -rf "$out"; mkdir -p "$out"
    (
        cd "$DP_SRC"
        "${GO_BUILD[@]}" -ldflags "-s -w -X main.version=$h" -o "$out/simtest-device-plugin" ./cmd/simtest-device-plugin
    )
    install_bins "$out" "$dir"
    version_matches "$h" "$dir/simtest-device-plugin" --version \
        || die "simtest-device-plugin built but its --version does not say $h"
    log "deviceplugin $h: done"
}

# Kueue has no --version flag (it connects to a cluster first), so the pin is checked in the build
# info Go embeds in every binary ("mod<TAB>sigs.k8s.io/kueue<TAB>v0.17.0"): no Go needed to read it.
kueue_cached() {
    local v="v$KUEUE_VERSION" dir="$TC/kueue-$KUEUE_VERSION"
    [[ -x "$dir/bin/kueue" && -f "$dir/crd/kueue.x-k8s.io_clusterqueues.yaml" ]] || return 1
    grep -qaF "$(printf 'mod\tsigs.k8s.io/kueue\t%s\t' "$v")" "$dir/bin/kueue"
}

build_kueue() {
    local v="$KUEUE_VERSION" dir="$TC/kueue-$KUEUE_VERSION"
    if kueue_cached; then log "kueue $v: cached"; return; fi
    estimate "kueue $v"
    require_go
    log "kueue $v: building the manager (sigs.k8s.io/kueue/cmd/kueue; several minutes on 2 cores)"
    local w="$TC/work/kueue-$v"
    new_wrapper "$w" local/kueuebin
    local ldf="-s -w -X sigs.k8s.io/kueue/pkg/version.GitVersion=v$v"
    ldf+=" -X sigs.k8s.io/kueue/pkg/version.BuildDate=$(date -u +%Y-%m-%dT%H:%M:%SZ)"
    (
        cd "$w"
        # Like helmfile: copy the module's replace lines (none in v0.17.0) into the wrapper,
        # since a dependent module ignores them.
        local gomod r
        gomod="$(go mod download -json "sigs.k8s.io/kueue@v$v" \
            | sed -n 's/^[[:space:]]*"GoMod": "\(.*\)",*$/\1/p')"
        [[ -f "$gomod" ]] || die "cannot download sigs.k8s.io/kueue@v$v"
        while read -r r; do
            [[ -n "$r" ]] && go mod edit -replace="$r"
        done < <(sed -n '/^replace (/,/^)/{/=>/{s/[[:space:]]*\/\/.*//;s/^[[:space:]]*//;s/ => /=/;s/ v/@v/g;p}}' "$gomod")
        go_get "sigs.k8s.io/kueue/cmd/kueue@v$v"
        "${GO_BUILD[@]}" -ldflags "$ldf" -o "$w/out/kueue" sigs.k8s.io/kueue/cmd/kueue
        # The CRDs the manager serves, from the same module version (kustomize bases, plain YAML).
        local src
        src="$(go list -m -f '{{.Dir}}' sigs.k8s.io/kueue)/config/components/crd/bases"
        [[ -d "$src" ]] || die "no config/components/crd/bases in sigs.k8s.io/kueue@v$v"
        rm -rf "$w/crd"; mkdir -p "$w/crd"
        cp "$src"/*.yaml "$w/crd/"
        chmod u+w "$w/crd"/*.yaml
    )
    install_bins "$w/out" "$dir/bin"
    rm -rf "$dir/crd"; mv "$w/crd" "$dir/crd"
    kueue_cached || die "kueue built but its build info does not name sigs.k8s.io/kueue v$v"
    log "kueue $v: done"
}

# --- main ------------------------------------------------------------------------------------
components=("$@")
[[ ${#components[@]} -gt 0 ]] || components=("${ALL_COMPONENTS[@]}")
for c in "${components[@]}"; do
    [[ " ${ALL_COMPONENTS[*]} " == *" $c "* ]] || die "unknown component '$c' (one of: ${ALL_COMPONENTS[*]})"
done

mkdir -p "$TC/bin" "$TC/work"
# One build at a time per cache (a test session and a shell may both call this).
if command -v flock >/dev/null 2>&1; then
    exec 9>"$TC/.build.lock"
    flock -n 9 || { log "another build holds $TC/.build.lock; waiting"; flock 9; }
fi

log "toolchain cache: $TC"
for c in "${components[@]}"; do "build_$c"; done

# Refresh bin/ symlinks to the pinned versions of what exists.
for pair in "etcd-$ETCD_VERSION:etcd" "kwok-$KWOK_VERSION:kwok kwokctl" \
    "kubernetes-$KUBERNETES_VERSION:$K8S_CMDS" "crictl-$CRI_TOOLS_VERSION:crictl" "helm-$HELM_VERSION:helm" "helmfile-$HELMFILE_VERSION:helmfile" \
    "kueue-$KUEUE_VERSION:kueue"; do
    d="${pair%%:*}"
    for b in ${pair#*:}; do
        [[ -x "$TC/$d/bin/$b" ]] && ln -sfn "../$d/bin/$b" "$TC/bin/$b"
    done
done
if dp_hash="$(deviceplugin_hash)" && [[ -x "$TC/deviceplugin-$dp_hash/bin/simtest-device-plugin" ]]; then
    ln -sfn "../deviceplugin-$dp_hash/bin/simtest-device-plugin" "$TC/bin/simtest-device-plugin"
fi
log "ready: $TC/bin ($(ls "$TC/bin" | tr '\n' ' '))"
