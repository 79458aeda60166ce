"""``simtest evaluate``: score recorded runs again with another criteria set, without simulating.

Parses options, loads the criteria file and prints what :func:`runner.reevaluate`
returns. Exit codes follow ``simtest run``: 0 every scenario passed, 1 some did not (a verdict
on the system under test, or evidence that cannot back a pass), 2 bad input.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from simtest_operator.cli.terminal import printable
from simtest_operator.errors import SimtestError
from simtest_operator.settings import Settings

if TYPE_CHECKING:
    from simtest_operator.evaluation.reevaluating import CriteriaSet
    from simtest_operator.results.evaluations import EvaluatedRun


def _load_criteria(path: Path | None) -> CriteriaSet:
    from simtest_operator.evaluation import reevaluating

    if path is None:
        return reevaluating.DEFAULT_CRITERIA
    import yaml

    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise SimtestError(f"cannot read criteria {path}: {str(exc).splitlines()[0]}") from None
    if not isinstance(data, dict):
        raise SimtestError(f"{path}: a criteria set is a mapping (name, baseScenarios, ...)")
    return reevaluating.load_criteria(data, where=str(path))


def _write_summary(
    path: Path | None, summary: str, *, evaluation_id: str = "", run: str = ""
) -> None:
    """The summary for whoever started us (the operator reads the Job pod's termination
    message); a file that cannot be written costs the message, not the evaluation."""
    if path is None:
        return
    from simtest_operator.results import EvaluationMessage

    message = EvaluationMessage(summary=summary, evaluation_id=evaluation_id, run_key=run)
    try:
        path.write_text(message.to_text(), encoding="utf-8")
    except OSError as exc:
        click.echo(f"simtest evaluate: cannot write the summary to {path}: {exc}", err=True)


@click.command()
@click.argument("source", metavar="OUTDIR|DSN", required=False)
@click.option(
    "--criteria",
    "criteria_file",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    help="Criteria set (YAML/JSON): thresholds per base-scenario type  [default: built-in]",
)
@click.option("--run", "run_key", metavar="KEY", help="Run key to evaluate  [default: newest]")
@click.option(
    "--artifacts",
    "artifacts",
    type=click.Path(exists=True, file_okay=False, path_type=Path),
    help="Where relative artifact paths start  [default: OUTDIR]",
)
@click.option(
    "--pvc-root",
    type=click.Path(exists=True, file_okay=False, path_type=Path),
    help="Local mount of the cluster's artifact volumes (for pvc:// artifacts).",
)
@click.option("--quiet", "-q", is_flag=True, help="Only the summary lines.")
@click.option(
    "--summary-file",
    type=click.Path(dir_okay=False, path_type=Path),
    help="Also write the outcome (evaluation id, summary line) there as JSON, e.g. "
    "/dev/termination-log in a Job  [default: $SIMTEST_EVALUATE_SUMMARY_FILE].",
)
def evaluate(
    source: str | None,
    criteria_file: Path | None,
    run_key: str | None,
    artifacts: Path | None,
    pvc_root: Path | None,
    quiet: bool,
    summary_file: Path | None,
) -> None:
    """Re-score recorded runs with another criteria set, from their recordings alone.

    SOURCE is a run's output folder (its results.sqlite) or a PostgreSQL DSN (default:
    $SIMTEST_RESULTS_DSN, so a DSN from a Secret stays out of the command line). Each scenario's
    recording is decomposed into base scenarios (following, cut-in, crossing, ...) and checked
    per type; the result is stored as a new evaluation of the same run (the original verdicts
    stay). Exit code: 0 all passed, 1 some failed or lack complete evidence, 2 bad input.
    """
    from simtest_operator import runner
    from simtest_operator.results import dsn, records

    defaults = Settings.from_env().results
    source = source or defaults.dsn
    if not source:
        raise click.MissingParameter(param_type="argument", param_hint="'OUTDIR|DSN'")
    summary_file = summary_file or defaults.summary_file
    local = Path(source)
    is_folder = local.is_dir()
    try:
        criteria = _load_criteria(criteria_file)
        if not is_folder and "://" not in source and "=" not in source and not local.is_file():
            raise SimtestError(f"{source}: no such output folder, database file or DSN")

        def show(category: str, run: EvaluatedRun) -> None:
            if not quiet:
                kinds = ", ".join(
                    f"{b.kind}{'' if b.verdict.value == 'Passed' else ' FAILED'}"
                    for b in run.base_scenarios
                )
                click.echo(
                    printable(f"{run.verdict.value:<8} {run.scenario_id}  [{kinds}]  {run.reason}")
                )

        summary = runner.reevaluate(
            runner.EvaluateRequest(
                target=source,
                base_dir=artifacts or (local if is_folder else None),
                criteria=criteria,
                run_key=records.RunKey(run_key) if run_key else None,
                pvc_root=pvc_root,
            ),
            progress=show,
        )
    except SimtestError as exc:
        click.echo(f"simtest evaluate: {exc}", err=True)
        _write_summary(summary_file, f"simtest evaluate: {exc}", run=run_key or "")
        raise SystemExit(2) from None
    counts = ", ".join(f"{n} {v.lower()}" for v, n in sorted(summary.totals.items()))
    incomplete = sum(1 for r in summary.runs if r.evidence != "complete")
    bases = sum(len(r.base_scenarios) for r in summary.runs)
    failed_bases = sum(
        1 for r in summary.runs for b in r.base_scenarios if b.verdict.value != "Passed"
    )
    line = (
        f"evaluation {summary.evaluation_id} of run {summary.run_key} ({dsn.describe(source)}) "
        f"with criteria {criteria.name!r}: {counts or 'no scenarios'}; "
        f"{bases} base scenarios, {failed_bases} failed; "
        f"{incomplete} without complete evidence; {summary.wall_seconds:.2f} s"
    )
    click.echo(line)
    failing = [r for r in summary.runs if r.verdict.value not in ("Passed", "Skipped")]
    verdict = ""
    if failing:
        first = failing[0]
        verdict = (
            f"{len(failing)} of {len(summary.runs)} scenarios not passed "
            f"(first: {first.scenario_id}: {first.verdict.value}: {first.reason})"
        )
        click.echo(verdict)
    _write_summary(
        summary_file,
        f"{line}; {verdict}" if verdict else line,
        evaluation_id=summary.evaluation_id,
        run=summary.run_key,
    )
    if failing:
        raise SystemExit(1)
