"""Submitting a TestCampaign and following it: the cluster side of ``simtest submit``.

The CLI validates the manifest and formats progress; everything that talks to the API server
sits here, next to the rest of the operator's Kubernetes code. The ``kubernetes`` client is
imported only when a connection is made, so the CLI module stays light. Failures a user can act on
(credentials, a name already taken, a refused object) are :class:`ClusterError`\\ s whose message
says what to do; other API errors pass through.
"""

from __future__ import annotations

import time
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from simtest_operator.api.v1alpha1 import GROUP, VERSION
from simtest_operator.errors import ClusterError

CAMPAIGN_LABEL = "simtest.dev/campaign"
PLURAL = "testcampaigns"


def connect(kubeconfig: Path | None, context: str | None) -> tuple[CampaignClient, str]:
    """A client for ``kubeconfig`` (``context``), and the namespace that context defaults to.

    Without a kubeconfig the in-cluster service account is tried first (namespace ``default``),
    then ``$KUBECONFIG``."""
    import kubernetes.client
    import kubernetes.config

    try:
        if kubeconfig is None:
            try:
                kubernetes.config.load_incluster_config()  # type: ignore[no-untyped-call]
                return CampaignClient(kubernetes.client.ApiClient()), "default"
            except kubernetes.config.ConfigException:
                pass
        api = kubernetes.config.new_client_from_config(  # type: ignore[no-untyped-call]
            config_file=str(kubeconfig) if kubeconfig else None, context=context
        )
        _, active = kubernetes.config.list_kube_config_contexts(  # type: ignore[no-untyped-call]
            config_file=str(kubeconfig) if kubeconfig else None
        )
        namespace = (active or {}).get("context", {}).get("namespace") or "default"
    except (kubernetes.config.ConfigException, OSError) as exc:
        raise ClusterError(f"cannot load Kubernetes credentials: {exc}") from exc
    return CampaignClient(api), str(namespace)


class CampaignClient:
    """TestCampaigns and their ScenarioBatches through one API connection."""

    __slots__ = ("_custom",)

    def __init__(self, api: Any) -> None:
        import kubernetes.client

        self._custom: Any = kubernetes.client.CustomObjectsApi(api)

    def create(self, namespace: str, body: Mapping[str, Any], *, replace: bool) -> None:
        """Create the campaign; with ``replace`` an existing one of that name is deleted first."""
        from kubernetes.client.exceptions import ApiException

        name = body["metadata"]["name"]
        for attempt in range(2):
            try:
                self._custom.create_namespaced_custom_object(
                    GROUP, VERSION, namespace, PLURAL, body
                )
                return
            except ApiException as exc:
                if exc.status == 409 and replace and attempt == 0:
                    self._custom.delete_namespaced_custom_object(
                        GROUP, VERSION, namespace, PLURAL, name, propagation_policy="Foreground"
                    )
                    self._wait_gone(namespace, name)
                    continue
                if exc.status == 409:
                    raise ClusterError(
                        f"testcampaign/{name} already exists in {namespace}; "
                        "pass --replace to rerun it"
                    ) from exc
                raise ClusterError(
                    f"the API server refused the campaign: {exc.status} {exc.reason}: {exc.body}"
                ) from exc

    def _wait_gone(self, namespace: str, name: str, timeout: float = 120.0) -> None:
        from kubernetes.client.exceptions import ApiException

        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                self._custom.get_namespaced_custom_object(GROUP, VERSION, namespace, PLURAL, name)
            except ApiException as exc:
                if exc.status == 404:
                    return
                raise
            time.sleep(0.5)
        raise ClusterError(f"testcampaign/{name} was not deleted within {timeout:.0f}s")

    def watch(self, namespace: str, name: str, timeout: float) -> Iterator[Mapping[str, Any]]:
        """The campaign as it changes, for at most ``timeout`` seconds (one watch)."""
        import kubernetes.watch

        watcher = kubernetes.watch.Watch()  # type: ignore[no-untyped-call]
        stream = watcher.stream(  # type: ignore[no-untyped-call]
            self._custom.list_namespaced_custom_object,
            GROUP,
            VERSION,
            namespace,
            PLURAL,
            field_selector=f"metadata.name={name}",
            timeout_seconds=max(int(timeout), 1),
        )
        for event in stream:
            yield event["object"]

    def results(self, namespace: str, name: str) -> list[Mapping[str, Any]]:
        """Per-scenario results of the campaign's ScenarioBatches, each with its scenario's
        ``sha256`` from the batch's frozen list."""
        reply = self._custom.list_namespaced_custom_object(
            GROUP, VERSION, namespace, "scenariobatches", label_selector=f"{CAMPAIGN_LABEL}={name}"
        )
        results: list[Mapping[str, Any]] = []
        for batch in reply.get("items", []):
            spec = batch.get("spec", {})
            digests = {s["id"]: s.get("sha256", "") for s in spec.get("scenarios", [])}
            for result in (batch.get("status") or {}).get("results", []):
                results.append({**result, "sha256": digests.get(result.get("id"), "")})
        return results
