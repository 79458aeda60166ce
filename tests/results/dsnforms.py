"""The spellings of one PostgreSQL DSN that libpq accepts, each carrying a password.

The throw-away server trusts loopback connections, so a password in the DSN is never checked:
every form reaches the same database, and a test can look for the password in every output.
"""

from __future__ import annotations

import psycopg.conninfo

PASSWORD = "SeCrEt-pw-4711"
"""Never to be seen in any output."""


def forms(dsn: str) -> dict[str, str]:
    """Name -> the DSN ``dsn`` respelled: key/value, upper-case scheme, ``postgres://``, query."""
    p = psycopg.conninfo.conninfo_to_dict(dsn)
    host, port, user, name = p["host"], p["port"], p["user"], p["dbname"]
    return {
        "key-value": f"host={host} port={port} user={user} password={PASSWORD} dbname={name}",
        "upper-case-uri": f"POSTGRESQL://{user}:{PASSWORD}@{host}:{port}/{name}",
        "postgres-uri": f"postgres://{user}:{PASSWORD}@{host}:{port}/{name}",
        "password-in-query": f"postgresql://{user}@{host}:{port}/{name}?password={PASSWORD}",
    }
