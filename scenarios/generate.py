"""Regenerate the scenario library: `python scenarios/generate.py [--out DIR]`.

Without --out the files are written next to this script (the committed library). The output
is deterministic, so a test regenerates into a temporary folder and compares bytes.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from libgen import suite, writing


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent)
    args = parser.parse_args(argv)
    files = writing.write_all(args.out, suite.suite(), suite.smoke(), suite.search_cases())
    sys.stdout.write(f"wrote {len(files)} files under {args.out}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
