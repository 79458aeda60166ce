"""Text from outside (file names, scenario ids, reasons, paths) made safe to print on a terminal.

Two hazards, one module: rich markup (a folder named ``s[/x]`` crashed ``scenario check`` with a
MarkupError, exit 1) and control characters (an ESC, CR, newline or right-to-left override in a
file name reached the terminal raw and could rewrite what the user sees; issue 29). Every piece of
user text the CLI prints goes through :func:`printable`, or :func:`markup` when the console
interprets markup.
"""

from __future__ import annotations

import re

_CONTROL = re.compile(
    "[\x00-\x1f\x7f-\x9f"  # C0 (ESC, CR, LF, BEL, ...), DEL, C1 (CSI, OSC, ...)
    "\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069"  # bidirectional marks, embeddings, overrides
    "\u2028\u2029]"  # line and paragraph separators
)


def _escaped(match: re.Match[str]) -> str:
    code = ord(match.group())
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def printable(text: object) -> str:
    r"""``text`` on one line with every control or bidi character written as ``\xNN``/``\uNNNN``."""
    return _CONTROL.sub(_escaped, str(text))


def markup(text: object) -> str:
    """:func:`printable`, also escaped for a rich console that reads markup."""
    from rich.markup import escape  # here: `scenario run` starts without rich

    return escape(printable(text))
