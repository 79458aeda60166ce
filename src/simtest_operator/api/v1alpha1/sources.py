"""Where a campaign's scenarios come from, and which of them it selects.

A source entry names exactly one kind of location. The rule is stated twice on purpose: as a CEL
rule in the CRD (so ``kubectl apply`` rejects a bad manifest) and as a pydantic validator (so
``simtest run`` rejects it identically without a cluster).
"""

from __future__ import annotations

from typing import Annotated, ClassVar

from pydantic import Field, StringConstraints, model_validator

from simtest_operator.api.v1alpha1.common import ApiModel, DnsLabel, SecretKeyRef, cel

SOURCE_KINDS = ("path", "configMap", "git", "http", "graphql", "rest")

NonEmpty = Annotated[str, StringConstraints(min_length=1, max_length=4096)]
MAX_PATTERNS = 256
"""Glob patterns per include/exclude list: every file of every source is matched against each
one, so an unbounded list is unbounded work (and API server storage)."""
Url = Annotated[str, StringConstraints(pattern=r"^(https?|file|ssh|git)://.+", max_length=4096)]
HttpUrl = Annotated[str, StringConstraints(pattern=r"^https?://[^#]+$", max_length=4096)]


class ConfigMapSource(ApiModel):
    """Scenario files stored as keys of a ConfigMap in the campaign's namespace."""

    name: DnsLabel
    """Name of the ConfigMap."""
    keys: list[NonEmpty] = Field(default_factory=list)
    """Keys to use; empty means every key ending in ``.xosc``."""


class GitSource(ApiModel):
    """A git repository pinned to a revision; the commit is resolved once and frozen."""

    url: NonEmpty
    """Clone URL (https, ssh, file) or a local repository path."""
    revision: NonEmpty = "HEAD"
    """Branch, tag or commit to check out."""
    path: Annotated[str, StringConstraints(max_length=4096)] = ""
    """Folder inside the repository that holds the scenarios."""


class HttpSource(ApiModel):
    """An archive (.tar.gz, .tgz, .zip) or a single .xosc file served over HTTP(S)."""

    url: Url
    """Where to download from."""
    sha256: Annotated[str, StringConstraints(pattern=r"^[0-9a-f]{64}$")] | None = None
    """Expected digest of the download; a mismatch fails resolution."""


class GraphqlSource(ApiModel):
    """A scenario database queried over GraphQL; each result names a scenario to download."""

    endpoint: Url
    """GraphQL endpoint URL."""
    query: NonEmpty
    """Query returning a list of scenarios (fields ``id`` and ``url`` or ``content``)."""
    variables: dict[str, str] = Field(default_factory=dict)
    """Variables passed with the query."""
    secret_ref: SecretKeyRef | None = None
    """Secret key holding a bearer token for the endpoint."""


class RestSource(ApiModel):
    """A scenario database answering a GET with JSON: a list of scenarios, or an object with one
    list field (``items``, ``scenarios``, ``results`` or ``data``); each item has ``id`` and
    ``url`` (downloaded) or ``content`` (the .xosc inline)."""

    url: HttpUrl
    """The URL to GET, query string included (no fragment)."""
    secret_ref: SecretKeyRef | None = None
    """Secret key holding a bearer token for the URL."""


class ScenarioSource(ApiModel):
    """One location of scenario files. Exactly one of the fields must be set."""

    cel_rules: ClassVar[tuple[dict[str, str], ...]] = (
        cel(
            " + ".join(f"(has(self.{kind}) ? 1 : 0)" for kind in SOURCE_KINDS) + " == 1",
            "exactly one of path, configMap, git, http, graphql or rest must be set",
        ),
    )

    path: NonEmpty | None = None
    """A file or folder on the operator's scenario volume (or the local disk for ``simtest run``),
    relative paths resolved against the manifest's folder."""
    config_map: ConfigMapSource | None = None
    """Scenario files stored in a ConfigMap."""
    git: GitSource | None = None
    """A git repository at a revision."""
    http: HttpSource | None = None
    """An archive or file downloaded over HTTP(S)."""
    graphql: GraphqlSource | None = None
    """A scenario database queried with GraphQL."""
    rest: RestSource | None = None
    """A scenario database read with a GET of JSON (REST)."""

    @model_validator(mode="after")
    def _exactly_one_kind(self) -> ScenarioSource:
        chosen = [kind for kind in SOURCE_KINDS if getattr(self, _snake(kind)) is not None]
        if len(chosen) != 1:
            found = ", ".join(chosen) if chosen else "none"
            raise ValueError(
                "exactly one of path, configMap, git, http, graphql or rest must be set "
                f"(found: {found})"
            )
        return self

    @property
    def kind(self) -> str:
        """The wire name of the one field that is set."""
        return next(kind for kind in SOURCE_KINDS if getattr(self, _snake(kind)) is not None)


class ScenarioSelector(ApiModel):
    """Selects scenarios by the tags and labels in their file headers."""

    match_tags: list[Annotated[str, StringConstraints(min_length=1, max_length=63)]] = Field(
        default_factory=list, max_length=64
    )
    """Every one of these tags must be present (``simtest:tags`` header property)."""
    match_labels: dict[str, str] = Field(default_factory=dict)
    """Header properties that must have exactly these values, e.g. ``category: cut-in``."""


class ScenarioSelection(ApiModel):
    """The scenarios of a campaign: sources, then include/exclude globs, then the selector."""

    sources: Annotated[list[ScenarioSource], Field(min_length=1, max_length=64)]
    """Where to find scenario files; resolved once, in order, when the campaign starts."""
    include: list[NonEmpty] = Field(default_factory=lambda: ["**/*.xosc"], max_length=MAX_PATTERNS)
    """Glob patterns (relative to each source root) a file must match (at most 256)."""
    exclude: list[NonEmpty] = Field(default_factory=list, max_length=MAX_PATTERNS)
    """Glob patterns that remove files the include patterns matched (at most 256)."""
    selector: ScenarioSelector | None = None
    """Optional tag/label selector applied after the globs."""
    overrides: dict[str, str] = Field(default_factory=dict)
    """OpenSCENARIO parameter values applied to every selected scenario."""


def _snake(camel: str) -> str:
    return "".join(f"_{c.lower()}" if c.isupper() else c for c in camel)
