"""Pass/fail criteria, evaluated online while each scenario runs, and the offline evaluation step
that re-scores the recorded runs once the campaign is over."""

from __future__ import annotations

import enum
from typing import Annotated

from pydantic import Field, StringConstraints

from simtest_operator.api.v1alpha1.common import ApiModel, DnsLabel

Seconds = Annotated[float, Field(ge=0, le=3600)]


class CollisionPolicy(enum.StrEnum):
    """What a collision of the ego means."""

    FORBIDDEN = "Forbidden"
    """Any bounding-box contact of the ego with another entity fails the scenario."""
    ALLOWED = "Allowed"
    """Collisions are recorded as metrics only."""


class Criteria(ApiModel):
    """Criteria the system under test must meet. Unset thresholds are not checked."""

    collision: CollisionPolicy = CollisionPolicy.FORBIDDEN
    """Forbidden or Allowed."""
    min_ttc: Seconds | None = None
    """Minimum time to collision (s) the ego must keep to the entity ahead, e.g. 1.5."""
    min_thw: Seconds | None = None
    """Minimum time headway (s) the ego must keep to the entity ahead."""
    max_deceleration: Annotated[float, Field(gt=0, le=30)] | None = None
    """Largest deceleration (m/s^2) the ego may apply."""
    off_road: bool = True
    """Fail when the ego leaves the drivable road."""
    complete_within: Annotated[float, Field(gt=0, le=86400)] | None = None
    """The storyboard must complete within this simulated time (s)."""


class CriteriaPatch(ApiModel):
    """A partial set of criteria; every field set replaces the campaign-wide value."""

    collision: CollisionPolicy | None = None
    """Forbidden or Allowed."""
    min_ttc: Seconds | None = None
    """Minimum time to collision (s)."""
    min_thw: Seconds | None = None
    """Minimum time headway (s)."""
    max_deceleration: Annotated[float, Field(gt=0, le=30)] | None = None
    """Largest deceleration (m/s^2)."""
    off_road: bool | None = None
    """Fail when the ego leaves the road."""
    complete_within: Annotated[float, Field(gt=0, le=86400)] | None = None
    """Simulated-time limit (s) for the storyboard to complete."""


class CriteriaOverride(ApiModel):
    """Criteria for the scenarios whose id matches a glob."""

    scenarios: Annotated[str, StringConstraints(min_length=1, max_length=1024)]
    """Glob over scenario ids, e.g. ``cut-in/*`` or ``pedestrian/*night*``."""
    criteria: CriteriaPatch
    """The fields to replace for those scenarios."""


class ConfigMapKeyRef(ApiModel):
    """A key of a ConfigMap in the campaign's namespace."""

    name: DnsLabel
    """Name of the ConfigMap."""
    key: Annotated[str, StringConstraints(pattern=r"^[-._a-zA-Z0-9]+$", max_length=253)]
    """Key within the ConfigMap's data."""


class CriteriaSetSource(ApiModel):
    """Where the offline evaluation's criteria set (``simtest evaluate --criteria``) comes from."""

    config_map_ref: ConfigMapKeyRef
    """A ConfigMap key holding the criteria set as YAML or JSON (docs/evaluation.md)."""


class OfflineEvaluationSpec(ApiModel):
    """An evaluation step after the runs: one Job re-scores the campaign's recordings from the
    results database (``simtest evaluate``) and stores a new evaluation of the run."""

    criteria: CriteriaSetSource | None = None
    """The criteria set; unset: the built-in set ``default``."""
    backoff_limit: Annotated[int, Field(ge=0, le=10)] = 1
    """Retries of the evaluation Job after a crash (each try is a new evaluation); a verdict
    (exit 1) or bad input (exit 2) is final and not retried."""


class EvaluationSpec(ApiModel):
    """Criteria for the whole campaign, with per-scenario overrides (last match wins), and an
    optional offline evaluation step."""

    criteria: Criteria = Field(default_factory=Criteria)
    """Campaign-wide criteria."""
    overrides: list[CriteriaOverride] = Field(default_factory=list)
    """Per-scenario replacements, applied in order."""
    offline: OfflineEvaluationSpec | None = None
    """Re-score the recordings once every scenario has its verdict (needs
    ``results.databaseSecretRef``); the outcome is the condition ``Evaluated``."""
