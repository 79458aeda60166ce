"""Chart tests: real helm/helmfile/kubectl fixtures (see helmtools) and the golden-file switch."""

from __future__ import annotations

import pytest

from tests.charts.helmtools import build_selected, helm, helmfile, kubectl, tools_home

__all__ = ["helm", "helmfile", "kubectl", "tools_home"]


def pytest_collection_finish(session: pytest.Session) -> None:
    build_selected(session)


@pytest.fixture
def update_golden(request: pytest.FixtureRequest) -> bool:
    """``--update-golden`` (registered by tests/render/conftest.py) rewrites the golden files."""
    return bool(request.config.getoption("--update-golden", default=False))
