"""Kubernetes-convention conditions: set a condition, keep its transition time when unchanged."""

from __future__ import annotations

import dataclasses
import datetime
from collections.abc import Iterable, Mapping, Sequence
from typing import Any


def rfc3339(moment: datetime.datetime) -> str:
    """``2024-05-01T12:00:00.123Z`` (UTC, milliseconds)."""
    utc = moment.astimezone(datetime.UTC)
    return utc.strftime("%Y-%m-%dT%H:%M:%S.") + f"{utc.microsecond // 1000:03d}Z"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Desired:
    """A condition as the planner wants it."""

    type: str
    status: bool | None
    """True, False or None (Unknown)."""
    reason: str
    message: str = ""

    @property
    def status_text(self) -> str:
        """``True``, ``False`` or ``Unknown``."""
        return {True: "True", False: "False", None: "Unknown"}[self.status]


def merge(
    current: Sequence[Mapping[str, Any]] | None,
    desired: Iterable[Desired],
    *,
    now: datetime.datetime,
    generation: int | None = None,
) -> list[dict[str, Any]]:
    """The conditions list with ``desired`` applied; a condition whose status did not change keeps
    its ``lastTransitionTime``, others not named stay as they are."""
    existing = {str(c.get("type")): c for c in current or () if isinstance(c, Mapping)}
    out: dict[str, dict[str, Any]] = {k: dict(v) for k, v in existing.items()}
    for want in desired:
        old = existing.get(want.type)
        changed = old is None or old.get("status") != want.status_text
        entry: dict[str, Any] = {
            "type": want.type,
            "status": want.status_text,
            "reason": want.reason,
            "message": want.message,
            "lastTransitionTime": rfc3339(now)
            if changed or old is None
            else old.get("lastTransitionTime", rfc3339(now)),
        }
        if generation is not None:
            entry["observedGeneration"] = generation
        out[want.type] = entry
    return [out[k] for k in sorted(out)]


def get(conditions: Sequence[Mapping[str, Any]] | None, kind: str) -> Mapping[str, Any] | None:
    """The condition of type ``kind``."""
    return next((c for c in conditions or () if c.get("type") == kind), None)
