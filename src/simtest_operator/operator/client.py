"""The operator's own Kubernetes API client: the only code that sends writes to the API server.

Small and asynchronous (aiohttp, which kopf already depends on): create, merge-patch status,
delete, get, post events. Credentials come from a kubeconfig or the in-cluster service account,
loaded once through the official client's config loader (it understands every kubeconfig
flavour) and shared with kopf's own login, so both talk to the same server as the same user.

Errors are mapped once: ``AlreadyExistsError``, ``NotFoundError``, ``ConflictError`` (a stale
``resourceVersion``) and everything else as :class:`ApiError`; throttling and server errors are
retried with backoff before they surface. Secrets read here are returned to the caller only and
never logged.
"""

from __future__ import annotations

import asyncio
import dataclasses
import json
import ssl
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import aiohttp

from simtest_operator.api.v1alpha1 import GROUP, VERSION
from simtest_operator.errors import ClusterError
from simtest_operator.operator.actions import Kind

CORE_KINDS = frozenset({Kind.POD, Kind.CONFIG_MAP, Kind.SERVICE_ACCOUNT, "events", "secrets"})
MERGE_PATCH = "application/merge-patch+json"
RETRIED_STATUSES = frozenset({429, 500, 502, 503, 504})


class ApiError(ClusterError):
    """The API server refused a request; ``status`` and ``reason`` are from its Status reply."""

    def __init__(self, status: int, reason: str, message: str) -> None:
        self.status = status
        self.reason = reason
        super().__init__(f"{status} {reason}: {message}")


class NotFoundError(ApiError):
    """The object does not exist (any more)."""


class AlreadyExistsError(ApiError):
    """An object of that name exists already."""


