"""Waiting for components: poll a health endpoint, but give up early when the process died.

Every wait is bounded and watches the processes it depends on, so a crash or a port clash shows
up within a poll interval as an error naming the component and quoting its log, never as a hang.
"""

from __future__ import annotations

import ssl
import time
import urllib.error
import urllib.request
from collections.abc import Callable, Sequence
from pathlib import Path

from simtest_operator.devcluster.processes import ProcessRecord, exited_error, is_alive, log_tail
from simtest_operator.errors import ClusterError

POLL_SECONDS = 0.2


def http_ok(
    url: str, *, ca_file: Path | None = None, token: str | None = None, verify: bool = True
) -> bool:
    """Whether ``GET url`` answers 200 within a second."""
    context: ssl.SSLContext | None = None
    if url.startswith("https://"):
        context = ssl.create_default_context(cafile=str(ca_file) if ca_file else None)
        if not verify:
            context.check_hostname = False
            context.verify_mode = ssl.CERT_NONE
    request = urllib.request.Request(url)
    if token:
        request.add_header("Authorization", f"Bearer {token}")
    try:
        with urllib.request.urlopen(request, timeout=1.0, context=context) as response:
            return bool(response.status == 200)
    except (urllib.error.URLError, OSError, ValueError):
        return False


def wait_until(
    check: Callable[[], bool],
    *,
    what: str,
    timeout: float,
    watch: Sequence[ProcessRecord],
    blame: ProcessRecord | None = None,
) -> float:
    """Poll ``check`` until it is true; return the seconds it took.

    Raises :class:`ClusterError` as soon as a watched process is gone, or after ``timeout`` with
    the log tail of ``blame`` (the component that should have become ready).
    """
    start = time.monotonic()
    while True:
        for record in watch:
            if not is_alive(record):
                raise exited_error(record, f"while waiting for {what}")
        if check():
            return time.monotonic() - start
        if time.monotonic() - start > timeout:
            detail = f"; log {blame.log}:\n{log_tail(blame.log)}" if blame else ""
            raise ClusterError(f"timed out after {timeout:.0f}s waiting for {what}{detail}")
        time.sleep(POLL_SECONDS)
