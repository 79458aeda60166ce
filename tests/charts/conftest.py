"""Chart tests: real helm/helmfile/kubectl fixtures (see helmtools)."""

from __future__ import annotations

import pytest

from tests.charts.helmtools import build_selected, helm, helmfile, kubectl, tools_home

__all__ = ["helm", "helmfile", "kubectl", "tools_home"]


def pytest_collection_finish(session: pytest.Session) -> None:
    build_selected(session)
