"""Results: the store (SQLite by default, PostgreSQL from a DSN), JUnit XML and the HTML report.

Public API (import from here)::

    store = results.open_store(outdir)            # or "postgresql://..."
    key = store.begin_campaign(results.CampaignInfo(...), scenarios=[results.ScenarioInfo(...)])
    store.add_outcome(key, scenario_info, outcome)   # one transaction, idempotent per attempt
    store.finish_campaign(key, finished_at=now, phase="Succeeded")
    store.outcomes(key); store.compare(key_a, key_b)
"""

from simtest_operator.results.comparing import Change, Comparison, ScenarioChange, compare
from simtest_operator.results.migrating import LATEST_VERSION
from simtest_operator.results.opening import describe, open_store
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
    "PostgresStore",
    "ResultSink",
    "ResultSource",
    "RunKey",
    "ScenarioChange",
    "ScenarioInfo",
    "SqliteStore",
    "Store",
    "StoredOutcome",
    "compare",
    "derive_run_key",
    "describe",
    "is_failing",
    "open_store",
]
