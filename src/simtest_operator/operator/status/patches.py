"""Status merge patches: the fields that changed, and which changes may wait.

Patches are computed against the observed wire form of a status (the views keep it as
``status_wire``), not against its typed reading: a field is rewritten only when its stored text
differs, so a timestamp written once is never rewritten in another spelling.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from simtest_operator.operator.status import counting


def changed_fields(desired: Mapping[str, Any], current: Mapping[str, Any]) -> dict[str, Any]:
    """The top-level fields of ``desired`` that differ from ``current`` (a merge patch)."""
    return {k: v for k, v in desired.items() if current.get(k) != v}


def only_progress(patch: Mapping[str, Any]) -> bool:
    """A patch that changes counters/progress/throughput only (may be deferred and coalesced)."""
    return set(patch) <= {*counting.COUNTER_KEYS, "progress", "throughput", "batches", "search"}
