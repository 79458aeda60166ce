-- Schema v1: campaign runs, scenarios, one row per attempt, metrics per attempt.
-- Dialect tokens (@JSON@, @TIMESTAMP@, @FLOAT@) are replaced per database by migrating.py;
-- statements are split on ';' at the end of a line, so no ';' may end a line inside a statement.

CREATE TABLE campaigns (
    run_key TEXT PRIMARY KEY,
    name TEXT NOT NULL,
    namespace TEXT NOT NULL DEFAULT '',
    manifest_sha256 TEXT NOT NULL DEFAULT '',
    started_at @TIMESTAMP@ NOT NULL,
    finished_at @TIMESTAMP@,
    phase TEXT NOT NULL DEFAULT '',
    sut_name TEXT NOT NULL DEFAULT '',
    sut_version TEXT NOT NULL DEFAULT '',
    simulator_version TEXT NOT NULL DEFAULT '',
    settings @JSON@ NOT NULL
);

CREATE INDEX campaigns_by_name ON campaigns (namespace, name, started_at);

CREATE TABLE scenarios (
    scenario_id TEXT NOT NULL,
    sha256 TEXT NOT NULL,
    source TEXT NOT NULL DEFAULT '',
    tags @JSON@ NOT NULL,
    category TEXT NOT NULL,
    road TEXT NOT NULL DEFAULT '',
    PRIMARY KEY (scenario_id, sha256)
);

CREATE TABLE runs (
    run_key TEXT NOT NULL REFERENCES campaigns (run_key) ON DELETE CASCADE,
    scenario_id TEXT NOT NULL,
    sha256 TEXT NOT NULL,
    attempt INTEGER NOT NULL CHECK (attempt >= 1),
    verdict TEXT NOT NULL
        CHECK (verdict IN ('Passed', 'Failed', 'Error', 'Timeout', 'Invalid', 'Skipped')),
    reason TEXT NOT NULL DEFAULT '',
    simulated_seconds @FLOAT@ NOT NULL DEFAULT 0,
    wall_seconds @FLOAT@ NOT NULL DEFAULT 0,
    artifacts @JSON@ NOT NULL,
    content_hashes @JSON@ NOT NULL,
    versions @JSON@ NOT NULL,
    recorded_at @TIMESTAMP@ NOT NULL,
    PRIMARY KEY (run_key, scenario_id, attempt),
    FOREIGN KEY (scenario_id, sha256) REFERENCES scenarios (scenario_id, sha256)
);

-- value NULL stands for NaN (SQLite cannot store NaN); +-Infinity is stored as is.
CREATE TABLE metrics (
    run_key TEXT NOT NULL,
    scenario_id TEXT NOT NULL,
    attempt INTEGER NOT NULL,
    name TEXT NOT NULL,
    value @FLOAT@,
    PRIMARY KEY (run_key, scenario_id, attempt, name),
    FOREIGN KEY (run_key, scenario_id, attempt)
        REFERENCES runs (run_key, scenario_id, attempt) ON DELETE CASCADE
);
