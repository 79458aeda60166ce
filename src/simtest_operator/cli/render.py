"""``simtest render MANIFEST --scenario ID``: the files one scenario's environment renders to.

Wiring only. The scenario list is resolved exactly as ``simtest run`` resolves it (``runner``),
and the environment request is built by the operator's own pure functions
(``operator.environment_request``), so the output is what the operator would create for that
scenario (first attempt, isolation ``PerScenario`` granularity). Without
``--out`` a summary and the content hash are printed; with it, ``values.yaml``, ``pod.yaml`` and
``helmfile.yaml`` are written. Exit code 2 with a one-line reason on any input problem.
"""

from __future__ import annotations

import dataclasses
import difflib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import NoReturn

import click
import yaml

from simtest_operator import operator as operating
from simtest_operator import render as rendering
from simtest_operator import runner
from simtest_operator.api import converting, v1alpha1
from simtest_operator.cli.run import env_secrets
from simtest_operator.errors import ScenarioError, SimtestError
from simtest_operator.scenarios.pinned import PinnedScenario
from simtest_operator.scenarios.resolving import FetchContext
from simtest_operator.settings import Settings

CLOSE_MATCHES = 3


@click.command("render")
@click.argument("manifest", type=click.Path(path_type=Path, dir_okay=False))
@click.option("--scenario", "scenario_id", required=True, help="Scenario id (of the frozen list).")
@click.option(
    "--out",
    type=click.Path(path_type=Path, file_okay=False),
    help="Write values.yaml, pod.yaml and helmfile.yaml here (default: print a summary).",
)
@click.option(
    "--templates",
    type=click.Path(path_type=Path, file_okay=False),
    help="Environment templates root (default: ./helm-templates or $SIMTEST_OPERATOR_TEMPLATES).",
)
@click.option(
    "--charts-dir",
    help=f"Charts root the helmfile refers to (default: the image's {rendering.CHARTS_DIR}).",
)
@click.option("--namespace", help="Namespace (default: the manifest's, else 'default').")
def render(
    manifest: Path,
    scenario_id: str,
    out: Path | None,
    templates: Path | None,
    charts_dir: str | None,
    namespace: str | None,
) -> None:
    """Render the environment of one scenario of a TestCampaign MANIFEST, as the operator would.

    Prints the environment's name, releases and content hash; --out writes the files.
    Same inputs, byte-identical files.
    """
    settings = Settings.from_env(operator_flags={"inputs.templates_dir": templates})
    templates_dir = settings.operator.inputs.templates_dir
    try:
        _, campaign = runner.read_manifest(manifest)
        frozen = _frozen_list(manifest, campaign, settings)
        position = _position(frozen, scenario_id, campaign.name)
        request = operating.environment_request(
            campaign,
            frozen,
            position,
            namespace=namespace or campaign.namespace or "default",
            templates=templates_dir,
        )
        if charts_dir is not None:
            request = dataclasses.replace(request, charts_dir=charts_dir)
        rendered = rendering.render_environment(request, rendering.TemplateLibrary(templates_dir))
    except SimtestError as exc:
        _fail(str(exc))
    files = rendered.files()
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        for name, text in sorted(files.items()):
            (out / name).write_text(text, encoding="utf-8")
    click.echo(_summary(request, rendered, out, sorted(files)), nl=False)


def _frozen_list(
    manifest: Path, campaign: v1alpha1.Manifest[v1alpha1.TestCampaignSpec], settings: Settings
) -> Sequence[PinnedScenario]:
    """The campaign's frozen list, resolved like ``simtest run`` resolves it."""
    spec = campaign.spec
    fetch = FetchContext(
        base_dir=manifest.absolute().parent,
        cache_dir=settings.cache.sources,
        secrets=env_secrets(settings.secrets),
    )
    frozen = runner.freeze(
        converting.selection(spec.scenarios),
        fetch,
        campaign=campaign.name,
        seed=spec.environment.simulator.seed,
    )
    return frozen.scenarios


def _position(frozen: Sequence[PinnedScenario], scenario_id: str, campaign: str) -> int:
    ids = [s.id for s in frozen]
    if scenario_id in ids:
        return ids.index(scenario_id)
    close = difflib.get_close_matches(scenario_id, ids, n=CLOSE_MATCHES, cutoff=0.4)
    hint = (
        f"close matches: {', '.join(close)}"
        if close
        else f"first ids: {', '.join(ids[:CLOSE_MATCHES]) or 'none'}"
    )
    raise ScenarioError(
        f"unknown scenario {scenario_id!r}: campaign {campaign} selects {len(ids)} "
        f"scenario(s); {hint}"
    )


def _summary(
    request: rendering.EnvironmentRequest,
    rendered: rendering.RenderedEnvironment,
    out: Path | None,
    names: Sequence[str],
) -> str:
    lines = [
        f"environment  {request.namespace}/{request.name} (template {request.template})",
        f"scenario     {request.scenarios[0].id}",
        f"pod          {rendered.pod['metadata']['name']} image "
        f"{rendered.pod['spec']['containers'][0]['image']}",
    ]
    for release in _releases(rendered.helmfile):
        lines.append(f"release      {release}")
    if out is not None:
        lines.append(f"wrote        {', '.join(str(out / n) for n in names)}")
    lines.append(f"hash         sha256:{rendered.content_hash}")
    return "\n".join(lines) + "\n"


def _releases(helmfile: str | None) -> list[str]:
    if helmfile is None:
        return []
    loaded = yaml.safe_load(helmfile)
    releases = loaded.get("releases", []) if isinstance(loaded, Mapping) else []
    return [
        f"{r.get('name')} ({str(r.get('chart', '')).rstrip('/').rsplit('/', 1)[-1]})"
        for r in releases
        if isinstance(r, Mapping)
    ]


def _fail(reason: str) -> NoReturn:
    click.echo(f"simtest render: {' '.join(reason.split())}", err=True)
    raise SystemExit(2)
