"""Results: the store (SQLite by default, PostgreSQL from a DSN), JUnit XML and the HTML report.

Public API (import from here)::

    store = results.open_store(outdir)            # or a DSN: "postgresql://...", "host=..."
    key = store.begin_campaign(results.CampaignInfo(...), scenarios=[results.ScenarioInfo(...)])
    store.add_outcome(key, scenario_info, outcome)   # one transaction, idempotent per attempt
    store.finish_campaign(key, finished_at=now, phase="Succeeded")
    store.outcomes(key); store.compare(key_a, key_b)

On a cluster (pods record attempts, the operator finishes the run; see :mod:`.clusterruns`)::

    key = results.cluster_run_key(namespace=ns, name=name, uid=uid, created=created)
    results.record_pod_attempt(store, key, campaign=name, scenario=info, outcome=o, now=now)
    results.finish_campaign_run(store, key, info=campaign_info, finish=results.Finish(...))
"""

from simtest_operator.results.clusterruns import (
    Finish,
    cluster_run_key,
    finish_campaign_run,
    key_time,
    record_pod_attempt,
    start_campaign_run,
)
from simtest_operator.results.comparing import Change, Comparison, ScenarioChange, compare
from simtest_operator.results.dsn import describe
from simtest_operator.results.evaluations import EvaluationMessage
from simtest_operator.results.migrating import LATEST_VERSION
from simtest_operator.results.opening import open_store
from simtest_operator.results.postgres import PostgresStore
from simtest_operator.results.records import (
    UNCATEGORIZED,
    CampaignInfo,
    CampaignRecord,
    RunKey,
    ScenarioInfo,
    StoredOutcome,
    derive_run_key,
    is_failing,
)
from simtest_operator.results.sqlite import DEFAULT_FILENAME, SqliteStore
from simtest_operator.results.stores import ResultSink, ResultSource, Store

__all__ = [
    "DEFAULT_FILENAME",
    "LATEST_VERSION",
    "UNCATEGORIZED",
    "CampaignInfo",
    "CampaignRecord",
    "Change",
    "Comparison",
    "EvaluationMessage",
    "Finish",
    "PostgresStore",
    "ResultSink",
    "ResultSource",
    "RunKey",
    "ScenarioChange",
    "ScenarioInfo",
    "SqliteStore",
    "Store",
    "StoredOutcome",
    "cluster_run_key",
    "compare",
    "derive_run_key",
    "describe",
    "finish_campaign_run",
    "is_failing",
    "key_time",
    "open_store",
    "record_pod_attempt",
    "start_campaign_run",
]
