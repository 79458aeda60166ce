"""Fixtures of the end-to-end tests on the dev control plane (marker ``cluster``, applied by the
shared cluster fixtures): a templates root with the test-only ``kwok`` template, a sources folder
and the operator process — whose logs are attached to the report of a failing test."""

from __future__ import annotations

from collections.abc import Generator, Iterator
from pathlib import Path

import pytest
from kubernetes import client

from tests.e2e import support

_operators = pytest.StashKey[list[support.OperatorProcess]]()


@pytest.fixture
def sources(tmp_path: Path) -> Path:
    folder = tmp_path / "sources"
    folder.mkdir()
    return folder


@pytest.fixture
def operator(
    request: pytest.FixtureRequest,
    kubeconfig_path: Path,
    k8s_namespace: str,
    sources: Path,
    tmp_path: Path,
) -> Iterator[support.OperatorProcess]:
    process = support.OperatorProcess(
        kubeconfig=kubeconfig_path,
        namespace=k8s_namespace,
        templates=support.templates_root(tmp_path),
        sources=sources,
        workdir=tmp_path,
    )
    request.node.stash.setdefault(_operators, []).append(process)
    try:
        yield process
    finally:
        process.stop()


@pytest.fixture
def cluster(k8s_api_client: client.ApiClient, k8s_namespace: str) -> support.Cluster:
    return support.Cluster(k8s_api_client, k8s_namespace)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    report = yield
    if report.failed:
        for process in item.stash.get(_operators, []):
            text = process.log_text()
            report.sections.append(("operator log (tail)", "\n".join(text.splitlines()[-150:])))
    return report
