"""Path globs with ``**``: the include/exclude patterns of a campaign and its criteria overrides.

Patterns match POSIX paths relative to a source root (or scenario ids), segment by segment:
``*`` and ``?`` never cross a ``/``, ``[...]`` is a character class, and a ``**`` segment matches
zero or more whole segments, so ``**/*.xosc`` also matches ``a.xosc`` at the root. A pattern
without ``/`` matches at the root only (``*.xosc``), as with ``pathlib.Path.glob``.
"""

from __future__ import annotations

import functools
import re


@functools.lru_cache(maxsize=256)
def compile_glob(pattern: str) -> re.Pattern[str]:
    """A regular expression matching exactly the paths ``pattern`` matches."""
    segments = pattern.strip("/").split("/")
    parts: list[str] = []
    for index, segment in enumerate(segments):
        last = index == len(segments) - 1
        if segment == "**":
            parts.append(".*" if last else "(?:[^/]+/)*")
            continue
        parts.append(_segment(segment) + ("" if last else "/"))
    return re.compile("".join(parts) + r"\Z", re.DOTALL)


def matches(path: str, pattern: str) -> bool:
    """Whether the relative POSIX ``path`` matches ``pattern``."""
    return compile_glob(pattern).match(path) is not None


def matches_any(path: str, patterns: tuple[str, ...] | list[str]) -> bool:
    """Whether ``path`` matches at least one of ``patterns``."""
    return any(matches(path, pattern) for pattern in patterns)


def _segment(segment: str) -> str:
    out: list[str] = []
    i = 0
    while i < len(segment):
        char = segment[i]
        if char == "*":
            out.append("[^/]*")
        elif char == "?":
            out.append("[^/]")
        elif char == "[":
            start = i + 1 + (segment[i + 1 : i + 2] == "!")
            start += segment[start : start + 1] == "]"  # a leading "]" is a literal member
            end = segment.find("]", start)
            if end == -1:
                out.append(re.escape(char))
            else:
                body = segment[i + 1 : end]
                negated = body.startswith("!")
                body = body[1:] if negated else body
                for special in ("\\", "]", "[", "^"):
                    body = body.replace(special, "\\" + special)
                body = body.replace("/", "")
                # A negated class must not match "/" either: "*" and "?" never cross segments.
                out.append(f"[^/{body}]" if negated else f"[{body}]")
                i = end
        else:
            out.append(re.escape(char))
        i += 1
    return "".join(out)
