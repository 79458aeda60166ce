"""Local component processes: start with a log file, recognise, stop, read log tails.

A started process is remembered as a :class:`ProcessRecord` (pid plus the kernel's start time of
that pid), so a later ``down`` — possibly from another shell — stops exactly the processes this
cluster started and never a stranger that happens to reuse a pid. Linux only (reads ``/proc``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import shutil
import signal
import socket
import subprocess
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from simtest_operator.errors import ClusterError


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ProcessRecord:
    """One started component process."""

    name: str
    pid: int
    start_ticks: int
    """Field 22 of ``/proc/<pid>/stat`` right after start: tells a reused pid apart."""
    argv: tuple[str, ...]
    log: Path


def _start_ticks(pid: int) -> int | None:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    # The command name (field 2) may contain spaces; fields after it are split safely.
    rest = stat.rsplit(")", 1)[1].split()
    if rest[0] == "Z":  # a zombie has exited; only its parent's wait is missing
        return None
    return int(rest[19])


def is_alive(record: ProcessRecord) -> bool:
    """Whether the recorded process is still running (and is still the same process)."""
    return _start_ticks(record.pid) == record.start_ticks


def spawn(
    name: str,
    argv: Sequence[str],
    *,
    log: Path,
    env: Mapping[str, str] | None = None,
    detach: bool = False,
) -> tuple[ProcessRecord, subprocess.Popen[bytes] | None]:
    """Start ``argv`` in a new session with stdout and stderr appended to ``log``.

    By default the process is our child and gets SIGTERM when we die (``PR_SET_PDEATHSIG``, set
    by util-linux ``setpriv`` before it execs the command; without ``setpriv`` this safety net is
    missing), so a killed test run cannot leak a control plane. With ``detach`` it is started
    through a short-lived ``sh`` and re-parented to init: it outlives the CLI call that started
    it, and no ``Popen`` object is left behind (the second element is then None).
    """
    log.parent.mkdir(parents=True, exist_ok=True)
    with log.open("ab") as out:
        out.write(f"\n=== {time.strftime('%Y-%m-%dT%H:%M:%S')} start: {' '.join(argv)}\n".encode())
        out.flush()
        common: dict[str, Any] = {
            "stdin": subprocess.DEVNULL,
            "stderr": out,
            "start_new_session": True,  # no terminal signals (Ctrl-C in the shell that ran `up`)
            "env": None if env is None else dict(env),
        }
        if detach:
            launcher = subprocess.run(
                ["sh", "-c", 'exec "$@" >&2 & echo $!', "sh", *argv],
                stdout=subprocess.PIPE,
                check=True,
                **common,
            )
            pid, proc = int(launcher.stdout), None
        else:
            setpriv = shutil.which("setpriv")
            tie = [setpriv, "--pdeathsig", "TERM", "--"] if setpriv else []
            proc = subprocess.Popen([*tie, *argv], stdout=out, **common)
            pid = proc.pid
    ticks = _start_ticks(pid)
    record = ProcessRecord(name=name, pid=pid, start_ticks=ticks or -1, argv=tuple(argv), log=log)
    return record, proc


def stop(record: ProcessRecord, *, grace: float = 10.0) -> bool:
    """SIGTERM the process, SIGKILL it after ``grace`` seconds; True if it was running."""
    if not is_alive(record):
        return False
    with contextlib.suppress(ProcessLookupError):
        os.kill(record.pid, signal.SIGTERM)
    deadline = time.monotonic() + grace
    while time.monotonic() < deadline:
        _reap(record.pid)
        if not is_alive(record):
            return True
        time.sleep(0.05)
    with contextlib.suppress(ProcessLookupError):
        os.kill(record.pid, signal.SIGKILL)
    for _ in range(100):
        _reap(record.pid)
        if not is_alive(record):
            break
        time.sleep(0.05)
    return True


def _reap(pid: int) -> None:
    """Collect the exit status if ``pid`` is our child (else it is init's job)."""
    with contextlib.suppress(ChildProcessError, OSError):
        os.waitpid(pid, os.WNOHANG)


def log_tail(path: Path, lines: int = 25) -> str:
    """The last ``lines`` lines of a log file ('' if there is none)."""
    try:
        with path.open("rb") as f:
            f.seek(0, os.SEEK_END)
            f.seek(max(0, f.tell() - 64 * 1024))
            text = f.read().decode(errors="replace")
    except OSError:
        return ""
    return "\n".join(text.splitlines()[-lines:])


def free_ports(count: int, host: str = "127.0.0.1") -> tuple[int, ...]:
    """``count`` distinct ports that are free right now on ``host``.

    Another program may still take one before the component binds it; the component then exits
    with "address already in use", which ``up`` reports with the log tail.
    """
    sockets = []
    try:
        for _ in range(count):
            s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            s.bind((host, 0))
            sockets.append(s)
        return tuple(s.getsockname()[1] for s in sockets)
    finally:
        for s in sockets:
            s.close()


def port_in_use(port: int, host: str = "127.0.0.1") -> bool:
    """Whether something already listens on ``host:port``."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((host, port))
        except OSError:
            return True
    return False


def exited_error(record: ProcessRecord, what: str) -> ClusterError:
    """The error for a component that died: names it, its log and the log's tail."""
    return ClusterError(
        f"{record.name} exited {what} (pid {record.pid}); log {record.log}:\n{log_tail(record.log)}"
    )
