"""``benchmarks/device_check.py`` stays runnable: its quick mode on the CPU agrees with itself,
times every path and writes the JSON that records a device's crossover."""

import json
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.mark.long
def test_device_check_quick_runs_and_writes_its_rows(tmp_path):
    out = tmp_path / "device.json"
    done = subprocess.run([sys.executable, os.path.join(ROOT, "benchmarks", "device_check.py"),
                           "--quick", "--json", str(out)], capture_output=True, text=True,
                          timeout=900, check=False, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    res = json.loads(out.read_text())
    assert res["info"]["backend"] == "cpu"
    paths = {(r["path"], r["precision"], r["batch"]) for r in res["rows"]}
    assert paths == {("native", "float64", 1), ("native", "float64", 2),
                     ("xla", "float64", 1), ("xla", "float64", 4),
                     ("xla", "float32", 1), ("xla", "float32", 4)}
    assert all(r["us"] > 0 for r in res["rows"])
    # on the CPU the "device" is the CPU: the XLA path is the reference itself; the native
    # kernel agrees to round-off after 100 steps of a bed in motion
    agree = {(r["path"], r["precision"]): r["max_abs_dr_m"] for r in res["agreement"]}
    assert agree[("xla", "float64")] == 0.0 and agree[("native", "float64")] < 1e-12
    c = res["crossover"]
    assert c["device_kind"] == "cpu" and set(c["native"]) == {"1", "2"}
    assert "MEASURED entry for this device" in done.stdout
