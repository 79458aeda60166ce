"""Telling a PostgreSQL DSN from a SQLite path, and showing a DSN without its secrets.

A results target comes from ``--db``, ``--database``, ``--compare`` or a Secret, and a DSN holds
a password. Taking a DSN for a file path once printed the password, saved it in campaign.json and
the report and created a SQLite file named after it (issue 12), so this module is the one place
that decides, and the one place that makes a target safe to show:

* every form libpq accepts is a DSN: a ``postgresql://`` or ``postgres://`` URI (the scheme in any
  case, as RFC 3986 allows; libpq itself wants lower case, so it is lowered) and the key/value
  form (``host=... password=...``); psycopg's libpq parser decides, not a pattern of ours;
* anything that could be either is refused (:class:`ResultsError`, never quoting the target):
  another ``scheme://``, ``user:password@host`` without a scheme, or text with ``=`` that libpq
  cannot parse (a mistyped DSN). A SQLite path with ``=`` in it is written ``./name`` or absolute;
* everything else is a SQLite path.
"""

from __future__ import annotations

import dataclasses
import urllib.parse
from collections.abc import Mapping
from pathlib import Path

from simtest_operator import redaction
from simtest_operator.errors import ResultsError

URI_SCHEMES = ("postgresql", "postgres")
"""The URI schemes libpq accepts (``postgresql://`` and ``postgres://``)."""
_PATH_STARTS = ("/", "./", "../", "~")
"""A target starting like this is a path: no libpq keyword starts with these characters."""


@dataclasses.dataclass(frozen=True, slots=True)
class Dsn:
    """A PostgreSQL connection string as libpq takes it; its text never shows in a repr."""

    conninfo: str = dataclasses.field(repr=False)
    """Exactly what to pass to ``psycopg.connect`` (the URI scheme lowered)."""
    given: str = dataclasses.field(repr=False)
    """The target as the user or the Secret wrote it."""
    passwords: tuple[str, ...] = dataclasses.field(repr=False)
    """The password as libpq reads it and as written (percent-encoded in a URI); may be empty."""
    where: str
    """``postgresql://host:port/dbname``: safe to show (no user, no password)."""


def classify(target: str | Path) -> Dsn | Path:
    """The DSN ``target`` names, or the SQLite path it is; ResultsError when it could be either."""
    if isinstance(target, Path):
        return target
    scheme, sep, _ = target.partition("://")
    if sep and scheme.lower() in URI_SCHEMES:
        return _parse(scheme.lower() + target[len(scheme) :], given=target)
    if target.startswith(_PATH_STARTS):
        return Path(target)
    if sep:
        raise ResultsError(
            f"unsupported results database URL scheme {_shown(scheme)!r}: give a "
            "postgresql://... DSN, a libpq key/value DSN (host=... dbname=...) or a SQLite path"
        )
    if "=" in target:
        return _parse(target, given=target)
    first = target.split("/", 1)[0]
    if "@" in first and ":" in first:
        raise ResultsError(
            "the results database target looks like user:password@host without a scheme; "
            "write it as postgresql://user:password@host/dbname (or ./NAME for a SQLite file)"
        )
    return Path(target)


def describe(target: str | Path) -> str:
    """A display form of a store target that never shows a password (never raises)."""
    try:
        located = classify(target)
    except ResultsError:
        return "<unrecognised results database target>"
    return located.where if isinstance(located, Dsn) else str(target)


def redact(text: str, dsn: Dsn) -> str:
    """``text`` (an error message, a log line) with every secret of ``dsn`` masked."""
    for whole in (dsn.given, dsn.conninfo):
        text = text.replace(whole, dsn.where)
    return redaction.Secrets.of(*dsn.passwords).redact(text)


def _parse(conninfo: str, *, given: str) -> Dsn:
    import psycopg.conninfo  # only for DSNs: 70 ms a SQLite target need not pay

    try:
        params = psycopg.conninfo.conninfo_to_dict(conninfo)
    except psycopg.ProgrammingError:
        # libpq's message quotes the text around the problem, which may be the password.
        raise ResultsError(
            "the results database target is neither a SQLite path nor a DSN libpq can parse "
            "(check the quoting and the keyword names of the key/value form); a SQLite path "
            "containing '=' is written ./NAME"
        ) from None
    password = str(params.get("password") or "")
    forms = {password, urllib.parse.quote(password, safe=""), _raw_password(given)} - {""}
    return Dsn(
        conninfo=conninfo,
        given=given,
        passwords=tuple(sorted(forms)) if password else (),
        where=_where(params),
    )


def _raw_password(given: str) -> str:
    """The password as written in a URI's user info (percent-encoded), if any."""
    netloc = urllib.parse.urlsplit(given).netloc
    userinfo, at, _ = netloc.rpartition("@")
    return userinfo.partition(":")[2] if at else ""


def _where(params: Mapping[str, object]) -> str:
    if "service" in params and "host" not in params:
        return f"postgresql://(service {params['service']})/{params.get('dbname', '')}"
    host = params.get("host") or params.get("hostaddr") or "localhost"
    return f"postgresql://{host}:{params.get('port', 5432)}/{params.get('dbname', '')}"


def _shown(text: str) -> str:
    # A scheme is short; anything longer is probably not one and may hold a secret.
    return text if len(text) <= 16 and text.isascii() and text.isalnum() else "?"
