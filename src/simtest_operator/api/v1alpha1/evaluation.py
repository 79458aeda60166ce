"""Pass/fail criteria, evaluated online while each scenario runs."""

from __future__ import annotations

import enum
from typing import Annotated

from pydantic import Field, StringConstraints

from simtest_operator.api.v1alpha1.common import ApiModel

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


class EvaluationSpec(ApiModel):
    """Criteria for the whole campaign, with per-scenario overrides (last match wins)."""

    criteria: Criteria = Field(default_factory=Criteria)
    """Campaign-wide criteria."""
    overrides: list[CriteriaOverride] = Field(default_factory=list)
    """Per-scenario replacements, applied in order."""
