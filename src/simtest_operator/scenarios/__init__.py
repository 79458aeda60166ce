"""Scenario sources, selection, the frozen (pinned) list and batching: the campaign's domain.

Public API::

    resolved = resolving.resolve(source_spec, FetchContext(base_dir=..., cache_dir=...))
    kept = selecting.by_globs(resolved.files, include=..., exclude=...)
    selecting.matches(selector, header_properties)
    FrozenList(campaign=..., scenarios=(PinnedScenario(id=..., source=..., sha256=...), ...))
    Locator(ctx).locate(pinned)            # the local file, sha256 verified
    needs(uris, selection.sources)         # ConfigMaps and databases a fetcher of uris needs
    batching.plan(frozen.scenarios, batch_size=...)

Reading file headers and expanding parameter distributions belong to the OpenSCENARIO layer above;
``runner.resolving`` composes both into a campaign's frozen list.
"""

from simtest_operator.scenarios.batching import Batch, Dispatcher, ExecutionPolicy, StartPolicy
from simtest_operator.scenarios.locating import Locator, Needs, needs
from simtest_operator.scenarios.mountedconfigmaps import MountedConfigMaps
from simtest_operator.scenarios.pinned import (
    FrozenList,
    PinnedScenario,
    ResolvedSourceInfo,
    sha256_hex,
)
from simtest_operator.scenarios.querying import SecretProvider
from simtest_operator.scenarios.resolving import (
    ConfigMapReader,
    FetchContext,
    ResolvedSource,
    resolve,
)
from simtest_operator.scenarios.specs import (
    ConfigMapSource,
    DatabaseSource,
    GitSource,
    GraphqlSource,
    HttpSource,
    PathSource,
    RestSource,
    SecretRef,
    Selection,
    Selector,
    SourceLimits,
    SourceSpec,
)

__all__ = [
    "Batch",
    "ConfigMapReader",
    "ConfigMapSource",
    "DatabaseSource",
    "Dispatcher",
    "ExecutionPolicy",
    "FetchContext",
    "FrozenList",
    "GitSource",
    "GraphqlSource",
    "HttpSource",
    "Locator",
    "MountedConfigMaps",
    "Needs",
    "PathSource",
    "PinnedScenario",
    "ResolvedSource",
    "ResolvedSourceInfo",
    "RestSource",
    "SecretProvider",
    "SecretRef",
    "Selection",
    "Selector",
    "SourceLimits",
    "SourceSpec",
    "StartPolicy",
    "needs",
    "resolve",
    "sha256_hex",
]
