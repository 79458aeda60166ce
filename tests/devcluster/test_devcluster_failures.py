"""Failures of ``DevCluster.up`` are reported fast and leave nothing running.

Uses stand-in executables (small scripts) instead of the real binaries, so it runs without the
Go build: a component that dies is named with its log tail, a busy apiserver port is refused up
front, missing binaries name the build script, and ``down`` (called by the failed ``up``) stops
the processes that had already started — and only those.
"""

from __future__ import annotations

import socket
import sys
import time
from pathlib import Path

import pytest

from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.toolchain import CONTROL_PLANE_BINARIES, Toolchain
from simtest_operator.errors import ClusterError, ToolchainError

# Serves 200 on every GET at the port of --listen-client-urls, like etcd's /health.
FAKE_ETCD = f"""#!{sys.executable}
import http.server, sys
url = next(a for a in sys.argv if a.startswith("--listen-client-urls=")).split("=", 1)[1]
port = int(url.rsplit(":", 1)[1])
class H(http.server.BaseHTTPRequestHandler):
    def do_GET(self):
        self.send_response(200); self.end_headers(); self.wfile.write(b'{{"health":"true"}}')
    def log_message(self, *args): pass
http.server.HTTPServer(("127.0.0.1", port), H).serve_forever()
"""

CRASH = """#!/bin/sh
echo "E0101 run.go:72] failed to listen on 127.0.0.1: bind: address already in use" >&2
exit 1
"""


def _toolchain(tmp_path: Path, scripts: dict[str, str]) -> Toolchain:
    bin_dir = tmp_path / "toolchain" / "bin"
    bin_dir.mkdir(parents=True)
    for name in CONTROL_PLANE_BINARIES:
        path = bin_dir / name
        path.write_text(scripts.get(name, CRASH))
        path.chmod(0o755)
    return Toolchain(root=tmp_path / "toolchain")


def test_crashing_component_is_named_with_its_log_tail(tmp_path: Path) -> None:
    cluster = DevCluster(tmp_path / "c", _toolchain(tmp_path, {}))
    started = time.monotonic()
    with pytest.raises(ClusterError, match=r"(?s)etcd exited .*address already in use"):
        cluster.up(timeout=30)
    assert time.monotonic() - started < 10
    assert not cluster.status().started
    assert (tmp_path / "c" / "logs" / "etcd.log").exists()


def test_failed_up_stops_what_it_started(tmp_path: Path) -> None:
    cluster = DevCluster(tmp_path / "c", _toolchain(tmp_path, {"etcd": FAKE_ETCD}))
    with pytest.raises(ClusterError, match="kube-apiserver exited") as failure:
        cluster.up(timeout=30)
    assert "address already in use" in str(failure.value)
    # The fake etcd was up and serving; the failed `up` must have stopped it.
    etcd_port = int(
        next(
            line
            for line in (tmp_path / "c" / "logs" / "etcd.log").read_text().splitlines()
            if "start:" in line
        )
        .split("--listen-client-urls=http://127.0.0.1:")[1]
        .split()[0]
    )
    with socket.socket() as probe:
        assert probe.connect_ex(("127.0.0.1", etcd_port)) != 0
    assert not cluster.status().started
    assert cluster.down() == ()


def test_busy_apiserver_port_is_refused_before_starting(tmp_path: Path) -> None:
    cluster = DevCluster(tmp_path / "c", _toolchain(tmp_path, {"etcd": FAKE_ETCD}))
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        with pytest.raises(ClusterError, match=f"port {port} .* in use"):
            cluster.up(apiserver_port=port)
    assert not (tmp_path / "c" / "logs").exists()


def test_missing_binaries_point_to_the_build_script(tmp_path: Path) -> None:
    cluster = DevCluster(tmp_path / "c", Toolchain(root=tmp_path / "empty"))
    with pytest.raises(ToolchainError, match=r"etcd, kube-apiserver.*build\.sh"):
        cluster.up()
