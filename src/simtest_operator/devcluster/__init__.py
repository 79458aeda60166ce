"""The dev control plane: a real Kubernetes control plane, kwok nodes and one real node, run as
local processes (``simtest dev-cluster``).

This module is the package's public entry, and the only part of it the CLI may import
(import-linter enforces that): the toolchain that builds and holds the binaries
(:class:`Toolchain`, :func:`find_build_script`, :func:`build_toolchain`), the cluster itself
(:class:`DevCluster` with its node shape, :class:`NodeShape`), and what a real node needs
(:func:`real_node_setup`, the chart it installs from :func:`find_chart`).
"""

from __future__ import annotations

from simtest_operator.devcluster.addons import find_chart
from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.images import real_node_setup
from simtest_operator.devcluster.nodes import NodeShape
from simtest_operator.devcluster.toolchain import Toolchain, find_build_script
from simtest_operator.devcluster.toolchain import build as build_toolchain

__all__ = [
    "DevCluster",
    "NodeShape",
    "Toolchain",
    "build_toolchain",
    "find_build_script",
    "find_chart",
    "real_node_setup",
]
