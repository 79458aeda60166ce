# syntax=docker/dockerfile:1.7
# The image of `provisioner: Helmfile` Jobs: helm and helmfile plus the repository's charts at
# /opt/simtest/charts, which rendered helmfiles refer to. helm and helmfile are built by the one
# recipe the dev toolchain uses (deploy/devcluster/build.sh, from Go modules, versions pinned in
# deploy/devcluster/versions.env), so the image runs exactly the binaries the tests ran.
#
#   docker build -f deploy/docker/helmfile.Dockerfile -t ghcr.io/simtest-dev/simtest-helmfile:0.1.0 .
#   bash deploy/docker/build.sh helmfile   # here: buildah, local bases, cached (docs/images.md)
ARG GO_IMAGE=golang:1.26.8-bookworm
ARG DEBIAN_IMAGE=debian:12.8-slim

# deploy/docker/build.sh mounts the dev toolchain's Go module and build caches at
# /build/toolchain/{gomodcache,gocache}, so helm and helmfile link in seconds instead of compiling.
FROM ${GO_IMAGE} AS build
COPY deploy/devcluster/build.sh deploy/devcluster/versions.env /src/
RUN bash /src/build.sh --cache-dir /build helm helmfile \
    && mkdir /out \
    && install -m 0755 "$(readlink -f /build/toolchain/bin/helm)" /out/helm \
    && install -m 0755 "$(readlink -f /build/toolchain/bin/helmfile)" /out/helmfile

FROM ${DEBIAN_IMAGE}
LABEL org.opencontainers.image.title="simtest-helmfile" \
      org.opencontainers.image.description="helm + helmfile + simtest charts for provisioner: Helmfile" \
      org.opencontainers.image.source="https://github.com/simtest-dev/simtest-operator" \
      org.opencontainers.image.licenses="Apache-2.0"
COPY --from=build /out/ /usr/local/bin/
COPY charts /opt/simtest/charts
ENV HOME=/tmp HELM_DRIVER=configmap HELM_CACHE_HOME=/tmp/helm/cache \
    HELM_CONFIG_HOME=/tmp/helm/config HELM_DATA_HOME=/tmp/helm/data
USER 65532:65532
WORKDIR /tmp
ENTRYPOINT ["helmfile"]
