"""The one redaction facility: configured secrets masked in every form, chains cut.

Covers: a secret is masked as written, percent-encoded and percent-decoded, the longest first;
``masking`` rewrites a SimtestError raised inside (same object, type and attributes) and cuts its
chain when a cause quotes the secret (a traceback would print it), leaves other errors and other
exceptions alone; no secret (an empty value) masks nothing.
"""

from __future__ import annotations

import traceback

import pytest

from simtest_operator.errors import ScenarioError, SourceError
from simtest_operator.redaction import MASK, Secrets


def test_every_form_of_a_secret_is_masked() -> None:
    secrets = Secrets.of("p@ss word/1", "")
    assert "p@ss" not in repr(secrets)
    for form in ("p@ss word/1", "p%40ss%20word%2F1", "p%40ss+word%2F1"):
        assert secrets.redact(f"denied for {form}.") == f"denied for {MASK}."
    assert Secrets.of("a%2Fb").redact("a/b and a%2Fb") == f"{MASK} and {MASK}"
    assert Secrets.of("tok", "tok_long").redact("tok_long tok") == f"{MASK} {MASK}"
    assert Secrets.of("").redact("anything") == "anything"


def test_masking_rewrites_the_error_and_cuts_a_quoting_chain() -> None:
    token = "tok_9f"
    with pytest.raises(ScenarioError) as caught, Secrets.of(token).masking():
        try:
            raise OSError(f"server said: Bearer {token}")
        except OSError as exc:
            raise ScenarioError(f"denied for Bearer {token}", file="a.xosc", line=3) from exc
    error = caught.value
    assert str(error) == f"denied for Bearer {MASK} (a.xosc, line 3)"
    assert (error.file, error.line) == ("a.xosc", 3)
    assert error.__cause__ is None and error.__suppress_context__
    assert token not in "".join(traceback.format_exception(error))


def test_masking_leaves_unrelated_errors_whole() -> None:
    with pytest.raises(SourceError) as caught, Secrets.of("tok_9f").masking():
        try:
            raise OSError("connection refused")
        except OSError as exc:
            raise SourceError("cannot connect") from exc
    assert isinstance(caught.value.__cause__, OSError), "a chain without secrets is kept"
    with pytest.raises(ValueError, match="tok_9f"), Secrets.of("tok_9f").masking():
        raise ValueError("tok_9f")  # not a SimtestError: a bug, left for its traceback
