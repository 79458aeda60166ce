"""Render tests share the chart tests' real helm/helmfile/kubectl fixtures (see helmtools)."""

from __future__ import annotations

from tests.charts.conftest import pytest_collection_finish
from tests.charts.helmtools import helm, helmfile, kubectl, tools_home

__all__ = [
    "helm",
    "helmfile",
    "kubectl",
    "pytest_collection_finish",
    "tools_home",
]
