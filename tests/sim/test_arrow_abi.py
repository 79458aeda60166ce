"""One Arrow ABI: libsumo and pyarrow side by side (issue 19).

libsumo ships its own, renamed libarrow (``libsumo.libs/``); pyarrow loads another. Both can live
in one process only while they share an ABI, so pyproject.toml pins pyarrow to the Arrow version
libsumo was built with. Covers: the installed pyarrow's ABI equals libsumo's
``buildConfig.ARROW_SO_VERSION`` and pyproject.toml's pin admits exactly that ABI (an upgrade of
one without the other fails here, saying what to change); and in one process, with either
library loaded first, both libarrow copies are mapped and both give correct results: the
project's SUMO run and recording, SUMO writing Parquet through its libarrow that pyarrow reads
back, omega-prime (polars on pyarrow) reading the recording to the same poses as our reader, and
a pyarrow Parquet round trip of that table.
"""

from __future__ import annotations

import importlib.metadata
import json
import subprocess
import sys
import tomllib
from pathlib import Path
from typing import Any

import pytest
from packaging.requirements import Requirement

from simtest_operator.sim import sumoloading

REPO = Path(__file__).resolve().parents[2]
SCENARIO = REPO / "scenarios" / "smoke" / "hard-braking_rural_v15_thw2_d4.xosc"


def arrow_so_version(version: str) -> str:
    """Arrow's SO version of a release, as libsumo writes it: "23.0.1" -> "2300"."""
    major, minor = (int(part) for part in version.split(".")[:2])
    return f"{major}{minor:02d}"


def libsumo_arrow() -> str:
    """The Arrow SO version libsumo was built with (empty when built without Arrow)."""
    lib: Any = sumoloading.bindings()
    return str(lib.simulation.getParameter("", "buildConfig.ARROW_SO_VERSION"))


def test_pyarrow_has_the_arrow_abi_libsumo_was_built_with() -> None:
    built = libsumo_arrow()
    pyarrow = importlib.metadata.version("pyarrow")
    libsumo = importlib.metadata.version("libsumo")
    assert built, (
        f"libsumo {libsumo} reports no Arrow build (buildConfig.ARROW_SO_VERSION is empty): "
        "the pyarrow pin in pyproject.toml is no longer needed; relax it and run `uv lock`"
    )
    major = int(built) // 100
    assert arrow_so_version(pyarrow) == built, (
        f"pyarrow {pyarrow} (Arrow ABI {arrow_so_version(pyarrow)}) but libsumo {libsumo} is "
        f"built against libarrow {built}: pin pyarrow>={major},<{major + 1} in pyproject.toml "
        "and run `uv lock` (or move libsumo to a release built against pyarrow's Arrow)"
    )


def test_the_pin_admits_exactly_libsumos_arrow() -> None:
    built = libsumo_arrow()
    major, minor = int(built) // 100, int(built) % 100
    project = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    [pin] = [Requirement(d) for d in project["dependencies"] if Requirement(d).name == "pyarrow"]
    fix = f"pin pyarrow>={major},<{major + 1} in pyproject.toml and run `uv lock`"
    assert f"{major}.{minor}.0" in pin.specifier, f"{pin} excludes libsumo's Arrow {built}: {fix}"
    for other in (f"{major + 1}.0.0", f"{major - 1}.0.0"):
        assert other not in pin.specifier, f"{pin} admits Arrow {other}, not {built}: {fix}"


_CHILD = r"""
import json, sys, warnings
from pathlib import Path

order, scenario, work = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
if order == "pyarrow-first":
    import pyarrow.parquet

from simtest_operator.recording import read_trajectories
from simtest_operator.runner import scenario_execution

report = scenario_execution.run_scenario(
    scenario_execution.RunRequest(
        scenario=scenario, nets_dir=work / "nets", output_dir=work / "out"
    )
)
outcome = report.outcome
ours = {
    str(idx): [[s.t, s.x, s.y] for s in samples]
    for idx, samples in read_trajectories(Path(outcome.artifacts["recording"])).items()
}

# SUMO itself writes Parquet through its own libarrow; libsumo's API gives the truth to compare.
import libsumo

net = next((work / "nets").glob("*.net.xml"))
libsumo.start(["sumo", "-n", str(net), "--fcd-output", str(work / "fcd.parquet"),
               "--no-step-log", "true", "--no-warnings", "true"])
edge = next(e for e in libsumo.edge.getIDList() if not e.startswith(":"))
libsumo.route.add("r", [edge])
libsumo.vehicle.add("v", "r", departSpeed="10")
seen = []
for _ in range(20):
    libsumo.simulationStep()
    if "v" in libsumo.vehicle.getIDList():
        seen.append([libsumo.simulation.getTime(), *libsumo.vehicle.getPosition("v")])
libsumo.close()

import pyarrow as pa
import pyarrow.parquet as pq

fcd = pq.read_table(work / "fcd.parquet").to_pydict()
written = [list(row) for row in zip(fcd["timestep_time"], fcd["vehicle_x"], fcd["vehicle_y"])]

with warnings.catch_warnings():
    warnings.simplefilter("ignore", DeprecationWarning)
    import omega_prime

    recording = omega_prime.Recording.from_file(
        outcome.artifacts["recording"], validate=True, parse_map=True, apply_proj=False
    )
table = recording.df.select("total_nanos", "idx", "x", "y").to_arrow()
sink = pa.BufferOutputStream()
pq.write_table(table, sink)
back = pq.read_table(pa.BufferReader(sink.getvalue()))
with open("/proc/self/maps", encoding="utf-8") as maps:
    arrow = sorted({Path(line.split()[-1]).name for line in maps if "/libarrow" in line})
print(json.dumps({
    "verdict": outcome.verdict.value, "reason": outcome.reason, "ours": ours,
    "omega": back.to_pylist(), "round_trip_equal": back.equals(table),
    "sumo_api": seen, "sumo_parquet": written, "libarrow": arrow,
}))
"""


@pytest.mark.slow
@pytest.mark.parametrize("order", ["libsumo-first", "pyarrow-first"])
def test_libsumo_and_pyarrow_work_in_one_process(order: str, tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-c", _CHILD, order, str(SCENARIO), str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=240,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    data = json.loads(done.stdout.strip().splitlines()[-1])
    # Two Arrow libraries in the process: libsumo's renamed copy and pyarrow's own.
    assert any(name.startswith("libarrow-") for name in data["libarrow"]), data["libarrow"]
    assert any(name.startswith("libarrow.so") for name in data["libarrow"]), data["libarrow"]
    assert data["verdict"] == "Passed", data["reason"]
    # omega-prime (polars and pyarrow) reads the recording to exactly our reader's poses.
    ours = {
        (int(idx), round(t * 1e9)): (x, y)
        for idx, samples in data["ours"].items()
        for t, x, y in samples
    }
    omega = {(row["idx"], row["total_nanos"]): (row["x"], row["y"]) for row in data["omega"]}
    assert len(ours) == 2 * 101 and omega.keys() == ours.keys()
    for key, (x, y) in ours.items():
        assert omega[key] == pytest.approx((x, y), abs=1e-9)
    assert data["round_trip_equal"]
    # SUMO's Parquet (its libarrow) read by pyarrow equals what libsumo's API reported.
    # (FCD stamps a step with its begin time; getTime() after the 1 s step is its end.)
    written = {round(t + 1.0, 6): (x, y) for t, x, y in data["sumo_parquet"]}
    assert len(data["sumo_api"]) >= 15
    for t, x, y in data["sumo_api"]:
        assert written[round(t, 6)] == pytest.approx((x, y), abs=1e-6)
