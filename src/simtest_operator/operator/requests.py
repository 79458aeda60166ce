"""From a campaign's spec and one SimEnvironment to the render request of its pod.

The only place where the wire spec (``api``) meets the render inputs; rendering itself never sees
pydantic models.
"""

from __future__ import annotations

from typing import Any

from simtest_operator.api import converting
from simtest_operator.api.v1alpha1 import API_VERSION, TestCampaignSpec
from simtest_operator.operator import names
from simtest_operator.operator.observed import EnvironmentView
from simtest_operator.render import (
    Amounts,
    ArtifactTarget,
    EnvironmentRequest,
    OwnerRef,
    PvcVolume,
    S3Target,
    SecretKey,
)
from simtest_operator.scenarios import needs
from simtest_operator.settings import OperatorSettings


def environment_request(
    spec: TestCampaignSpec, env: EnvironmentView, *, config: OperatorSettings, run_key: str = ""
) -> EnvironmentRequest:
    """What the environment's pod renders from.

    ``run_key`` names the campaign's run in the results database (see
    ``recording_results.run_key``); callers that only need names or release lists may omit it.
    """
    execution = spec.execution
    requests = execution.resources.requests
    limits = execution.resources.limits or requests
    environment = spec.environment
    database = spec.results.database_secret_ref
    return EnvironmentRequest(
        template=environment.template,
        namespace=env.namespace,
        name=env.name,
        campaign=env.campaign,
        batch=env.batch,
        attempt=env.attempt,
        labels=names.environment_labels(env.campaign, env.batch, env.attempt),
        owner=OwnerRef(api_version=API_VERSION, kind="SimEnvironment", name=env.name, uid=env.uid),
        service_account=names.service_account(env.campaign),
        scenarios=env.scenarios,
        isolation=execution.isolation.value,
        image=environment.simulator.image,
        requests=Amounts(cpu=requests.cpu, memory=requests.memory, gpu=requests.gpu),
        limits=Amounts(cpu=limits.cpu, memory=limits.memory, gpu=limits.gpu),
        timeout_seconds=execution.timeout_seconds,
        node_selector=dict(execution.node_selector),
        tolerations=tuple(t.to_wire() for t in execution.tolerations),
        artifacts=artifacts(spec, env.campaign),
        scenario_volume=PvcVolume(claim_name=config.inputs.scenario_claim, read_only=True)
        if config.inputs.scenario_claim
        else None,
        scenario_mount=str(config.inputs.sources_dir.absolute())
        if config.inputs.scenario_claim
        else "/scenarios",
        source_needs=needs(
            (s.source for s in env.scenarios),
            tuple(converting.source(entry) for entry in spec.scenarios.sources),
        ),
        results_dsn=SecretKey(name=database.name, key=database.key) if database else None,
        results_run_key=run_key if database else "",
        sut=environment.sut.to_wire(),
        simulator=environment.simulator.to_wire(),
        # The evaluation step is the operator's business: pods (and their hashes) stay as before.
        evaluation={k: v for k, v in spec.evaluation.to_wire().items() if k != "offline"},
        values=dict(environment.values),
    )


def artifacts(spec: TestCampaignSpec, campaign: str) -> ArtifactTarget:
    """Where the campaign's runs keep their artifacts, and the URIs they report."""
    pvc, s3 = spec.artifacts.pvc, spec.artifacts.s3
    keep = spec.artifacts.keep_recordings
    if s3 is not None:
        return ArtifactTarget(
            s3=S3Target(endpoint=s3.endpoint, secret_name=s3.secret_ref),
            uri_prefix=f"s3://{s3.bucket}/" + "/".join(p for p in (s3.prefix, campaign) if p),
            keep_recordings=keep,
        )
    if pvc is None:
        return ArtifactTarget(keep_recordings=keep)
    sub = "/".join(p for p in (pvc.sub_path, campaign) if p)
    return ArtifactTarget(
        pvc=PvcVolume(claim_name=pvc.claim_name, sub_path=sub),
        uri_prefix=f"pvc://{pvc.claim_name}/{sub}",
        keep_recordings=keep,
    )


def tolerations(spec: TestCampaignSpec) -> list[tuple[str | None, str | None, str | None, str]]:
    """(key, value, effect, operator) of each toleration, for slot counting."""
    out = []
    for t in spec.execution.tolerations:
        wire: dict[str, Any] = t.to_wire()
        out.append(
            (
                wire.get("key"),
                wire.get("value"),
                wire.get("effect"),
                str(wire.get("operator", "Equal")),
            )
        )
    return out
