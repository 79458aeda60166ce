"""The restricted Pod Security settings of every pod the product renders in Python.

The evaluation Job (``render``) and the helmfile Jobs (``packaging``) sit side by side and may not
import each other, so both take their ``securityContext`` blocks from here; the simulator pod's
template spells the same values in Jinja, and ``render.podchecks`` checks all of them.
"""

from __future__ import annotations

from typing import Any

RUN_AS = 65532
"""The images' numeric non-root user and group (runner, helmfile, operator)."""


def pod_context() -> dict[str, Any]:
    """The pod-level ``securityContext``: non-root ``RUN_AS``, the runtime's seccomp profile."""
    return {
        "runAsNonRoot": True,
        "runAsUser": RUN_AS,
        "runAsGroup": RUN_AS,
        "fsGroup": RUN_AS,
        "seccompProfile": {"type": "RuntimeDefault"},
    }


def container_context() -> dict[str, Any]:
    """A container's ``securityContext``: no privilege escalation, no capabilities, a
    read-only root filesystem (writable paths are volumes)."""
    return {
        "runAsNonRoot": True,
        "allowPrivilegeEscalation": False,
        "readOnlyRootFilesystem": True,
        "capabilities": {"drop": ["ALL"]},
        "seccompProfile": {"type": "RuntimeDefault"},
    }
