"""Where artifacts and results go."""

from __future__ import annotations

from typing import Annotated, ClassVar

from pydantic import Field, StringConstraints, model_validator

from simtest_operator.api.v1alpha1.common import ApiModel, DnsLabel, SecretKeyRef, cel

_SEGMENT = r"[A-Za-z0-9_-]+(\.[A-Za-z0-9_-]+)*"
RelativePath = Annotated[
    str, StringConstraints(pattern=rf"^({_SEGMENT}(/{_SEGMENT})*)?$", max_length=1024)
]
"""A relative path without ``..`` or a leading ``/``: it cannot leave its volume or prefix."""


class PvcArtifacts(ApiModel):
    """A PersistentVolumeClaim mounted into every simulator pod."""

    claim_name: DnsLabel
    """Name of the PVC in the campaign's namespace."""
    sub_path: RelativePath = ""
    """Folder inside the volume; the campaign's files go below ``<subPath>/<campaign>/``."""


class S3Artifacts(ApiModel):
    """An S3-compatible bucket."""

    endpoint: Annotated[str, StringConstraints(pattern=r"^https?://.+", max_length=1024)]
    """Endpoint URL."""
    bucket: Annotated[str, StringConstraints(min_length=3, max_length=63)]
    """Bucket name."""
    prefix: RelativePath = ""
    """Key prefix for the campaign's objects."""
    secret_ref: DnsLabel
    """Secret with ``AWS_ACCESS_KEY_ID`` and ``AWS_SECRET_ACCESS_KEY``."""


class ArtifactsSpec(ApiModel):
    """Recordings, logs and result files of each run."""

    cel_rules: ClassVar[tuple[dict[str, str], ...]] = (
        cel("!(has(self.pvc) && has(self.s3))", "set at most one of pvc or s3"),
    )

    pvc: PvcArtifacts | None = None
    """Store on a PersistentVolumeClaim."""
    s3: S3Artifacts | None = None
    """Store in an S3-compatible bucket."""
    keep_recordings: bool = True
    """Keep the MCAP recordings (they are the largest artifacts)."""

    @model_validator(mode="after")
    def _one_store(self) -> ArtifactsSpec:
        if self.pvc is not None and self.s3 is not None:
            raise ValueError("set at most one of pvc or s3")
        return self


class ResultsSpec(ApiModel):
    """The results database that receives every run."""

    database_secret_ref: SecretKeyRef | None = None
    """Secret key holding a PostgreSQL DSN; unset keeps results in status and artifacts only."""
    retention_days: Annotated[int, Field(ge=1, le=3650)] | None = None
    """Delete finished child objects of the campaign after this many days."""
