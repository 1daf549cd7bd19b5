"""``benchmarks/device_check.py`` stays runnable: its quick mode on the CPU agrees with itself,
times every path and writes the JSON that records a device's crossover."""

import json
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.mark.slow  # not in CI (its time budget); its thesis-scan sibling stays
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
    assert c["fused"] == {} and c["fused_from"] is None  # not timed without a GPU
    assert "fused: not timed" in done.stdout


@pytest.mark.long
def test_device_check_times_the_thesis_scan_as_one_command(tmp_path):
    """``--scan-only --quick``: the scan's command (``jaxdamp frf``, 3 × 2 × 2 systems, 50 ms)
    runs, and its wall time is split into settling and driving and projected to 5 s."""
    out = tmp_path / "scan.json"
    done = subprocess.run([sys.executable, os.path.join(ROOT, "benchmarks", "device_check.py"),
                           "--scan-only", "--quick", "--scan-duration", "0.05", "--json",
                           str(out)], capture_output=True, text=True, timeout=900, check=False,
                          cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    scan = json.loads(out.read_text())["scan"]
    assert "error" not in scan, scan
    assert scan["systems"] == 12 and scan["engine"] == "native"
    assert 0 < scan["driving_s"] < scan["wall_s"]
    assert scan["projected_5s_min"] * 60 > scan["wall_s"]
