-- Schema v4: re-evaluations of recorded runs. An evaluation scores the runs of one campaign run
-- again with a named criteria set, from their recordings alone; the original verdicts stay in
-- `runs`. Each evaluated attempt keeps its verdict, the quality of its evidence and its base
-- scenarios (free driving, following, cut-in, ...) with their metrics and thresholds.

CREATE TABLE evaluations (
    evaluation_id TEXT PRIMARY KEY,
    run_key TEXT NOT NULL REFERENCES campaigns (run_key) ON DELETE CASCADE,
    criteria_name TEXT NOT NULL,
    criteria @JSON@ NOT NULL,
    criteria_sha256 TEXT NOT NULL,
    created_at @TIMESTAMP@ NOT NULL,
    finished_at @TIMESTAMP@,
    versions @JSON@ NOT NULL
);

CREATE INDEX evaluations_by_run ON evaluations (run_key, created_at);

CREATE TABLE evaluated_runs (
    evaluation_id TEXT NOT NULL REFERENCES evaluations (evaluation_id) ON DELETE CASCADE,
    run_key TEXT NOT NULL,
    scenario_id TEXT NOT NULL,
    attempt INTEGER NOT NULL,
    verdict TEXT NOT NULL
        CHECK (verdict IN ('Passed', 'Failed', 'Error', 'Timeout', 'Invalid', 'Skipped')),
    reason TEXT NOT NULL DEFAULT '',
    evidence TEXT NOT NULL CHECK (evidence IN ('complete', 'incomplete', 'missing')),
    quality @JSON@ NOT NULL,
    issues @JSON@ NOT NULL,
    recording TEXT NOT NULL DEFAULT '',
    recorded_at @TIMESTAMP@ NOT NULL,
    PRIMARY KEY (evaluation_id, scenario_id, attempt),
    FOREIGN KEY (run_key, scenario_id, attempt)
        REFERENCES runs (run_key, scenario_id, attempt) ON DELETE CASCADE
);

-- value NULL stands for NaN; +-Infinity is stored as is (e.g. minTTC without a closing lead).
CREATE TABLE evaluated_metrics (
    evaluation_id TEXT NOT NULL,
    scenario_id TEXT NOT NULL,
    attempt INTEGER NOT NULL,
    name TEXT NOT NULL,
    value @FLOAT@,
    PRIMARY KEY (evaluation_id, scenario_id, attempt, name),
    FOREIGN KEY (evaluation_id, scenario_id, attempt)
        REFERENCES evaluated_runs (evaluation_id, scenario_id, attempt) ON DELETE CASCADE
);

CREATE TABLE base_scenarios (
    evaluation_id TEXT NOT NULL,
    scenario_id TEXT NOT NULL,
    attempt INTEGER NOT NULL,
    position INTEGER NOT NULL,
    kind TEXT NOT NULL,
    actor INTEGER,
    start_seconds @FLOAT@ NOT NULL,
    end_seconds @FLOAT@ NOT NULL,
    verdict TEXT NOT NULL CHECK (verdict IN ('Passed', 'Failed')),
    reason TEXT NOT NULL DEFAULT '',
    detail TEXT NOT NULL DEFAULT '',
    PRIMARY KEY (evaluation_id, scenario_id, attempt, position),
    FOREIGN KEY (evaluation_id, scenario_id, attempt)
        REFERENCES evaluated_runs (evaluation_id, scenario_id, attempt) ON DELETE CASCADE
);

CREATE INDEX base_scenarios_by_kind ON base_scenarios (kind, verdict);

-- threshold and passed are NULL for a metric computed but not checked; passed is 0 or 1.
CREATE TABLE base_scenario_metrics (
    evaluation_id TEXT NOT NULL,
    scenario_id TEXT NOT NULL,
    attempt INTEGER NOT NULL,
    position INTEGER NOT NULL,
    name TEXT NOT NULL,
    value @FLOAT@,
    threshold @FLOAT@,
    passed INTEGER,
    PRIMARY KEY (evaluation_id, scenario_id, attempt, position, name),
    FOREIGN KEY (evaluation_id, scenario_id, attempt, position)
        REFERENCES base_scenarios (evaluation_id, scenario_id, attempt, position) ON DELETE CASCADE
);
