"""Resolving a campaign once: freeze its scenario list into ConfigMap children.

The frozen list is computed by :func:`simtest_operator.runner.resolving.freeze` — the same code
``simtest run`` uses, so a campaign selects the same scenarios on a laptop and in a cluster —
with ConfigMap and Secret readers that go through the operator's API client. Before anything is
created, one environment is rendered as a pre-flight check: a broken template or values override
fails the campaign with a clear reason instead of failing every scenario.

Resolution is idempotent: if the ConfigMap exists (a restart, a second operator) it is read,
never recomputed, so a rerun after a restart is exact even when the sources moved on.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import dataclasses
from collections.abc import Callable, Mapping
from pathlib import Path

from simtest_operator.api import converting
from simtest_operator.api.v1alpha1.search import SearchSpec
from simtest_operator.errors import ClusterError, RenderError, ScenarioError
from simtest_operator.operator import bodies, names, observed, requests, scenariolists
from simtest_operator.operator.actions import Kind
from simtest_operator.operator.client import AlreadyExistsError, Client, NotFoundError
from simtest_operator.operator.scenariolists import StoredList
from simtest_operator.render import EnvironmentRequest, RenderedEnvironment, ScenarioRef
from simtest_operator.runner import resolving as freezing
from simtest_operator.scenarios import FetchContext, Locator, PinnedScenario, SecretRef
from simtest_operator.search import SearchSpace
from simtest_operator.settings import OperatorSettings


class ResolutionError(ScenarioError):
    """The campaign's scenarios cannot be resolved or its environment cannot be rendered."""


async def load(client: Client, campaign: observed.CampaignView) -> StoredList | None:
    """The stored frozen list, or None when the campaign has not been resolved yet."""
    try:
        body = await client.get(
            Kind.CONFIG_MAP, campaign.namespace, names.scenario_list(campaign.name)
        )
    except NotFoundError:
        return None
    chunks = [
        await client.get(Kind.CONFIG_MAP, campaign.namespace, name)
        for name in scenariolists.chunk_names(body)
    ]  # the head exists only once every chunk does (created last)
    return scenariolists.read(body, chunks)


def fetch_context(
    client: Client, campaign: observed.CampaignView, *, config: OperatorSettings
) -> FetchContext:
    """What fetching the campaign's sources may use: the operator's folders, and ConfigMaps and
    Secrets read through its API client (from a worker thread: call this in the event loop)."""
    loop = asyncio.get_running_loop()

    def blocking(coro_factory: Callable[[], object]) -> object:
        return asyncio.run_coroutine_threadsafe(coro_factory(), loop).result()  # type: ignore[arg-type]

    def config_maps(name: str) -> Mapping[str, bytes]:
        try:
            body = blocking(lambda: client.get(Kind.CONFIG_MAP, campaign.namespace, name))
        except NotFoundError as exc:
            raise ResolutionError(f"ConfigMap {name!r} not found in {campaign.namespace}") from exc
        assert isinstance(body, dict)
        data = {k: str(v).encode() for k, v in (body.get("data") or {}).items()}
        data.update({k: base64.b64decode(v) for k, v in (body.get("binaryData") or {}).items()})
        return data

    def secrets(ref: SecretRef) -> str:
        try:
            body = blocking(lambda: client.get("secrets", campaign.namespace, ref.name))
        except NotFoundError as exc:
            raise ResolutionError(f"Secret {ref.name!r} not found in {campaign.namespace}") from exc
        assert isinstance(body, dict)
        raw = (body.get("data") or {}).get(ref.key)
        if raw is None:
            raise ResolutionError(f"Secret {ref.name!r} has no key {ref.key!r}")
        return base64.b64decode(raw).decode("utf-8").strip()

    return FetchContext(
        base_dir=config.inputs.sources_dir.absolute(),
        cache_dir=config.inputs.cache_dir / "sources",
        config_maps=config_maps,
        secrets=secrets,
    )


async def locate(
    client: Client,
    campaign: observed.CampaignView,
    pinned: PinnedScenario,
    *,
    config: OperatorSettings,
) -> Path:
    """The operator's local copy of a pinned scenario (a search's logical scenario), fetched
    and verified like a pod would."""
    context = fetch_context(client, campaign, config=config)
    return await asyncio.to_thread(Locator(context).locate, pinned)


