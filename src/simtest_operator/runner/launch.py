"""``simtest-runner``'s console script: the runner imported with the cyclic collector off.

A simulator pod's start-up is mostly imports (the OpenSCENARIO and OpenDRIVE models, numpy,
pydantic, libsumo). They allocate objects that live as long as the process, and the collector,
at its default thresholds, scans them again and again while they arrive: 0.06-0.1 s of a
runner's start to its first step. Collection resumes once the imports are done, with everything
imported so far frozen (never scanned again, and in a warm pod never copied by the forks'
collectors).
"""

from __future__ import annotations

import gc


def main() -> None:
    """Console-script entry point: import :mod:`.entrypoint` without collections, then run it."""
    gc.disable()
    try:
        from simtest_operator.runner import entrypoint
    finally:
        gc.freeze()
        gc.enable()
    entrypoint.main()
