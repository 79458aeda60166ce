"""The environment request the operator would build for one scenario, without a cluster.

``simtest render`` previews what the operator creates: the SimEnvironment body, its view and
:func:`requests.environment_request` are the operator's own pure functions, so the preview is the
request of the scenario's first environment (first attempt, isolation ``PerScenario``
granularity) byte for byte.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from simtest_operator import render
from simtest_operator.api import v1alpha1
from simtest_operator.operator import bodies, names, observed, requests
from simtest_operator.scenarios.pinned import PinnedScenario
from simtest_operator.settings import InputSettings, OperatorSettings

PLACEHOLDER_UID = "00000000-0000-0000-0000-000000000000"
"""uid of the SimEnvironment and batch that do not exist yet (owner references show it)."""


def environment_request(
    campaign: v1alpha1.Manifest[v1alpha1.TestCampaignSpec],
    frozen: Sequence[PinnedScenario],
    position: int,
    *,
    namespace: str,
    templates: Path,
) -> render.EnvironmentRequest:
    """The operator's request for the first environment of scenario ``frozen[position]``."""
    spec = campaign.spec
    batch_size = spec.execution.batch_size
    batch_index, first = divmod(position, batch_size)
    body = bodies.environment(
        campaign=campaign.name,
        namespace=namespace,
        batch_name=names.batch(campaign.name, batch_index),
        batch_uid=PLACEHOLDER_UID,
        name=names.environment(campaign.name, batch_index, first, 1),
        attempt=1,
        isolation=spec.execution.isolation.value,
        scenarios=[frozen[position]],
    )
    body["metadata"]["uid"] = PLACEHOLDER_UID
    config = OperatorSettings(inputs=InputSettings(templates_dir=templates))
    return requests.environment_request(spec, observed.environment_view(body), config=config)