async def search_space(
    client: Client,
    campaign: observed.CampaignView,
    base: PinnedScenario,
    *,
    config: OperatorSettings,
) -> tuple[SearchSpace, PinnedScenario]:
    """The space of the campaign's search over its pinned logical scenario ``base``, and the
    pin its proposals run (for a distribution: the scenario file it names)."""
    assert campaign.spec is not None and campaign.spec.search is not None
    path = await locate(client, campaign, base, config=config)
    return await asyncio.to_thread(_search_space, campaign.spec.search, base, path)


def _search_space(
    spec: SearchSpec, base: PinnedScenario, path: Path
) -> tuple[SearchSpace, PinnedScenario]:
    space = SearchSpace.from_spec(spec, path)
    return space, freezing.search_target(base, path, space)


async def resolve(
    client: Client,
    campaign: observed.CampaignView,
    *,
    config: OperatorSettings,
    render: Callable[[EnvironmentRequest], RenderedEnvironment],
) -> StoredList:
    """Freeze the campaign's list, check it renders, and store it (or read what is stored).

    A search (``spec.search``) freezes only its logical scenario; the space (and for a
    distribution, the pin of the scenario file it names) is built once here, so a parameter the
    file does not declare fails the campaign before anything runs."""
    assert campaign.spec is not None
    spec = campaign.spec
    context = fetch_context(client, campaign, config=config)
    if spec.search is None:
        frozen = await asyncio.to_thread(
            freezing.freeze,
            converting.selection(spec.scenarios),
            context,
            campaign=campaign.name,
            seed=spec.environment.simulator.seed,
        )
    else:
        frozen = await asyncio.to_thread(
            freezing.freeze_search,
            converting.selection(spec.scenarios),
            context,
            campaign=campaign.name,
            scenario=spec.search.scenario,
            seed=spec.environment.simulator.seed,
        )
        path = await asyncio.to_thread(Locator(context).locate, frozen.scenarios[0])
        await asyncio.to_thread(_search_space, spec.search, frozen.scenarios[0], path)
    stored = StoredList(frozen=frozen, batch_size=spec.execution.batch_size)
    if frozen.scenarios:
        _preflight(campaign, stored, config=config, render=render)
    owner = bodies.owner("TestCampaign", campaign.name, campaign.uid)
    *chunks, head = scenariolists.config_maps(
        stored, namespace=campaign.namespace, campaign=campaign.name, owner=owner
    )
    account = bodies.service_account(
        campaign=campaign.name, namespace=campaign.namespace, campaign_uid=campaign.uid
    )
    with contextlib.suppress(AlreadyExistsError):
        await client.create(Kind.SERVICE_ACCOUNT, campaign.namespace, account)
    for chunk in chunks:  # named by content: one that exists holds exactly this
        with contextlib.suppress(AlreadyExistsError):
            await client.create(Kind.CONFIG_MAP, campaign.namespace, chunk)
    try:
        await client.create(Kind.CONFIG_MAP, campaign.namespace, head)
    except AlreadyExistsError:
        existing = await load(client, campaign)
        if existing is None:
            raise ClusterError("the scenario-list ConfigMap vanished while being created") from None
        return existing
    return stored


def _preflight(
    campaign: observed.CampaignView,
    stored: StoredList,
    *,
    config: OperatorSettings,
    render: Callable[[EnvironmentRequest], RenderedEnvironment],
) -> None:
    assert campaign.spec is not None
    first = stored.frozen.scenarios[0]
    name = names.environment(campaign.name, 0, 0, 1)
    probe = observed.EnvironmentView(
        name=name,
        namespace=campaign.namespace,
        uid="00000000-0000-0000-0000-000000000000",
        resource_version="",
        campaign=campaign.name,
        batch=names.batch(campaign.name, 0),
        attempt=1,
        scenarios=(
            ScenarioRef(
                id=first.id, source=first.source, sha256=first.sha256, overrides=first.overrides
            ),
        ),
    )
    request = requests.environment_request(campaign.spec, probe, config=config)
    try:
        render(dataclasses.replace(request))
    except RenderError as exc:
        raise ResolutionError(f"environment template {request.template!r}: {exc}") from exc
