"""The same table of invalid manifests against the real API server with the generated CRDs
(server-side validation: OpenAPI schema + CEL rules), each rejected with a message naming the field.

Requests are server-side dry runs with strict field validation, as ``kubectl apply`` sends them,
so nothing is stored and unknown fields are errors rather than warnings."""

from __future__ import annotations

import json
from typing import Any

import pytest
from kubernetes import client
from kubernetes.client.exceptions import ApiException

from simtest_operator.api.v1alpha1 import common, kinds
from tests.api import badmanifests

SERVER_CASES = [case for case in badmanifests.load() if not case.local_only]


def _create(api: client.ApiClient, manifest: dict[str, Any]) -> None:
    client.CustomObjectsApi(api).create_namespaced_custom_object(
        group=common.GROUP,
        version=common.VERSION,
        namespace="default",
        plural=kinds.TEST_CAMPAIGN.plural,
        body=manifest,
        dry_run="All",
        field_validation="Strict",
    )


def _message(error: ApiException) -> str:
    try:
        status = json.loads(error.body)
    except (TypeError, ValueError):
        return str(error.body)
    causes = status.get("details", {}).get("causes", [])
    parts = [status.get("message", "")]
    parts += [f"{cause.get('field', '')}: {cause.get('message', '')}" for cause in causes]
    return "\n".join(parts)


def test_base_manifest_is_accepted(k8s_api_client: client.ApiClient) -> None:
    _create(k8s_api_client, badmanifests.base())


@pytest.mark.parametrize("case", SERVER_CASES, ids=[case.id for case in SERVER_CASES])
def test_rejected_by_the_api_server(
    k8s_api_client: client.ApiClient, case: badmanifests.BadManifest
) -> None:
    with pytest.raises(ApiException) as caught:
        _create(k8s_api_client, case.manifest)
    assert caught.value.status in (400, 422), caught.value.body
    message = _message(caught.value)
    assert case.names_field(message), f"{case.field!r} not named in: {message}"
