"""Names and labels of the objects a campaign owns, derived from ids — never random.

Deterministic names make every create idempotent (a repeated create after a crash or a stale
cache is a harmless ``409 AlreadyExistsError``) and let a restarted operator find everything again.

::

    <campaign>-scenarios            ConfigMap with the frozen list (its head, when chunked)
    <campaign>-scenarios-3-1a2b3c4d ConfigMap with chunk 3 of a long frozen list (by content)
    <campaign>-simulator            ServiceAccount of the simulator pods (no RBAC bindings)
    <campaign>-evaluate             Job of the evaluation step (spec.evaluation.offline)
    <campaign>-b00042               ScenarioBatch 42
    <campaign>-b00042-e007-a2       SimEnvironment (and its pod): scenario 7 of batch 42, attempt 2
"""

from __future__ import annotations

import dataclasses
import re

LABEL_CAMPAIGN = "simtest.dev/campaign"
LABEL_BATCH = "simtest.dev/batch"
LABEL_ATTEMPT = "simtest.dev/attempt"
LABEL_MANAGED_BY = "app.kubernetes.io/managed-by"
MANAGED_BY = "simtest-operator"
LABEL_COMPONENT = "app.kubernetes.io/component"

_ENV = re.compile(r"^(?P<batch>.+-b(?P<index>\d{5,}))-e(?P<first>\d{3})-a(?P<attempt>\d+)$")


def scenario_list(campaign: str) -> str:
    """ConfigMap holding the campaign's frozen scenario list."""
    return f"{campaign}-scenarios"


def scenario_list_chunk(campaign: str, index: int, digest: str) -> str:
    """ConfigMap holding chunk ``index`` (from 1) of a frozen list too long for one object,
    named by its content, so a resolution retried after a crash never meets a stale chunk."""
    return f"{scenario_list(campaign)}-{index}-{digest[:8]}"


def service_account(campaign: str) -> str:
    """ServiceAccount the campaign's simulator pods run as."""
    return f"{campaign}-simulator"


def evaluation_job(campaign: str) -> str:
    """Job of the campaign's evaluation step: one per campaign, so a restart finds it."""
    return f"{campaign}-evaluate"


def evaluation_labels(campaign: str) -> dict[str, str]:
    """Labels of the evaluation Job and its pod."""
    return {**campaign_labels(campaign), LABEL_COMPONENT: "evaluation"}


def batch(campaign: str, index: int) -> str:
    """ScenarioBatch ``index`` of ``campaign``: five digits at least, more past 99,999 (a list
    of up to ~800,000 scenarios may have batches of one), so existing names never change."""
    return f"{campaign}-b{index:05d}"


def environment(campaign: str, batch_index: int, first: int, attempt: int) -> str:
    """SimEnvironment (and pod) running the unit that starts at slice position ``first``."""
    return f"{batch(campaign, batch_index)}-e{first:03d}-a{attempt}"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EnvironmentName:
    """The parts of an environment name."""

    batch: str
    batch_index: int
    first: int
    attempt: int


def parse_environment(name: str) -> EnvironmentName | None:
    """Inverse of :func:`environment`; None for names the operator did not make."""
    match = _ENV.match(name)
    if match is None:
        return None
    return EnvironmentName(
        batch=match["batch"],
        batch_index=int(match["index"]),
        first=int(match["first"]),
        attempt=int(match["attempt"]),
    )


def campaign_labels(campaign: str) -> dict[str, str]:
    """Labels every object of a campaign carries (the operator selects by them)."""
    return {LABEL_CAMPAIGN: campaign, LABEL_MANAGED_BY: MANAGED_BY}


def environment_labels(campaign: str, batch_name: str, attempt: int) -> dict[str, str]:
    """Labels of a SimEnvironment and its pod."""
    return {
        **campaign_labels(campaign),
        LABEL_BATCH: batch_name,
        LABEL_ATTEMPT: str(attempt),
        LABEL_COMPONENT: "simulator",
    }
