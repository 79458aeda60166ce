"""Kubeconfig files for the dev cluster: the admin one for people and tests, one per component.

They embed the cluster CA, so TLS is verified (the serving cert covers 127.0.0.1 and localhost)
and the same file works unchanged for kubectl, helm, kopf, kwok and the Python client.
"""

from __future__ import annotations

import base64
from pathlib import Path
from typing import Any

import yaml

CONTEXT = "simtest-dev"


def render(*, server: str, ca_pem: bytes, user: str, token: str) -> dict[str, Any]:
    """The kubeconfig document for one token user."""
    return {
        "apiVersion": "v1",
        "kind": "Config",
        "clusters": [
            {
                "name": CONTEXT,
                "cluster": {
                    "server": server,
                    "certificate-authority-data": base64.b64encode(ca_pem).decode(),
                },
            }
        ],
        "users": [{"name": user, "user": {"token": token}}],
        "contexts": [{"name": CONTEXT, "context": {"cluster": CONTEXT, "user": user}}],
        "current-context": CONTEXT,
        "preferences": {},
    }


def write(path: Path, *, server: str, ca_pem: bytes, user: str, token: str) -> Path:
    """Write a kubeconfig readable only by its owner (it holds a bearer token)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    text = yaml.safe_dump(render(server=server, ca_pem=ca_pem, user=user, token=token))
    tmp = path.with_suffix(".tmp")
    tmp.write_text(text)
    tmp.chmod(0o600)
    tmp.replace(path)
    return path
