-- Schema v3: the final counters of a campaign run (total, passed, failed, errored, ...), as the
-- operator reports them when the campaign completes. They cover scenarios whose pods could not
-- write a row (database down, pod lost before it wrote), so the run's record stays complete.

ALTER TABLE campaigns ADD COLUMN counts @JSON@ NOT NULL DEFAULT '{}';
