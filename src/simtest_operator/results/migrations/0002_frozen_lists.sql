-- Schema v2: the frozen scenario list of each campaign run (so a report can name what never
-- ran, e.g. after a killed run), the elements a run ignored, and indexes for history queries.

CREATE TABLE campaign_scenarios (
    run_key TEXT NOT NULL REFERENCES campaigns (run_key) ON DELETE CASCADE,
    position INTEGER NOT NULL,
    scenario_id TEXT NOT NULL,
    sha256 TEXT NOT NULL,
    PRIMARY KEY (run_key, scenario_id),
    FOREIGN KEY (scenario_id, sha256) REFERENCES scenarios (scenario_id, sha256)
);

ALTER TABLE runs ADD COLUMN ignored_elements @JSON@ NOT NULL DEFAULT '[]';

CREATE INDEX runs_by_scenario ON runs (scenario_id, recorded_at);

CREATE INDEX metrics_by_name ON metrics (name, value);
