"""The frozen scenario list as ConfigMaps: written once at resolution, read on every restart.

The list lives in child objects, not in the campaign status (DESIGN §3): gzip-compressed JSON in
``binaryData``, ``immutable: true`` to make "frozen" literal. The batch size is frozen with it,
because it decides which batch each scenario belongs to.

One ConfigMap, ``<campaign>-scenarios``, holds some 20,000 entries within :data:`MAX_BYTES`
(headroom below the 1 MiB ConfigMap limit, itself below etcd's 1.5 MiB request limit). A longer
list is cut into chunks of whole entries, each its own ConfigMap named by its content
(:func:`~simtest_operator.operator.names.scenario_list_chunk`); the head ConfigMap lists their
names and is created last, so a head that exists means a complete list.
"""

from __future__ import annotations

import base64
import dataclasses
import gzip
import hashlib
import json
from collections.abc import Mapping, Sequence
from typing import Any

from simtest_operator.errors import SourceError
from simtest_operator.operator import names
from simtest_operator.operator.batches import Layout
from simtest_operator.scenarios import FrozenList

DATA_KEY = "scenarios.json.gz"
CHUNKS_KEY = "chunks"
"""In the head's ``data``: the chunk ConfigMaps' names, comma-separated (absent: no chunks)."""
MAX_BYTES = 900 * 1024
"""Headroom below the 1 MiB object limit for metadata (and base64's third: see :func:`_fits`)."""
MAX_CHUNKS = 64
"""At most this many chunk objects (about a million scenarios): beyond, split the campaign."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class StoredList:
    """What the ConfigMaps hold."""

    frozen: FrozenList
    batch_size: int
    layout: Layout = dataclasses.field(init=False, repr=False, compare=False)
    """How the list is sliced into batches (indexed once here, not on every step)."""

    def __post_init__(self) -> None:
        layout = Layout(ids=tuple(s.id for s in self.frozen.scenarios), batch_size=self.batch_size)
        object.__setattr__(self, "layout", layout)


def config_maps(
    stored: StoredList, *, namespace: str, campaign: str, owner: Mapping[str, Any]
) -> list[dict[str, Any]]:
    """The ConfigMap bodies, in the order to create them: the chunks, then the head."""
    head_document = {**stored.frozen.to_json(), "batchSize": stored.batch_size}
    entries = head_document.pop("scenarios")
    head_packed, *parts = _cut(entries, head_document)
    chunks: list[dict[str, Any]] = []
    for index, packed in enumerate(parts, start=1):
        name = names.scenario_list_chunk(campaign, index, hashlib.sha256(packed).hexdigest())
        chunks.append(_body(name, namespace, campaign, owner, packed, {"index": str(index)}))
    data = {"count": str(len(entries)), "batchSize": str(stored.batch_size)}
    if chunks:
        data[CHUNKS_KEY] = ",".join(c["metadata"]["name"] for c in chunks)
    head = _body(names.scenario_list(campaign), namespace, campaign, owner, head_packed, data)
    return [*chunks, head]


def config_map(
    stored: StoredList, *, namespace: str, campaign: str, owner: Mapping[str, Any]
) -> dict[str, Any]:
    """The head ConfigMap (the whole list while it fits in one)."""
    return config_maps(stored, namespace=namespace, campaign=campaign, owner=owner)[-1]


def chunk_names(head: Mapping[str, Any]) -> tuple[str, ...]:
    """The chunk ConfigMaps a head names, in order."""
    listed = str((head.get("data") or {}).get(CHUNKS_KEY) or "")
    return tuple(n for n in listed.split(",") if n)


def read(body: Mapping[str, Any], chunks: Sequence[Mapping[str, Any]] = ()) -> StoredList:
    """Parse the ConfigMaps written by :func:`config_maps`: the head, then its chunks in the
    order :func:`chunk_names` lists them."""
    name = (body.get("metadata") or {}).get("name", "?")
    try:
        document = _unpack(body)
        batch_size = int(document.pop("batchSize"))
        if len(chunks) != len(chunk_names(body)):
            raise ValueError(f"{len(chunk_names(body))} chunks named, {len(chunks)} given")
        for chunk in chunks:
            document["scenarios"].extend(_unpack(chunk)["scenarios"])
    except (KeyError, ValueError, OSError, TypeError, AttributeError) as exc:
        raise SourceError(f"ConfigMap {name} is not a frozen scenario list: {exc}") from exc
    return StoredList(
        frozen=FrozenList.from_json(document, where=f"ConfigMap {name}"), batch_size=batch_size
    )


def _cut(entries: list[Any], head: Mapping[str, Any]) -> list[bytes]:
    """The entries in as few equal consecutive parts as fit, packed, the first with the
    ``head`` fields (provenance, batch size) beside it. The first guess is the whole list's
    size over the budget; parts of equal entry counts compress alike, so it rarely needs a
    second."""
    whole = _pack({**head, "scenarios": entries})
    if _fits(whole):
        return [whole]
    parts = max(-(-len(whole) * 4 // 3 // MAX_BYTES), 2)
    while parts <= MAX_CHUNKS:
        size = -(-len(entries) // parts)
        cut = [entries[i : i + size] for i in range(0, len(entries), size)]
        packed = [_pack({**head, "scenarios": cut[0]})]
        packed += [_pack({"scenarios": part}) for part in cut[1:]]
        if all(_fits(p) for p in packed):
            return packed
        parts += max(parts // 8, 1)
    raise SourceError(
        f"the frozen list of {len(entries)} scenarios does not fit in {MAX_CHUNKS} ConfigMaps "
        f"of {MAX_BYTES} bytes; split the campaign"
    )


def _fits(packed: bytes) -> bool:
    """Whether a packed part stays within the budget once base64 grows it by a third."""
    return len(packed) * 4 // 3 <= MAX_BYTES


def _pack(document: Mapping[str, Any]) -> bytes:
    text = json.dumps(document, sort_keys=True, separators=(",", ":"))
    return gzip.compress(text.encode("utf-8"), mtime=0)


def _unpack(body: Mapping[str, Any]) -> dict[str, Any]:
    packed = base64.b64decode((body.get("binaryData") or {})[DATA_KEY])
    document = json.loads(gzip.decompress(packed).decode("utf-8"))
    if not isinstance(document, dict) or not isinstance(document.get("scenarios"), list):
        raise ValueError("no scenario entries")
    return document


def _body(
    name: str,
    namespace: str,
    campaign: str,
    owner: Mapping[str, Any],
    packed: bytes,
    data: Mapping[str, str],
) -> dict[str, Any]:
    return {
        "apiVersion": "v1",
        "kind": "ConfigMap",
        "metadata": {
            "name": name,
            "namespace": namespace,
            "labels": names.campaign_labels(campaign),
            "ownerReferences": [dict(owner)],
        },
        "immutable": True,
        "data": dict(data),
        "binaryData": {DATA_KEY: base64.b64encode(packed).decode("ascii")},
    }
