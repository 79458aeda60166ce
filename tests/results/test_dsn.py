"""Telling a PostgreSQL DSN from a SQLite path, and redacting it (issue 12, item 1).

Covers: every DSN form libpq accepts (key/value, ``postgresql://`` and ``postgres://`` in any
case, the password in the query or percent-encoded, several hosts, a service) is a DSN; plain,
relative and absolute paths (also with ``=`` when written ``./``) are paths; ambiguous targets
(another scheme, ``user:pw@host`` without one, unparsable key/value text) are refused without
quoting the password; ``describe`` and ``redact`` never show it; ``open_store`` on a DSN never
creates a SQLite file.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator import results
from simtest_operator.errors import ResultsError
from simtest_operator.results import dsn

SECRET = "SeCrEt-pw"


@pytest.mark.parametrize(
    ("target", "where"),
    [
        (f"host=db.example port=6543 user=u password={SECRET} dbname=res",
         "postgresql://db.example:6543/res"),
        (f"dbname = res host = db password = '{SECRET}'", "postgresql://db:5432/res"),
        (f"postgresql://u:{SECRET}@db/res", "postgresql://db:5432/res"),
        (f"POSTGRESQL://u:{SECRET}@db:6000/res", "postgresql://db:6000/res"),
        (f"Postgres://u:{SECRET}@db/res?sslmode=require", "postgresql://db:5432/res"),
        (f"postgres://u:{SECRET.replace('-', '%2D')}@db/res", "postgresql://db:5432/res"),
        (f"postgresql:///res?host=/run/pg&password={SECRET}", "postgresql:///run/pg:5432/res"),
        (f"postgresql://u:{SECRET}@h1:5432,h2:5433/res", "postgresql://h1,h2:5432,5433/res"),
        ("service=results", "postgresql://(service results)/"),
    ],
)  # fmt: skip
def test_every_libpq_form_is_a_dsn(target: str, where: str) -> None:
    located = dsn.classify(target)
    assert isinstance(located, dsn.Dsn)
    assert located.where == where == dsn.describe(target)
    assert SECRET not in repr(located) and SECRET not in located.where
    assert located.conninfo.startswith(("postgresql://", "postgres://")) or "=" in located.conninfo


@pytest.mark.parametrize(
    "target", ["results.sqlite", "out/run", "/tmp/out/results.sqlite", "./a=b.sqlite",
               "/tmp/run=1/results.sqlite", "../x=y", "me@work/results.sqlite"],
)  # fmt: skip
def test_paths_are_paths(target: str) -> None:
    assert dsn.classify(target) == Path(target)
    assert dsn.describe(target) == target
    assert dsn.classify(Path(target)) == Path(target)


@pytest.mark.parametrize(
    ("target", "message"),
    [
        (f"mysql://u:{SECRET}@db/res", "unsupported results database URL scheme 'mysql'"),
        (f"sqlite:///{SECRET}", "unsupported results database URL scheme 'sqlite'"),
        (f"u:{SECRET}@db/res", "looks like user:password@host without a scheme"),
        (f"host=db password={SECRET} dbname", "neither a SQLite path nor a DSN libpq can parse"),
        (f"host=db pasword={SECRET}", "neither a SQLite path nor a DSN libpq can parse"),
        (f"host=db password=Se {SECRET}", "neither a SQLite path nor a DSN libpq can parse"),
        (f"out/run={SECRET}", "a SQLite path containing '=' is written ./NAME"),
    ],
)  # fmt: skip
def test_ambiguous_targets_are_refused_without_the_secret(target: str, message: str) -> None:
    with pytest.raises(ResultsError, match=message) as raised:
        dsn.classify(target)
    assert SECRET not in str(raised.value)
    assert "\n" not in str(raised.value)
    assert dsn.describe(target) == "<unrecognised results database target>"


def test_redact_masks_the_whole_dsn_and_every_spelling_of_the_password() -> None:
    given = f"POSTGRESQL://u:{SECRET.replace('-', '%2D')}@db/res"
    located = dsn.classify(given)
    assert isinstance(located, dsn.Dsn)
    text = f"a {given} b {located.conninfo} c {SECRET} d {SECRET.replace('-', '%2D')}"
    redacted = dsn.redact(text, located)
    assert SECRET not in redacted and "%2D" not in redacted
    assert redacted == "a postgresql://db:5432/res b postgresql://db:5432/res c *** d ***"


@pytest.mark.parametrize("target", [f"host=127.0.0.1 port=1 password={SECRET} dbname=d",
                                    f"POSTGRESQL://u:{SECRET}@127.0.0.1:1/d"])  # fmt: skip
def test_open_store_connects_to_a_dsn_and_never_creates_a_file(
    target: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ResultsError, match="cannot connect to the results database") as raised:
        results.open_store(target, connect_timeout=1)
    assert SECRET not in str(raised.value)
    assert "postgresql://127.0.0.1:1/d" in str(raised.value)
    assert "\n" not in str(raised.value)
    assert list(tmp_path.iterdir()) == []
