"""The frozen scenario list: what a campaign runs, pinned by content so a rerun is exact.

A campaign's sources are resolved once; afterwards only this list matters. Each entry names the
scenario (stable id), where its file comes from (a source URI, see :mod:`uris`), the sha256 of the
file's bytes and the parameter overrides of the run. ``frozen.json`` in a local output folder and
the operator's scenario-list ConfigMap hold the same document.
"""

from __future__ import annotations

import dataclasses
import hashlib
import re
from collections.abc import Mapping, Sequence
from typing import Any

from simtest_operator.errors import SourceError

FORMAT = "simtest.dev/frozen-list/v1"
"""Format tag of the JSON document, checked on read."""

_SHA256 = re.compile(r"^[0-9a-f]{64}$")


def sha256_hex(data: bytes) -> str:
    """The lower-case hex sha256 of ``data``."""
    return hashlib.sha256(data).hexdigest()


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ProposalPin:
    """Where a search's concrete scenario came from, so the search can be replayed exactly.

    The searcher's proposals are a pure function of its spec and the sequence of asks and tells;
    ``told`` (the outcomes told since the previous proposal, in order) and ``basis`` pin that
    sequence, so a resumed run or a restarted operator rebuilds the same searcher."""

    index: int
    """0, 1, 2, ... in the order asked."""
    basis: int
    """Outcomes the searcher had been told when it proposed this."""
    told: tuple[int, ...] = ()
    """Indices of the proposals told since the previous proposal was asked, in the order told."""
    values: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """Parameter name -> value as text (``repr`` of a float, a choice as is)."""

    def to_json(self) -> dict[str, Any]:
        """Wire form, identical to the API's ``SearchProposalRecord``."""
        wire: dict[str, Any] = {
            "index": self.index,
            "basis": self.basis,
            "values": dict(sorted(self.values.items())),
        }
        if self.told:
            wire["told"] = list(self.told)
        return wire

    @classmethod
    def from_json(cls, data: Any, *, where: str) -> ProposalPin:
        """Inverse of :meth:`to_json`; raises SourceError naming ``where`` when malformed."""
        try:
            values = data.get("values") or {}
            return cls(
                index=int(data["index"]),
                basis=int(data["basis"]),
                told=tuple(int(i) for i in data.get("told") or ()),
                values={str(k): str(v) for k, v in values.items()},
            )
        except (AttributeError, KeyError, TypeError, ValueError) as exc:
            raise SourceError(f"{where}: malformed search proposal: {exc}") from exc


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class PinnedScenario:
    """One run of the frozen list."""

    id: str
    """Stable id: path inside its source, plus ``#<suffix>`` for an expanded distribution."""
    source: str
    """Source URI of the scenario file (see :mod:`simtest_operator.scenarios.uris`)."""
    sha256: str
    """Digest of the scenario file; a changed file is a different scenario."""
    overrides: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """OpenSCENARIO parameter values of this run (campaign overrides, then distribution values)."""
    proposal: ProposalPin | None = None
    """The search proposal this run is (``spec.search``); None for a listed scenario."""

    def to_json(self) -> dict[str, Any]:
        """Wire form, identical to the API's ``FrozenScenario``."""
        wire: dict[str, Any] = {
            "id": self.id,
            "source": self.source,
            "sha256": self.sha256,
            "overrides": dict(sorted(self.overrides.items())),
        }
        if self.proposal is not None:
            wire["proposal"] = self.proposal.to_json()
        return wire

    @classmethod
    def from_json(cls, data: Any, *, where: str = "frozen list") -> PinnedScenario:
        """Inverse of :meth:`to_json`; raises SourceError naming ``where`` on a malformed entry."""
        if not isinstance(data, Mapping):
            raise SourceError(f"{where}: an entry must be an object")
        ident, source, digest = data.get("id"), data.get("source"), data.get("sha256")
        overrides = data.get("overrides", {})
        if not isinstance(ident, str) or not ident:
            raise SourceError(f"{where}: entry without a string 'id'")
        if not isinstance(source, str) or not source:
            raise SourceError(f"{where}: entry {ident!r} has no string 'source'")
        if not isinstance(digest, str) or not _SHA256.match(digest):
            raise SourceError(f"{where}: entry {ident!r} has no 64-hex-digit 'sha256'")
        if not isinstance(overrides, Mapping) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in overrides.items()
        ):
            raise SourceError(f"{where}: entry {ident!r} has 'overrides' that are not strings")
        proposal = data.get("proposal")
        return cls(
            id=ident,
            source=source,
            sha256=digest,
            overrides=dict(overrides),
            proposal=None if proposal is None else ProposalPin.from_json(proposal, where=where),
        )


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ResolvedSourceInfo:
    """What one campaign source resolved to, recorded next to the list for provenance."""

    kind: str
    """path, git, http, graphql or configMap."""
    location: str
    """URL or path as given."""
    revision: str = ""
    """Resolved git commit, or the sha256 of an HTTP download."""
    files: int = 0
    """Files the source listed before selection."""

    def to_json(self) -> dict[str, Any]:
        """JSON form."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class FrozenList:
    """The whole list plus provenance."""

    campaign: str
    scenarios: tuple[PinnedScenario, ...]
    sources: tuple[ResolvedSourceInfo, ...] = ()
    notes: tuple[str, ...] = ()
    """What resolution skipped and why (catalog files, unreadable headers, ...)."""

    def __post_init__(self) -> None:
        seen: set[str] = set()
        for entry in self.scenarios:
            if entry.id in seen:
                raise SourceError(f"frozen list: scenario id {entry.id!r} appears twice")
            seen.add(entry.id)

    def subset(self, ids: Sequence[str] | set[str]) -> FrozenList:
        """The entries whose id is in ``ids``, in list order."""
        wanted = set(ids)
        return dataclasses.replace(
            self, scenarios=tuple(s for s in self.scenarios if s.id in wanted)
        )

    def to_json(self) -> dict[str, Any]:
        """JSON document (``frozen.json``)."""
        return {
            "format": FORMAT,
            "campaign": self.campaign,
            "sources": [source.to_json() for source in self.sources],
            "notes": list(self.notes),
            "scenarios": [entry.to_json() for entry in self.scenarios],
        }

    @classmethod
    def from_json(cls, data: Any, *, where: str = "frozen list") -> FrozenList:
        """Read a document written by :meth:`to_json`; raises SourceError when malformed."""
        if not isinstance(data, Mapping) or data.get("format") != FORMAT:
            raise SourceError(f"{where}: not a frozen scenario list (format {FORMAT!r} expected)")
        entries = data.get("scenarios")
        if not isinstance(entries, list):
            raise SourceError(f"{where}: 'scenarios' must be a list")
        sources = []
        for raw in data.get("sources", []):
            if isinstance(raw, Mapping):
                sources.append(
                    ResolvedSourceInfo(
                        kind=str(raw.get("kind", "")),
                        location=str(raw.get("location", "")),
                        revision=str(raw.get("revision", "")),
                        files=int(raw.get("files", 0)),
                    )
                )
        return cls(
            campaign=str(data.get("campaign", "")),
            scenarios=tuple(PinnedScenario.from_json(e, where=where) for e in entries),
            sources=tuple(sources),
            notes=tuple(str(n) for n in data.get("notes", [])),
        )
