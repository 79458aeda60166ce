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


def render(
    *,
    server: str,
    ca_pem: bytes,
    user: str,
    token: str | None = None,
    client_cert: Path | None = None,
    client_key: Path | None = None,
) -> dict[str, Any]:
    """The kubeconfig document for one user: a bearer token, or a client certificate (files)."""
    credentials: dict[str, str] = {"token": token} if token else {}
    if client_cert and client_key:
        credentials = {"client-certificate": str(client_cert), "client-key": str(client_key)}
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
        "users": [{"name": user, "user": credentials}],
        "contexts": [{"name": CONTEXT, "context": {"cluster": CONTEXT, "user": user}}],
        "current-context": CONTEXT,
        "preferences": {},
    }


def write(
    path: Path,
    *,
    server: str,
    ca_pem: bytes,
    user: str,
    token: str | None = None,
    client_cert: Path | None = None,
    client_key: Path | None = None,
) -> Path:
    """Write a kubeconfig readable only by its owner (it holds credentials)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    document = render(
        server=server,
        ca_pem=ca_pem,
        user=user,
        token=token,
        client_cert=client_cert,
        client_key=client_key,
    )
    text = yaml.safe_dump(document)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(text)
    tmp.chmod(0o600)
    tmp.replace(path)
    return path
