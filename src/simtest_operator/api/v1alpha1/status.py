"""Status vocabulary shared by the three kinds: phases, counters and per-scenario results."""

from __future__ import annotations

import datetime
import enum
from typing import Annotated

from pydantic import Field, StringConstraints

from simtest_operator.api.v1alpha1.common import ApiModel, Condition
from simtest_operator.verdicts import Verdict

Count = Annotated[int, Field(ge=0)]


class Phase(enum.StrEnum):
    """Lifecycle phase of a TestCampaign or ScenarioBatch."""

    PENDING = "Pending"
    RESOLVING = "Resolving"
    RUNNING = "Running"
    SUSPENDED = "Suspended"
    SUCCEEDED = "Succeeded"
    """Every scenario ran and passed."""
    FAILED = "Failed"
    """Every scenario ended, at least one Failed or timed out."""
    ERROR = "Error"
    """Every scenario ended, at least one with Error or Invalid, or resolution failed."""
    CANCELLED = "Cancelled"

    @property
    def finished(self) -> bool:
        """Whether the phase is terminal."""
        return self in (Phase.SUCCEEDED, Phase.FAILED, Phase.ERROR, Phase.CANCELLED)


class Counters(ApiModel):
    """How many scenarios are in each state; the same fields on campaigns and batches."""

    total: Count = 0
    """Scenarios selected."""
    queued: Count = 0
    """Not started yet."""
    running: Count = 0
    """In flight (pod pending or running)."""
    passed: Count = 0
    """Final verdict Passed."""
    failed: Count = 0
    """Final verdict Failed."""
    errored: Count = 0
    """Final verdict Error (after retries)."""
    timed_out: Count = 0
    """Final verdict Timeout."""
    invalid: Count = 0
    """Final verdict Invalid (the scenario file cannot be run)."""
    skipped: Count = 0
    """Final verdict Skipped (cancelled before it ran)."""


class ScenarioResult(ApiModel):
    """The final result of one scenario, as kept in its batch's status."""

    id: Annotated[str, StringConstraints(min_length=1, max_length=1024)]
    """Scenario id from the frozen list."""
    verdict: Verdict
    """Passed, Failed, Error, Timeout, Invalid or Skipped."""
    reason: Annotated[str, StringConstraints(max_length=1024)] = ""
    """One-line reason."""
    metrics: dict[str, float] = Field(default_factory=dict)
    """Key metrics (minTTC, minTHW, minDistance, maxDecel, ...)."""
    duration_seconds: Annotated[float, Field(ge=0)] = 0.0
    """Wall time of the final attempt."""
    attempts: Annotated[int, Field(ge=1)] = 1
    """Attempts made (more than one only after infrastructure errors)."""
    artifacts: dict[str, str] = Field(default_factory=dict)
    """Artifact name to URI (recording, log, result)."""
    results_stored: bool | None = None
    """``false`` when the pod could not store this attempt in the results database (down,
    misconfigured, no time left); absent otherwise. The verdict stands either way."""
    sut_image_id: Annotated[str, StringConstraints(max_length=512)] | None = None
    """The external SUT's image as the kubelet ran it for this attempt: its ``imageID``, e.g.
    ``ghcr.io/acme/planner@sha256:…`` (registry digest) or ``sha256:…`` (the runtime's image id);
    absent without a SUT container."""


class CommonStatus(Counters):
    """Fields every kind's status carries."""

    phase: Phase = Phase.PENDING
    """Lifecycle phase."""
    observed_generation: Annotated[int, Field(ge=0)] | None = None
    """The ``metadata.generation`` the status reflects."""
    progress: Annotated[str, StringConstraints(max_length=32)] = ""
    """Finished over total, e.g. ``120/200``."""
    start_time: datetime.datetime | None = None
    """When execution began."""
    completion_time: datetime.datetime | None = None
    """When the last scenario finished."""
    conditions: list[Condition] = Field(default_factory=list)
    """Kubernetes-convention conditions."""
