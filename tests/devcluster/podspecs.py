"""Small helpers shared by the cluster tests: pod manifests and bounded polling."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

from simtest_operator.devcluster.nodes import SIMULATOR_RESOURCE

T = TypeVar("T")


def simulator_pod(
    name: str, *, slots: int = 1, annotations: Mapping[str, str] | None = None
) -> dict[str, Any]:
    """A bare pod asking for ``slots`` simulator units (extended resources: limits only)."""
    return {
        "apiVersion": "v1",
        "kind": "Pod",
        "metadata": {"name": name, "annotations": dict(annotations or {})},
        "spec": {
            "restartPolicy": "Never",
            "terminationGracePeriodSeconds": 0,
            "containers": [
                {
                    "name": "sim",
                    "image": "simtest.dev/fake-simulator:0",
                    "resources": {"limits": {SIMULATOR_RESOURCE: str(slots)}},
                }
            ],
        },
    }


def eventually(check: Callable[[], T | None], *, timeout: float, what: str) -> T:
    """Poll ``check`` every 0.2 s until it returns something truthy; fail after ``timeout``."""
    deadline = time.monotonic() + timeout
    while True:
        value = check()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"not within {timeout:.0f}s: {what} (last: {value!r})")
        time.sleep(0.2)
