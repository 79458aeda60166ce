"""``simtest submit``: hand a TestCampaign to the cluster, optionally wait and write JUnit.

For CI steps and GitOps checks. The manifest is validated locally first (same rules and field
paths as the API server), then created. With ``--wait`` the command follows the campaign's
``Complete`` condition, prints progress as it changes, collects the per-scenario results from the
campaign's ScenarioBatches and exits like ``simtest run``: 0 all passed, 1 some failed or timed
out, 2 errors, a cancelled campaign (``spec.cancel`` or ``activeDeadlineSeconds``; the reason is
printed on one line), a campaign that could not be submitted, or a wait that timed out.
"""

from __future__ import annotations

import datetime
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import click

from simtest_operator import operator as operating
from simtest_operator.api import manifestfiles
from simtest_operator.api.v1alpha1 import ManifestError, parse_campaign
from simtest_operator.cli import options
from simtest_operator.cli.terminal import printable
from simtest_operator.errors import ClusterError, ScenarioError
from simtest_operator.results import junit, records
from simtest_operator.verdicts import ScenarioOutcome, Verdict

EXIT_PASSED, EXIT_FAILED, EXIT_ERROR = 0, 1, 2
EXIT_BY_PHASE = {"Succeeded": EXIT_PASSED, "Failed": EXIT_FAILED}


def _documents(path: Path) -> list[Any]:
    try:
        return manifestfiles.read(path)[1]
    except ScenarioError as exc:  # exit 2 like an invalid manifest, not click's 1 ("failed")
        click.echo(f"error: {exc}", err=True)
        raise SystemExit(EXIT_ERROR) from None


@click.command("submit")
@click.argument("manifest", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--namespace", "-n", help="Namespace (default: the manifest's, else the context's).")
@options.kubeconfig
@click.option("--context", help="Kubeconfig context.")
@click.option("--wait", is_flag=True, help="Wait until the campaign is Complete; exit by verdict.")
@click.option(
    "--timeout", type=float, default=6 * 3600.0, show_default=True, help="Seconds to wait."
)
@click.option(
    "--junit",
    "junit_file",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Write the results as JUnit XML (implies --wait).",
)
@click.option("--replace", is_flag=True, help="Delete an existing campaign of that name first.")
def submit(
    manifest: Path,
    namespace: str | None,
    kubeconfig: Path | None,
    context: str | None,
    wait: bool,
    timeout: float,
    junit_file: Path | None,
    replace: bool,
) -> None:
    """Create the TestCampaign in MANIFEST on the cluster (and wait for its verdict)."""
    documents = [
        d for d in _documents(manifest) if isinstance(d, dict) and d.get("kind") == "TestCampaign"
    ]
    if len(documents) != 1:
        raise click.ClickException(
            f"{manifest}: expected exactly one TestCampaign, found {len(documents)}"
        )
    document = documents[0]
    try:
        parsed = parse_campaign(document, source=str(manifest))
    except ManifestError as exc:
        for path, message in exc.problems:
            click.echo(f"{manifest}: {path}: {message}", err=True)
        raise SystemExit(EXIT_ERROR) from exc
    try:
        client, default_namespace = operating.connect(kubeconfig, context)
        namespace = namespace or parsed.namespace or default_namespace
        body = {**document, "metadata": {**document["metadata"], "namespace": namespace}}
        body.pop("status", None)
        name = parsed.name
        client.create(namespace, body, replace=replace)
        click.echo(f"testcampaign/{name} created in {namespace}")
        if not (wait or junit_file):
            return
        status = _wait(client, namespace, name, timeout=timeout)
        results = client.results(namespace, name)
    except ClusterError as exc:
        raise click.ClickException(str(exc)) from exc
    if junit_file is not None:
        junit_file.parent.mkdir(parents=True, exist_ok=True)
        junit_file.write_text(_junit(namespace, name, status, results), encoding="utf-8")
        click.echo(f"JUnit: {junit_file}")
    phase = str(status.get("phase", ""))
    for result in sorted(results, key=lambda r: str(r["id"])):
        if result.get("verdict") != "Passed":
            click.echo(
                printable(f"  {result['verdict']:<8} {result['id']}: {result.get('reason', '')}")
            )
    click.echo(f"{name}: {phase} ({_counts(status)})")
    if phase == "Cancelled":
        click.echo(f"{name}: cancelled: {_complete_reason(status)}", err=True)
    raise SystemExit(EXIT_BY_PHASE.get(phase, EXIT_ERROR))


def _complete(status: Mapping[str, Any]) -> bool:
    return any(
        c.get("type") == "Complete" and c.get("status") == "True"
        for c in status.get("conditions") or ()
    )


def _complete_reason(status: Mapping[str, Any]) -> str:
    """``<reason>: <message>`` of the Complete condition (why a campaign was cancelled)."""
    for condition in status.get("conditions") or ():
        if condition.get("type") == "Complete":
            message = str(condition.get("message") or "").strip()
            reason = str(condition.get("reason") or "")
            return f"{reason}: {message}" if message else reason
    return "no reason recorded"


def _wait(
    client: operating.CampaignClient, namespace: str, name: str, *, timeout: float
) -> Mapping[str, Any]:
    deadline = time.monotonic() + timeout
    last = ""
    while time.monotonic() < deadline:
        for obj in client.watch(namespace, name, deadline - time.monotonic()):
            status = obj.get("status") or {}
            line = f"{status.get('phase', 'Pending')} {status.get('progress', '')}".strip()
            if line != last:
                click.echo(f"{name}: {line}")
                last = line
            if _complete(status):
                return status
            if time.monotonic() >= deadline:
                break
    click.echo(f"{name}: not Complete after {timeout:.0f}s", err=True)
    raise SystemExit(EXIT_ERROR)


def _counts(status: Mapping[str, Any]) -> str:
    keys = ("passed", "failed", "errored", "timedOut", "invalid", "skipped")
    return ", ".join(f"{status.get(k, 0)} {k}" for k in keys if status.get(k)) or "no scenarios"


def _time(value: Any) -> datetime.datetime | None:
    if not isinstance(value, str):
        return None
    return datetime.datetime.fromisoformat(value.replace("Z", "+00:00"))


def _junit(
    namespace: str, name: str, status: Mapping[str, Any], results: list[Mapping[str, Any]]
) -> str:
    started = _time(status.get("startTime")) or datetime.datetime.now(datetime.UTC)
    info = records.CampaignInfo(name=name, namespace=namespace, started_at=started)
    campaign = records.CampaignRecord(
        run_key=records.derive_run_key(info),
        info=info,
        finished_at=_time(status.get("completionTime")),
        phase=str(status.get("phase", "")),
    )
    outcomes = [
        records.StoredOutcome(
            scenario=records.ScenarioInfo(
                scenario_id=str(r["id"]), sha256=str(r.get("sha256") or "0" * 64)
            ),
            outcome=ScenarioOutcome(
                scenario_id=str(r["id"]),
                verdict=Verdict(r["verdict"]),
                reason=str(r.get("reason", "")),
                metrics={str(k): float(v) for k, v in (r.get("metrics") or {}).items()},
                wall_seconds=float(r.get("durationSeconds", 0.0)),
                attempts=int(r.get("attempts", 1)),
                artifacts={str(k): str(v) for k, v in (r.get("artifacts") or {}).items()},
            ),
        )
        for r in results
    ]
    return junit.render(campaign, outcomes)
