"""Keeping configured secrets out of text that comes from outside.

Servers, git and libpq quote requests back in their errors: a GraphQL server echoed the request's
``Authorization`` header (``query failed: denied for Bearer tok_…``) and the token reached stdout
(issue 29). Masking where the text is *shown* would need every display to know every secret, so
the masking happens where the secret is *held*: the code that sends a token, a password or a DSN
wraps its work in :meth:`Secrets.masking`, and any :class:`~simtest_operator.errors.SimtestError`
leaving it -- the only way outside text travels on to messages, logs, statuses and the results
database -- has every secret replaced by :data:`MASK`. One facility for database tokens, git URL
passwords, DSN passwords and S3 keys.
"""

from __future__ import annotations

import contextlib
import dataclasses
import urllib.parse
from collections.abc import Iterator

from simtest_operator.errors import SimtestError

MASK = "***"
"""What a secret is replaced with in text that is shown or stored."""


@dataclasses.dataclass(frozen=True, slots=True)
class Secrets:
    """Secret values in every form a server may give them back in; never shown in a repr."""

    forms: tuple[str, ...] = dataclasses.field(default=(), repr=False)
    """Longest first, so a secret containing another is masked whole."""

    @classmethod
    def of(cls, *values: str) -> Secrets:
        """The secrets ``values`` (empty ones ignored) as written, percent-encoded (a URL or a
        query string quotes them) and percent-decoded (a URL's user info is written encoded)."""
        forms = {
            form
            for value in values
            if value
            for form in (
                value,
                urllib.parse.quote(value, safe=""),
                urllib.parse.quote_plus(value),
                urllib.parse.unquote(value),
            )
        }
        forms.discard("")
        return cls(tuple(sorted(forms, key=lambda f: (-len(f), f))))

    def redact(self, text: str) -> str:
        """``text`` with every secret replaced by :data:`MASK`."""
        for form in self.forms:
            text = text.replace(form, MASK)
        return text

    @contextlib.contextmanager
    def masking(self) -> Iterator[None]:
        """Mask the secrets in the message of a SimtestError raised inside (same exception, same
        type); its chain of causes is cut when any of them quotes a secret (a traceback or a
        logged exception would print them)."""
        try:
            yield
        except SimtestError as exc:
            if self.forms and self._quoted(exc):
                exc.args = (self.redact(str(exc)),)
                exc.__cause__ = exc.__context__ = None
                exc.__suppress_context__ = True
            raise

    def _quoted(self, exc: BaseException) -> bool:
        seen: set[int] = set()
        chain: BaseException | None = exc
        while chain is not None and id(chain) not in seen:
            seen.add(id(chain))
            if self.redact(str(chain)) != str(chain):
                return True
            chain = chain.__cause__ or chain.__context__
        return False
