"""``simtest-runner``: the entrypoint a simulator pod runs (filled in by the operator issue)."""

from __future__ import annotations

import sys


def main() -> None:
    """Console-script entry point."""
    sys.stderr.write("simtest-runner: not available in this build yet\n")
    raise SystemExit(2)
