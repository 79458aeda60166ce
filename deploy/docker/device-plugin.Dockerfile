# syntax=docker/dockerfile:1.7
# The simulator-slot device plugin (deploy/deviceplugin): makes a node advertise the extended
# resource simtest.dev/simulator to its kubelet. Run by the operator chart's DaemonSet
# (devicePlugin.enabled=true). The binary is built by the one recipe the dev toolchain uses
# (deploy/devcluster/build.sh deviceplugin: static, -trimpath, stamped with the content hash of
# deploy/deviceplugin), so the image runs exactly the binary the tests ran.
#
#   docker build -f deploy/docker/device-plugin.Dockerfile -t ghcr.io/simtest-dev/simtest-device-plugin:0.1.0 .
#
# Build context: the repository root. Pin the bases by digest with --build-arg GO_IMAGE=...@sha256:...
ARG GO_IMAGE=golang:1.26.8-bookworm
ARG RUNTIME_IMAGE=scratch

FROM ${GO_IMAGE} AS build
COPY deploy/devcluster/build.sh deploy/devcluster/versions.env /src/deploy/devcluster/
COPY deploy/deviceplugin /src/deploy/deviceplugin
RUN bash /src/deploy/devcluster/build.sh --cache-dir /build deviceplugin \
    && mkdir /out \
    && install -m 0755 "$(readlink -f /build/toolchain/bin/simtest-device-plugin)" /out/simtest-device-plugin

# A static binary needs nothing else: no shell, no libc, no CA bundle (in-cluster credentials
# carry their own CA).
FROM ${RUNTIME_IMAGE}
LABEL org.opencontainers.image.title="simtest-device-plugin" \
      org.opencontainers.image.description="Kubelet device plugin advertising simtest.dev/simulator slots" \
      org.opencontainers.image.source="https://github.com/simtest-dev/simtest-operator" \
      org.opencontainers.image.licenses="Apache-2.0"
COPY --from=build /out/simtest-device-plugin /simtest-device-plugin
# Root, unlike every other simtest image: the plugin creates its socket in the kubelet's
# device-plugin directory (a hostPath, /var/lib/kubelet/device-plugins, owned by root with mode
# 0750) and connects to the kubelet's kubelet.sock there (root-only). The chart's DaemonSet still
# drops every capability, forbids privilege escalation and mounts the root file system read-only:
# uid 0 is needed for those file permissions, nothing more.
USER 0:0
ENTRYPOINT ["/simtest-device-plugin"]
