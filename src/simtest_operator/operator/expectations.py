"""Expectations: do not plan again until the cache has seen our own writes.

The planner reads kopf's watch-fed indexes. Right after a write those lag behind by one watch
event; planning in that gap would count a just-created environment as missing and start a second
one, or over-fill the window. Like controller-runtime's ReplicaSet expectations, a campaign loop
records what each write must make visible (an object present, gone, or at a newer
resourceVersion) and skips planning until all of it is visible — or a deadline passes, after
which the cache is trusted again.
"""

from __future__ import annotations

import dataclasses
import datetime
import enum
from collections.abc import Callable

from simtest_operator.operator.actions import Kind


class Want(enum.Enum):
    """What must become visible."""

    PRESENT = "present"
    ABSENT = "absent"
    VERSION = "version"
    """Present at ``version`` or later."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Expectation:
    """One write the cache has to show."""

    kind: Kind
    name: str
    want: Want
    version: str = ""


Lookup = Callable[[Kind, str], tuple[bool, str, bool] | None]
"""(kind, name) -> None when absent, else (present, resourceVersion, deleting)."""


def newer_or_equal(seen: str, wanted: str) -> bool:
    """Whether resourceVersion ``seen`` is at least ``wanted`` (etcd revisions are integers; an
    unparsable version only matches itself)."""
    if seen == wanted:
        return True
    try:
        return int(seen) >= int(wanted)
    except ValueError:
        return False


@dataclasses.dataclass(slots=True)
class Expectations:
    """Pending expectations of one campaign loop."""

    timeout: float = 5.0
    pending: list[Expectation] = dataclasses.field(default_factory=list)
    deadline: datetime.datetime | None = None

    def expect(self, items: list[Expectation], *, now: datetime.datetime) -> None:
        """Add expectations (the deadline restarts)."""
        if items:
            self.pending.extend(items)
            self.deadline = now + datetime.timedelta(seconds=self.timeout)

    def satisfied(self, lookup: Lookup, *, now: datetime.datetime) -> bool:
        """Drop the expectations the cache fulfils; True when none are left or time is up."""
        self.pending = [e for e in self.pending if not _met(e, lookup(e.kind, e.name))]
        if not self.pending or (self.deadline is not None and now >= self.deadline):
            self.pending.clear()
            self.deadline = None
            return True
        return False


def _met(expectation: Expectation, seen: tuple[bool, str, bool] | None) -> bool:
    if expectation.want is Want.ABSENT:
        return seen is None or seen[2]
    if seen is None:
        return False
    if expectation.want is Want.PRESENT:
        return True
    return newer_or_equal(seen[1], expectation.version)
