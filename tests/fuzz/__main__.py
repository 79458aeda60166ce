"""Run one fuzz target under atheris (libFuzzer) for a bounded time.

    .venv/bin/python -m tests.fuzz xodr --seconds 600        # longer, on demand
    .venv/bin/python -m tests.fuzz all --seconds 20          # every target, one after another

The committed corpus (``tests/fuzz/corpus/<target>``) seeds the run and is only read: inputs
libFuzzer finds interesting go to a scratch folder (``--keep DIR`` to keep them, e.g. to add the
best ones to the corpus). A failing input is written to ``--artifacts`` (default: a scratch
folder, printed) and the exit code is non-zero. Each input must finish within ``--input-timeout``
seconds and the process within ``--rss-mb`` MiB (a simulator pod's memory request).
"""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
import tempfile
from pathlib import Path

from tests.fuzz.targets import CORPUS, INSTRUMENTED, TARGETS


def _arguments(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="python -m tests.fuzz", description=__doc__.split("\n")[0]
    )
    parser.add_argument("target", choices=[*TARGETS, "all"])
    parser.add_argument("--seconds", type=int, default=20, help="total fuzzing time per target")
    parser.add_argument("--input-timeout", type=int, default=10, help="seconds per input")
    parser.add_argument("--rss-mb", type=int, default=1024, help="memory limit (MiB)")
    parser.add_argument("--max-len", type=int, default=65536, help="largest input (bytes)")
    parser.add_argument("--keep", type=Path, help="folder for new interesting inputs")
    parser.add_argument("--artifacts", type=Path, help="folder for crashing inputs")
    return parser.parse_args(argv)


def main(argv: list[str]) -> int:
    options = _arguments(argv)
    if options.target == "all":
        # One process per target: libFuzzer exits the process when its time is up.
        codes = [
            subprocess.call([sys.executable, "-m", "tests.fuzz", name, *argv[1:]])
            for name in TARGETS
        ]
        return max(codes)
    return _fuzz(options)


def _fuzz(options: argparse.Namespace) -> int:
    import atheris  # only here: the corpus replay under pytest must not need it

    with atheris.instrument_imports(include=list(INSTRUMENTED[options.target])):
        for module in INSTRUMENTED[options.target]:
            importlib.import_module(module)  # the targets import them lazily: instrument now
    target = TARGETS[options.target]
    if options.keep is None or options.artifacts is None:
        scratch = Path(tempfile.mkdtemp(prefix=f"fuzz-{options.target}-"))
    found = options.keep or scratch / "found"
    artifacts = options.artifacts or scratch / "artifacts"
    found.mkdir(parents=True, exist_ok=True)
    artifacts.mkdir(parents=True, exist_ok=True)
    print(f"fuzzing {options.target} for {options.seconds} s; failing inputs go to {artifacts}")
    libfuzzer = [
        sys.argv[0],
        f"-max_total_time={options.seconds}",
        f"-timeout={options.input_timeout}",
        f"-rss_limit_mb={options.rss_mb}",
        f"-max_len={options.max_len}",
        f"-artifact_prefix={artifacts}/",
        "-print_final_stats=1",
        str(found),
        str(CORPUS / options.target),
    ]
    atheris.Setup(libfuzzer, target)
    atheris.Fuzz()  # exits the process: 0 when the time ran out, non-zero on a finding
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