class ConflictError(ApiError):
    """The object changed since the resourceVersion the write was based on; re-read, re-plan."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Credentials:
    """Where the API server is and who we are."""

    server: str
    ca_file: str | None = None
    insecure: bool = False
    token: str | None = None
    cert_file: str | None = None
    key_file: str | None = None
    refresh: Callable[[], str | None] | None = None
    """Returns a fresh bearer token (rotated service-account tokens, exec plugins)."""


def load_credentials(kubeconfig: Path | None = None, *, context: str | None = None) -> Credentials:
    """Credentials from ``kubeconfig`` (or ``$KUBECONFIG``/``~/.kube/config``), else in-cluster."""
    import kubernetes.client
    import kubernetes.config

    configuration = kubernetes.client.Configuration()
    try:
        if kubeconfig is None:
            try:
                kubernetes.config.load_incluster_config(client_configuration=configuration)  # type: ignore[no-untyped-call]
            except kubernetes.config.ConfigException:
                kubernetes.config.load_kube_config(  # type: ignore[no-untyped-call]
                    context=context, client_configuration=configuration
                )
        else:
            kubernetes.config.load_kube_config(  # type: ignore[no-untyped-call]
                config_file=str(kubeconfig), context=context, client_configuration=configuration
            )
    except (kubernetes.config.ConfigException, OSError) as exc:
        raise ClusterError(
            f"cannot load Kubernetes credentials ({exc}); pass --kubeconfig or run in a pod "
            "with a service account"
        ) from exc

    def token() -> str | None:
        hook: Any = getattr(configuration, "refresh_api_key_hook", None)
        if hook is not None:
            hook(configuration)
        header = configuration.get_api_key_with_prefix(
            "BearerToken"
        ) or configuration.get_api_key_with_prefix("authorization")
        if not header:
            return None
        return str(header).split(" ", 1)[-1]

    return Credentials(
        server=str(configuration.host).rstrip("/"),
        ca_file=configuration.ssl_ca_cert,
        insecure=not configuration.verify_ssl,
        token=token(),
        cert_file=configuration.cert_file,
        key_file=configuration.key_file,
        refresh=token,
    )


GROUP_PATHS: Mapping[str, str] = {
    Kind.JOB: "/apis/batch/v1",
    Kind.ROLE_BINDING: "/apis/rbac.authorization.k8s.io/v1",
    Kind.WORKLOAD: "/apis/kueue.x-k8s.io/v1beta2",
}
"""Kinds outside the core group and ours."""


def _path(kind: Kind | str, namespace: str | None, name: str | None = None) -> str:
    base = "/api/v1" if kind in CORE_KINDS else f"/apis/{GROUP}/{VERSION}"
    base = GROUP_PATHS.get(kind, base)
    if kind == "nodes":
        base = "/api/v1"
    scope = f"/namespaces/{namespace}" if namespace else ""
    tail = f"/{name}" if name else ""
    return f"{base}{scope}/{kind}{tail}"


class Client:
    """Async API client (one per operator process; create inside the running event loop)."""

    def __init__(
        self,
        credentials: Credentials,
        *,
        connections: int = 32,
        timeout: float = 30.0,
        on_request: Callable[[str, str, int], None] | None = None,
    ) -> None:
        self.credentials = credentials
        context = ssl.create_default_context(cafile=credentials.ca_file)
        if credentials.insecure:
            context.check_hostname = False
            context.verify_mode = ssl.CERT_NONE
        if credentials.cert_file and credentials.key_file:
            context.load_cert_chain(credentials.cert_file, credentials.key_file)
        self._session = aiohttp.ClientSession(
            connector=aiohttp.TCPConnector(ssl=context, limit=connections),
            timeout=aiohttp.ClientTimeout(total=timeout),
        )
        self._on_request = on_request

    async def close(self) -> None:
        """Release the connection pool."""
        await self._session.close()

    def _headers(self, content_type: str) -> dict[str, str]:
        headers = {"Accept": "application/json", "Content-Type": content_type}
        refresh = self.credentials.refresh
        token = refresh() if refresh is not None else self.credentials.token
        if token:
            headers["Authorization"] = f"Bearer {token}"
        return headers

    async def request(
        self,
        method: str,
        path: str,
        *,
        body: Any = None,
        params: Mapping[str, str] | None = None,
        content_type: str = "application/json",
        kind: str = "",
    ) -> dict[str, Any]:
        """One request, retried on throttling and server errors; the parsed JSON reply."""
        data = json.dumps(body) if body is not None else None
        delay = 0.2
        for attempt in range(5):
            try:
                async with self._session.request(
                    method,
                    self.credentials.server + path,
                    data=data,
                    params=params,
                    headers=self._headers(content_type),
                ) as response:
                    text = await response.text()
                    status = response.status
            except (aiohttp.ClientError, TimeoutError) as exc:
                if attempt == 4:
                    raise ClusterError(f"{method} {path}: {exc}") from exc
                await asyncio.sleep(delay)
                delay *= 2
                continue
            if self._on_request is not None:
                self._on_request(method, kind, status)
            if status < 300:
                return json.loads(text) if text else {}
            if status in RETRIED_STATUSES and attempt < 4:
                await asyncio.sleep(delay)
                delay *= 2
                continue
            raise _error(status, text)
        raise ClusterError(f"{method} {path}: retries exhausted")

    # --- verbs -----------------------------------------------------------------------------

    async def create(
        self, kind: Kind | str, namespace: str, body: Mapping[str, Any]
    ) -> dict[str, Any]:
        """Create ``body``; raises :class:`AlreadyExistsError` when the name is taken."""
        return await self.request("POST", _path(kind, namespace), body=body, kind=str(kind))

    async def get(self, kind: Kind | str, namespace: str | None, name: str) -> dict[str, Any]:
        """Read one object; raises :class:`NotFoundError`."""
        return await self.request("GET", _path(kind, namespace, name), kind=str(kind))

    async def patch_status(
        self,
        kind: Kind | str,
        namespace: str,
        name: str,
        patch: Mapping[str, Any],
        *,
        resource_version: str | None = None,
    ) -> dict[str, Any]:
        """Merge-patch the status subresource (conditional on ``resource_version`` if given)."""
        body: dict[str, Any] = {"status": dict(patch)}
        if resource_version is not None:
            body["metadata"] = {"resourceVersion": resource_version}
        return await self.request(
            "PATCH",
            _path(kind, namespace, name) + "/status",
            body=body,
            content_type=MERGE_PATCH,
            kind=str(kind),
        )

    async def delete(
        self,
        kind: Kind | str,
        namespace: str,
        name: str,
        *,
        uid: str | None = None,
        grace_seconds: int | None = None,
    ) -> None:
        """Delete (background propagation); ``NotFoundError`` and a changed uid count as done."""
        options: dict[str, Any] = {
            "apiVersion": "v1",
            "kind": "DeleteOptions",
            "propagationPolicy": "Background",
        }
        if uid is not None:
            options["preconditions"] = {"uid": uid}
        if grace_seconds is not None:
            options["gracePeriodSeconds"] = grace_seconds
        try:
            await self.request("DELETE", _path(kind, namespace, name), body=options, kind=str(kind))
        except (NotFoundError, ConflictError):
            return


def _error(status: int, text: str) -> ApiError:
    try:
        reply = json.loads(text)
    except ValueError:
        reply = {}
    reason = str(reply.get("reason", "")) if isinstance(reply, dict) else ""
    message = str(reply.get("message", text[:300])) if isinstance(reply, dict) else text[:300]
    if status == 404:
        return NotFoundError(status, reason or "NotFound", message)
    if status == 409 and reason == "AlreadyExists":
        return AlreadyExistsError(status, reason, message)
    if status == 409:
        return ConflictError(status, reason or "Conflict", message)
    return ApiError(status, reason or "Error", message)
