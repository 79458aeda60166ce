"""The termination message: the compact result a simulator pod leaves in its container status.

The runner writes it to ``/dev/termination-log``; the kubelet copies it into
``status.containerStatuses[].state.terminated.message``, where the operator reads it without any
extra channel. Kubernetes keeps at most 4096 bytes, so the encoder shrinks in steps (drop
versions and ignored elements, keep the result-file artifact only, shorten the reason, keep the
key metrics) until the text fits — the verdict and the scenario id always survive.

One scenario is one JSON object (:meth:`ScenarioOutcome.to_json`); a warm worker (isolation
``Reuse``) writes ``{"results": [...]}``.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from simtest_operator.verdicts import ScenarioOutcome

LIMIT_BYTES = 4096
"""Kubernetes' limit for one container's termination message."""
RESULTS_STORED = "resultsStored"
"""Entry flag, ``false`` when the pod could not store the scenario's row in the results database."""
STOPPED = "stopped"
"""Entry flag, ``true`` when SIGTERM ended the scenario before it finished (or before it started):
a verdict of the environment, not of the scenario."""
KEY_METRICS = ("minTTC", "minTHW", "minDistance", "maxDecel", "collisions", "offRoad")
"""Metrics kept first when a message has to shrink."""


class MessageError(ValueError):
    """The text is not a termination message this codec wrote."""


def encode(outcomes: Sequence[ScenarioOutcome], *, limit: int = LIMIT_BYTES) -> str:
    """The smallest faithful text for ``outcomes`` that fits in ``limit`` UTF-8 bytes."""
    if not outcomes:
        raise ValueError("nothing to encode")
    docs = [o.to_json() for o in outcomes]
    for shrink in _STEPS:
        docs = [shrink(d) for d in docs]
        text = _dumps(docs)
        if len(text.encode("utf-8")) <= limit:
            return text
    # Still too long (hundreds of scenarios in one worker): keep id and verdict only.
    docs = [{"scenarioId": d["scenarioId"][:200], "verdict": d["verdict"]} for d in docs]
    while len(_dumps(docs).encode("utf-8")) > limit and len(docs) > 1:
        docs = docs[:-1]
    return _dumps(docs)


def encode_flagged(
    outcomes: Sequence[ScenarioOutcome],
    flags: Mapping[str, Mapping[str, bool]],
    *,
    limit: int = LIMIT_BYTES,
) -> str:
    """:func:`encode` plus per-entry flags (scenario id -> {flag: value}), within ``limit``."""
    reserve = sum(len(f',"{key}":false') for entry in flags.values() for key in entry)
    text = encode(outcomes, limit=limit - reserve)
    if not flags:
        return text
    data = json.loads(text)
    entries = data["results"] if isinstance(data.get("results"), list) else [data]
    for entry in entries:
        entry.update(flags.get(entry.get("scenarioId"), {}))
    return json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=False)


def flagged(text: str, flag: str, value: bool, *, default_id: str | None = None) -> frozenset[str]:
    """Scenario ids whose entry has ``flag`` set to ``value`` (none for text we did not write)."""
    try:
        data = json.loads(text)
    except ValueError:
        return frozenset()
    entries = data.get("results") if isinstance(data, Mapping) and "results" in data else [data]
    if not isinstance(entries, list):
        return frozenset()
    return frozenset(
        str(entry.get("scenarioId", default_id))
        for entry in entries
        if isinstance(entry, Mapping) and entry.get(flag) is value
    )


def decode(text: str, *, default_id: str | None = None) -> tuple[ScenarioOutcome, ...]:
    """Parse a message; ``default_id`` fills a missing ``scenarioId`` (single-scenario pods)."""
    try:
        data = json.loads(text)
    except ValueError as exc:
        raise MessageError(f"not JSON: {_clip(text)}") from exc
    items = data.get("results") if isinstance(data, Mapping) and "results" in data else [data]
    if not isinstance(items, list) or not items:
        raise MessageError("expected an object or {'results': [...]}")
    outcomes = []
    for item in items:
        if not isinstance(item, Mapping) or "verdict" not in item:
            raise MessageError(f"entry without a verdict: {_clip(text)}")
        if "scenarioId" not in item:
            if default_id is None:
                raise MessageError("entry without a scenarioId")
            item = {**item, "scenarioId": default_id}
        try:
            outcomes.append(ScenarioOutcome.from_json(item))
        except (KeyError, TypeError, ValueError) as exc:
            raise MessageError(f"malformed entry: {exc}") from exc
    return tuple(outcomes)


def _dumps(docs: list[dict[str, Any]]) -> str:
    payload: Any = docs[0] if len(docs) == 1 else {"results": docs}
    return json.dumps(payload, sort_keys=True, separators=(",", ":"), ensure_ascii=False)


def _clip(text: str, n: int = 120) -> str:
    flat = " ".join(text.split())
    return flat if len(flat) <= n else flat[: n - 1] + "…"


def _drop_empty(doc: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in doc.items() if v not in ({}, [], "", None) or k == "verdict"}


def _drop_provenance(doc: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in doc.items() if k not in ("versions", "ignoredElements")}


def _result_artifact_only(doc: dict[str, Any]) -> dict[str, Any]:
    artifacts = doc.get("artifacts") or {}
    kept = {k: v for k, v in artifacts.items() if k == "result"}
    return _drop_empty({**doc, "artifacts": kept})


def _reason(n: int) -> Callable[[dict[str, Any]], dict[str, Any]]:
    def shorten(doc: dict[str, Any]) -> dict[str, Any]:
        reason = str(doc.get("reason", ""))
        return {**doc, "reason": reason if len(reason) <= n else reason[: n - 1] + "…"}

    return shorten


def _key_metrics(doc: dict[str, Any]) -> dict[str, Any]:
    metrics = doc.get("metrics") or {}
    kept = {k: round(float(metrics[k]), 3) for k in KEY_METRICS if k in metrics}
    return _drop_empty({**doc, "metrics": kept})


def _bare(doc: dict[str, Any]) -> dict[str, Any]:
    keep = ("scenarioId", "verdict", "reason", "wallSeconds", "simulatedSeconds", "attempts")
    return {k: doc[k] for k in keep if k in doc}


_STEPS: tuple[Callable[[dict[str, Any]], dict[str, Any]], ...] = (
    _drop_empty,
    _drop_provenance,
    _result_artifact_only,
    _reason(400),
    _key_metrics,
    _reason(120),
    _bare,
    _reason(40),
)
