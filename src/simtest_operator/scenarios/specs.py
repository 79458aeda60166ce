"""Domain values describing where scenarios come from and which of them a campaign selects.

The wire schema (``api.v1alpha1.sources``) is converted into these by ``api.converting``; every
package below the api layer (resolution, selection, freezing) works on them only. Sources are
untrusted, so the limits that bound what a source may make us download, extract or list travel
with the request as a value too.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SecretRef:
    """A key of a Secret; the value is fetched through an injected provider, never stored."""

    name: str
    key: str


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class PathSource:
    """A file or folder on the local disk (or the operator's scenario volume)."""

    path: str
    """As written in the manifest; relative paths are resolved against the manifest's folder."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class GitSource:
    """A git repository at a revision; the commit is resolved once and pinned."""

    url: str
    """Clone URL (https, ssh, git, file) or a local repository path."""
    revision: str = "HEAD"
    """Branch, tag or commit."""
    path: str = ""
    """Folder inside the repository holding the scenarios."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class HttpSource:
    """One .xosc file or a .tar.gz/.tgz/.zip archive served over HTTP(S)."""

    url: str
    sha256: str | None = None
    """Expected digest of the download; a mismatch fails resolution."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class GraphqlSource:
    """A scenario database queried over GraphQL; each result item is ``{id, url | content}``."""

    endpoint: str
    query: str
    variables: Mapping[str, str] = dataclasses.field(default_factory=dict)
    secret: SecretRef | None = None
    """Bearer token for the endpoint."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RestSource:
    """A scenario database answering a GET with JSON: a list of ``{id, url | content}`` items,
    top-level or in the one ``items``/``scenarios``/``results``/``data`` field of an object."""

    url: str
    secret: SecretRef | None = None
    """Bearer token for the endpoint."""


DatabaseSource = GraphqlSource | RestSource
"""A scenario database: queried once to resolve, and again by whoever fetches an inline item."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ConfigMapSource:
    """Scenario files stored as ConfigMap keys; reading them needs a cluster."""

    name: str
    keys: tuple[str, ...] = ()
    """Keys to use; empty means every key ending in ``.xosc``."""


SourceSpec = PathSource | GitSource | HttpSource | GraphqlSource | RestSource | ConfigMapSource
"""Exactly one kind of location."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Selector:
    """Tag and label selection over the ``simtest:*`` properties of a file's FileHeader."""

    tags: tuple[str, ...] = ()
    """Every one must appear in the comma-separated ``simtest:tags`` property."""
    labels: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """Properties that must have exactly these values; a key ``k`` matches the property ``k`` or
    ``simtest:k``."""

    @property
    def empty(self) -> bool:
        """Whether the selector accepts everything."""
        return not self.tags and not self.labels


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Selection:
    """A campaign's scenarios: sources, then include/exclude globs, then the selector."""

    sources: tuple[SourceSpec, ...]
    include: tuple[str, ...] = ("**/*.xosc",)
    exclude: tuple[str, ...] = ()
    selector: Selector = dataclasses.field(default_factory=Selector)
    overrides: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """OpenSCENARIO parameter values applied to every selected scenario."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SourceLimits:
    """Bounds on what an untrusted source may make us download, extract or list."""

    max_download_bytes: int = 256 * 1024 * 1024
    """Largest HTTP body (archive, file, GraphQL or REST response) we read."""
    max_archive_members: int = 20_000
    """Most entries an archive may hold (files, folders and links together)."""
    max_extracted_bytes: int = 1024 * 1024 * 1024
    """Largest total size of the files extracted from one archive (zip bombs stop here)."""
    max_files: int = 100_000
    """Most files one source may list."""
    max_scenario_bytes: int = 20 * 1024 * 1024
    """Largest single scenario file (matches the OpenSCENARIO reader's limit)."""
    network_timeout: float = 60.0
    """Seconds an HTTP request may stall before it fails."""
    git_timeout: float = 600.0
    """Seconds one git command may take."""
