"""The frozen scenario list as a ConfigMap: written once at resolution, read on every restart.

The list lives in a child object, not in the campaign status (DESIGN §3): gzip-compressed JSON in
``binaryData`` keeps 10,000 entries far below the 1 MiB ConfigMap limit, and ``immutable: true``
makes the "frozen" literal. The batch size is frozen with it, because it decides which batch
each scenario belongs to.
"""

from __future__ import annotations

import base64
import dataclasses
import gzip
import json
from collections.abc import Mapping
from typing import Any

from simtest_operator.errors import SourceError
from simtest_operator.operator import names
from simtest_operator.operator.batches import Layout
from simtest_operator.scenarios import FrozenList

DATA_KEY = "scenarios.json.gz"
MAX_BYTES = 900 * 1024
"""Headroom below the 1 MiB object limit for metadata."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class StoredList:
    """What the ConfigMap holds."""

    frozen: FrozenList
    batch_size: int
    layout: Layout = dataclasses.field(init=False, repr=False, compare=False)
    """How the list is sliced into batches (indexed once here, not on every step)."""

    def __post_init__(self) -> None:
        layout = Layout(ids=tuple(s.id for s in self.frozen.scenarios), batch_size=self.batch_size)
        object.__setattr__(self, "layout", layout)


def config_map(
    stored: StoredList, *, namespace: str, campaign: str, owner: Mapping[str, Any]
) -> dict[str, Any]:
    """The ConfigMap body."""
    text = json.dumps(
        {**stored.frozen.to_json(), "batchSize": stored.batch_size},
        sort_keys=True,
        separators=(",", ":"),
    )
    packed = gzip.compress(text.encode("utf-8"), mtime=0)
    if len(packed) > MAX_BYTES:
        raise SourceError(
            f"the frozen list of {len(stored.frozen.scenarios)} scenarios is {len(packed)} bytes "
            f"compressed, over the {MAX_BYTES}-byte ConfigMap budget; split the campaign"
        )
    return {
        "apiVersion": "v1",
        "kind": "ConfigMap",
        "metadata": {
            "name": names.scenario_list(campaign),
            "namespace": namespace,
            "labels": names.campaign_labels(campaign),
            "ownerReferences": [dict(owner)],
        },
        "immutable": True,
        "data": {
            "count": str(len(stored.frozen.scenarios)),
            "batchSize": str(stored.batch_size),
        },
        "binaryData": {DATA_KEY: base64.b64encode(packed).decode("ascii")},
    }


def read(body: Mapping[str, Any]) -> StoredList:
    """Parse the ConfigMap body written by :func:`config_map`."""
    name = (body.get("metadata") or {}).get("name", "?")
    try:
        packed = base64.b64decode((body.get("binaryData") or {})[DATA_KEY])
        document = json.loads(gzip.decompress(packed).decode("utf-8"))
        batch_size = int(document.pop("batchSize"))
    except (KeyError, ValueError, OSError, TypeError) as exc:
        raise SourceError(f"ConfigMap {name} is not a frozen scenario list: {exc}") from exc
    return StoredList(
        frozen=FrozenList.from_json(document, where=f"ConfigMap {name}"), batch_size=batch_size
    )
