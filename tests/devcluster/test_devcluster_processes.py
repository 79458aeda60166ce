"""Process bookkeeping: ``down`` must stop exactly the processes ``up`` started.

Covers: a spawned process is alive and ``stop`` ends it; a record whose start time does not match
(a reused pid) is never signalled; a (default, tied) process ends when its parent dies, while a
detached one is not our child; the log gets the command line and the process output;
``free_ports`` gives distinct ports.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import time
from pathlib import Path

from simtest_operator.devcluster.processes import (
    ProcessRecord,
    free_ports,
    is_alive,
    log_tail,
    spawn,
    stop,
)


def test_spawn_and_stop(tmp_path: Path) -> None:
    record, proc = spawn("sleeper", ["sh", "-c", "echo hello; exec sleep 60"], log=tmp_path / "l")
    assert is_alive(record)
    deadline = time.monotonic() + 5
    while not log_tail(record.log).endswith("\nhello") and time.monotonic() < deadline:
        time.sleep(0.05)
    assert "start: sh -c" in log_tail(record.log)
    assert log_tail(record.log).endswith("hello")
    assert stop(record) is True
    proc.wait(timeout=5)  # already reaped by stop(); just settles the Popen object
    assert not is_alive(record)
    assert stop(record) is False


def test_a_reused_pid_is_left_alone(tmp_path: Path) -> None:
    record, proc = spawn("sleeper", ["sleep", "60"], log=tmp_path / "l")
    try:
        stranger = dataclasses.replace(record, start_ticks=record.start_ticks - 1)
        assert not is_alive(stranger)
        assert stop(stranger) is False
        assert proc.poll() is None
    finally:
        stop(record)
        proc.wait(timeout=5)


def test_die_with_parent(tmp_path: Path) -> None:
    pid_file = tmp_path / "pid"
    parent = f"""
import sys
from pathlib import Path
from simtest_operator.devcluster.processes import spawn
record, _ = spawn("child", ["sleep", "60"], log=Path({str(tmp_path / "l")!r}))
Path({str(pid_file)!r}).write_text(f"{{record.pid}} {{record.start_ticks}}")
"""
    subprocess.run([sys.executable, "-c", parent], check=True, timeout=30)
    pid, ticks = map(int, pid_file.read_text().split())
    child = ProcessRecord(name="child", pid=pid, start_ticks=ticks, argv=(), log=tmp_path / "l")
    deadline = time.monotonic() + 5
    while is_alive(child) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not is_alive(child)


def test_detached_process_is_not_our_child(tmp_path: Path) -> None:
    record, proc = spawn("sleeper", ["sleep", "60"], log=tmp_path / "l", detach=True)
    assert proc is None
    try:
        assert is_alive(record)
        ppid = int(Path(f"/proc/{record.pid}/stat").read_text().rsplit(")", 1)[1].split()[1])
        assert ppid != os.getpid()
    finally:
        assert stop(record) is True
    assert not is_alive(record)


def test_free_ports_are_distinct() -> None:
    ports = free_ports(6)
    assert len(set(ports)) == 6
    assert all(1024 < p < 65536 for p in ports)
