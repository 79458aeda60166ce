"""What a local SUT process prints, kept within a fixed size.

A SUT's own log is the first thing its developer reads when a run ends ``Error``, so the runner
keeps stdout and stderr (merged, in the order the SUT wrote them) as the scenario's ``sut.log``
artifact and quotes its tail in every SUT error. A SUT may print without end; only the first
``head`` and the last ``tail`` bytes are kept, with the count of what was left out between them,
so memory and the artifact stay bounded whatever the SUT does.
"""

from __future__ import annotations

import os
import threading
from pathlib import Path
from typing import IO

HEAD_BYTES = 32 * 1024
TAIL_BYTES = 96 * 1024
READ_CHUNK = 8192


class BoundedOutput:
    """A process's output stream read on a thread into a head and a rolling tail."""

    __slots__ = ("_head", "_head_limit", "_lock", "_skipped", "_tail", "_tail_limit", "_thread")

    def __init__(self, *, head: int = HEAD_BYTES, tail: int = TAIL_BYTES) -> None:
        self._head = bytearray()
        self._tail = bytearray()
        self._head_limit, self._tail_limit = head, tail
        self._skipped = 0
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None

    def follow(self, stream: IO[bytes]) -> None:
        """Read ``stream`` until it closes, on a daemon thread (the SUT never waits for us)."""
        self._thread = threading.Thread(
            target=self._pump, args=(stream,), name="sut-output", daemon=True
        )
        self._thread.start()

    def feed(self, data: bytes) -> None:
        """Keep ``data``: into the head while it has room, else the tail (oldest bytes out)."""
        with self._lock:
            room = self._head_limit - len(self._head)
            if room > 0:
                self._head += data[:room]
                data = data[room:]
            self._tail += data
            excess = len(self._tail) - self._tail_limit
            if excess > 0:
                del self._tail[:excess]
                self._skipped += excess

    def finish(self, timeout: float = 2.0) -> None:
        """Wait (bounded) for the reader to drain the closed stream."""
        if self._thread is not None:
            self._thread.join(timeout)

    def last(self, chars: int) -> str:
        """The last ``chars`` characters, whitespace folded to single spaces (for one-line
        errors)."""
        with self._lock:
            data = bytes(self._head + self._tail) if not self._skipped else bytes(self._tail)
        return " ".join(data.decode("utf-8", "replace").split())[-chars:]

    def text(self) -> str:
        """Everything kept, with a marker where bytes were left out."""
        with self._lock:
            head, tail, skipped = bytes(self._head), bytes(self._tail), self._skipped
        middle = f"\n[... {skipped} bytes of SUT output not kept ...]\n" if skipped else ""
        return head.decode("utf-8", "replace") + middle + tail.decode("utf-8", "replace")

    def write(self, path: Path) -> None:
        """Write what was kept to ``path`` (the scenario's ``sut.log``) and start over: a warm
        SUT's next run gets a log of its own."""
        text = self.text()
        with self._lock:
            self._head.clear()
            self._tail.clear()
            self._skipped = 0
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")

    def skipped(self, count: int) -> None:
        """Count ``count`` bytes left out before what is fed next (read past, never kept)."""
        with self._lock:
            self._skipped += count

    def _pump(self, stream: IO[bytes]) -> None:
        try:
            while chunk := os.read(stream.fileno(), READ_CHUNK):
                self.feed(chunk)
        except (OSError, ValueError):  # closed under us when the process is stopped
            pass
        finally:
            stream.close()


def take_files(folder: Path, log: Path) -> bool:
    """Move what a pod's sidecars printed since the last call into ``log``; False: nothing there.

    Each sidecar appends to ``<container>.log`` in ``folder`` (the pod template's output
    capture). Each file gives its first ``HEAD_BYTES`` and last ``TAIL_BYTES`` under a header
    naming the container, read without loading what lies between, and is then emptied: its
    writer appends (``O_APPEND``), so what it prints next starts the next run's log. A line
    printed between the read and the truncation is lost; runs of one pod follow each other, so
    that is the moment between two scenarios.
    """
    parts = []
    for path in sorted(folder.glob("*.log")):
        kept = BoundedOutput()
        try:
            with path.open("r+b") as stream:
                size = os.fstat(stream.fileno()).st_size
                kept.feed(stream.read(min(size, HEAD_BYTES)))
                if size > HEAD_BYTES + TAIL_BYTES:
                    kept.skipped(size - HEAD_BYTES - TAIL_BYTES)
                    stream.seek(size - TAIL_BYTES)
                while chunk := stream.read(READ_CHUNK):
                    kept.feed(chunk)
                stream.truncate(0)
        except OSError:
            continue
        parts.append(f"==> {path.stem} <==\n{kept.text()}")
    if not parts:
        return False
    log.parent.mkdir(parents=True, exist_ok=True)
    log.write_text("\n".join(parts), encoding="utf-8")
    return True


def files_said(folder: Path, chars: int) -> str | None:
    """For an error: the last ``chars`` characters each sidecar printed into ``folder`` during
    this run (whitespace folded), by container; None when they printed nothing."""
    said = []
    for path in sorted(folder.glob("*.log")):
        try:
            with path.open("rb") as stream:
                size = os.fstat(stream.fileno()).st_size
                stream.seek(max(size - 4 * chars, 0))
                text = stream.read().decode("utf-8", "replace")
        except OSError:
            continue
        tail = " ".join(text.split())[-chars:]
        if tail:
            said.append(f"{path.stem}: {tail}")
    return "the SUT's sidecars said last: " + " | ".join(said) if said else None


__all__ = ["BoundedOutput", "files_said", "take_files"]
