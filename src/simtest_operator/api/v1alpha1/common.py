"""Building blocks shared by the three kinds: the model base, conditions, quantities, references.

Every model forbids unknown fields (a typo in a manifest is an error, not a silently ignored key),
uses camelCase on the wire and takes its field descriptions from the attribute docstrings, which
the CRD generator copies into the OpenAPI schema.
"""

from __future__ import annotations

import datetime
import enum
import re
from typing import Annotated, Any, ClassVar

from pydantic import BaseModel, ConfigDict, Field, StringConstraints
from pydantic.alias_generators import to_camel

GROUP = "simtest.dev"
VERSION = "v1alpha1"
API_VERSION = f"{GROUP}/{VERSION}"

DNS1123_LABEL = r"^[a-z0-9]([-a-z0-9]*[a-z0-9])?$"
QUANTITY = r"^[0-9]+(\.[0-9]+)?(m|k|M|G|T|P|E|Ki|Mi|Gi|Ti|Pi|Ei)?$"
CONDITION_REASON = r"^[A-Za-z]([A-Za-z0-9_,:]*[A-Za-z0-9_])?$"

Quantity = Annotated[str, StringConstraints(pattern=QUANTITY, max_length=32)]
"""A Kubernetes resource quantity such as ``500m``, ``2``, ``4Gi``."""
DnsLabel = Annotated[str, StringConstraints(pattern=DNS1123_LABEL, max_length=63)]
"""An RFC 1123 label: lower-case alphanumerics and '-', at most 63 characters."""

CEL_KEY = "x-kubernetes-validations"
PRESERVE_KEY = "x-kubernetes-preserve-unknown-fields"


def cel(rule: str, message: str, *, field_path: str | None = None) -> dict[str, str]:
    """One CEL rule for ``x-kubernetes-validations``; pydantic validators mirror it locally."""
    entry = {"rule": rule, "message": message}
    if field_path is not None:
        entry["fieldPath"] = field_path
    return entry


def is_quantity(value: str) -> bool:
    """Whether ``value`` is a resource quantity this API accepts."""
    return re.fullmatch(QUANTITY, value) is not None


class ApiModel(BaseModel):
    """Base of every wire model: camelCase, strict about unknown fields, immutable.

    Validators are built on a model's first use (``defer_build``), not when its module is
    imported: a process validates a few of these models (the simulator pod three), and building
    all of them cost about 0.1 s of every start-up.
    """

    model_config = ConfigDict(
        alias_generator=to_camel,
        populate_by_name=True,
        extra="forbid",
        frozen=True,
        use_attribute_docstrings=True,
        validate_default=False,
        defer_build=True,
    )

    cel_rules: ClassVar[tuple[dict[str, str], ...]] = ()
    """CEL rules the CRD generator attaches to this object's schema."""

    def to_wire(self) -> dict[str, Any]:
        """The JSON-compatible dict as it appears in a manifest (camelCase, no unset fields)."""
        return self.model_dump(mode="json", by_alias=True, exclude_none=True)


class ConditionStatus(enum.StrEnum):
    """Kubernetes condition status values."""

    TRUE = "True"
    FALSE = "False"
    UNKNOWN = "Unknown"


class Condition(ApiModel):
    """A Kubernetes-convention condition (type, status, reason, message, times)."""

    type: Annotated[str, StringConstraints(max_length=316)]
    """CamelCase condition type, e.g. ``Resolved``, ``Running``, ``Complete``, ``Degraded``."""
    status: ConditionStatus
    """Whether the condition holds: True, False or Unknown."""
    reason: Annotated[str, StringConstraints(pattern=CONDITION_REASON, max_length=1024)]
    """CamelCase machine-readable reason for the last transition."""
    message: Annotated[str, StringConstraints(max_length=32768)] = ""
    """Human-readable details about the last transition."""
    last_transition_time: datetime.datetime
    """When the status last changed."""
    observed_generation: Annotated[int, Field(ge=0)] | None = None
    """The ``metadata.generation`` this condition was computed from."""


class SecretKeyRef(ApiModel):
    """A key of a Secret in the campaign's namespace; secret values never enter specs or logs."""

    name: DnsLabel
    """Name of the Secret."""
    key: Annotated[str, StringConstraints(min_length=1, max_length=253)]
    """Key within the Secret's data."""


class TolerationOperator(enum.StrEnum):
    """How a toleration matches a taint's value."""

    EXISTS = "Exists"
    EQUAL = "Equal"


class TaintEffect(enum.StrEnum):
    """Taint effects a toleration may name."""

    NO_SCHEDULE = "NoSchedule"
    PREFER_NO_SCHEDULE = "PreferNoSchedule"
    NO_EXECUTE = "NoExecute"


class Toleration(ApiModel):
    """A pod toleration, as in core/v1, for nodes reserved for simulators (e.g. GPU nodes)."""

    key: Annotated[str, StringConstraints(max_length=316)] | None = None
    """Taint key the toleration applies to; empty with operator Exists matches every taint."""
    operator: TolerationOperator = TolerationOperator.EQUAL
    """Exists or Equal."""
    value: Annotated[str, StringConstraints(max_length=63)] | None = None
    """Taint value to match when the operator is Equal."""
    effect: TaintEffect | None = None
    """Taint effect to match; unset matches all effects."""
    toleration_seconds: int | None = None
    """For NoExecute: how long the pod stays bound after the taint appears."""
