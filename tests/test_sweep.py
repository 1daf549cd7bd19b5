"""Batched sweeps: FRF of the empty box and its fit, sharding, resume."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from jaxdamp.analysis.response import fit_frf, frf_amplitude
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.studies.sweep import sweep

SMALL = ["grains.0.count=20", "numerics.duration=0.04", "numerics.chunk=0.01",
         "numerics.settle_time=0.05", "numerics.record_dt=1e-3"]


def test_empty_box_frf_fit_recovers_mass_and_damping():
    """A 10-frequency sweep of the empty box (one batch) matches the analytic FRF to 1e-4 and
    the least-squares fit with U, K fixed recovers M and C within 1 %."""
    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          ["grains=[]", "primary.C=26.3", "numerics.duration=2.5",
                           "numerics.chunk=0.5", "numerics.analysis_window=0.12"])
    f = np.linspace(8, 25, 10)
    res = sweep(cfg, {"frequency": f}, progress=False, echo=None)
    p = cfg.primary
    Z = res.summary["amplitude"]
    assert np.max(np.abs(Z / frf_amplitude(f, p.M, p.K, p.C, p.U) - 1)) < 1e-4
    M, C, dM, dC = fit_frf(f, Z, p.U, p.K, M0=2.0, C0=15.0)
    assert M == pytest.approx(p.M, rel=0.01) and C == pytest.approx(p.C, rel=0.01)
    assert dM < 0.01 * M and dC < 0.01 * C


def _small_grid():
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), SMALL + ["numerics.engine='jax'"])
    return cfg, {"frequency": [12.0, 15.0, 18.0], "box.Lz": [0.05, 0.08]}


SHARD_SCRIPT = """
import json, sys, numpy as np
import jax
assert len(jax.devices()) == 4, jax.devices()
sys.path.insert(0, {tests!r})
import h5py
from test_sweep import _small_grid
from jaxdamp.config import apply_overrides
from jaxdamp.studies.sweep import sweep
cfg, axes = _small_grid()
cfg = apply_overrides(cfg, ["numerics.engine={engine!r}", "tangential_law={law!r}"])
a = sweep(cfg, axes, progress=False, echo=None, shard=True, out={out!r})
b = sweep(cfg, axes, progress=False, echo=None, shard=False)
with h5py.File({out!r}) as h:
    used = (h.attrs["engine"], int(h.attrs["devices"]))
out = {{"amplitude": float(np.max(np.abs(a.summary["amplitude"] - b.summary["amplitude"])))}}
out["used"] = used
# killed after 2 of 4 chunks and resumed, sharded: bit-identical to the uninterrupted run
assert sweep(cfg, axes, progress=False, echo=None, shard=True, out={out!r} + ".part",
             max_chunks=2) is None
c = sweep(cfg, axes, progress=False, echo=None, shard=True, out={out!r} + ".part", resume=True)
out["resumed"] = float(np.max(np.abs(c.records["work"] - a.records["work"])))
out["z_cm"] = float(np.max(np.abs(a.records["z_cm"] - b.records["z_cm"])))
out["work"] = float(np.max(np.abs(a.records["work"] - b.records["work"])))
out["loss"] = a.records["work"][:, -1, 2:6].sum(axis=1).tolist()
print("RESULT", json.dumps(out))
"""


@pytest.mark.long
@pytest.mark.parametrize("engine, law", [
    ("jax", "viscous"), ("native", "viscous"),
    pytest.param("native", "mindlin", marks=pytest.mark.slow)])  # slow: CI's time budget
def test_sharded_sweep_equals_unsharded(engine, law, tmp_path):
    """4 forced host devices: the 6-point grid (padded to 8) sharded over them gives the same
    numbers as the unsharded batch, on either engine — the native one runs its kernel on
    every device's shard (the file records the engine that ran and the device count), with
    the tangential springs too (their rows rekeyed per shard) — and a sharded sweep killed
    halfway resumes bit-identically."""
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=4")
    code = SHARD_SCRIPT.format(tests=os.path.dirname(__file__), engine=engine, law=law,
                               out=str(tmp_path / "sharded.h5"))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    res = json.loads(out.stdout.split("RESULT", 1)[1])
    assert res["used"] == [engine, 4] and res["resumed"] == 0.0
    assert res["amplitude"] < 1e-12 and res["z_cm"] < 1e-12
    assert min(res["loss"]) > 0  # the grains collided and rubbed in every point
    assert res["work"] <= 1e-9 * max(res["loss"])


@pytest.mark.long  # 56 s on 2 cores: CI's second step
def test_killed_sweep_resumes_without_recomputing(tmp_path):
    cfg, axes = _small_grid()
    full = sweep(cfg, axes, progress=False, echo=None)
    path = str(tmp_path / "sw.h5")
    assert sweep(cfg, axes, out=path, progress=False, echo=None, max_chunks=2) is None
    import h5py

    with h5py.File(path) as h:
        assert h.attrs["status"] == "partial" and h["checkpoint"].attrs["chunk"] == 2
    messages = []
    res = sweep(cfg, axes, out=path, resume=True, progress=False, echo=messages.append)
    assert any("resuming sweep at chunk 2/4" in m for m in messages)
    np.testing.assert_array_equal(res.summary["amplitude"], full.summary["amplitude"])
    np.testing.assert_array_equal(res.records["z_cm"], full.records["z_cm"])
    assert res.summary["amplitude"].shape == (3, 2)


@pytest.mark.long  # 32 s on 2 cores: CI's second step
def test_reuse_or_run_reads_back_resumes_or_replaces(tmp_path):
    """Experiments' raw sweeps: a finished file of the same sweep is read back without
    computing (same results, its compute time kept), a partial one is resumed, a file holding
    another sweep is replaced."""
    import h5py

    from jaxdamp.studies.sweep import holds, reuse_or_run

    cfg, axes = _small_grid()
    path = str(tmp_path / "raw.h5")
    assert not holds(path, cfg, axes)
    assert sweep(cfg, axes, out=path, progress=False, echo=None, max_chunks=3) is None
    assert holds(path, cfg, axes)
    msgs = []
    first = reuse_or_run(cfg, axes, path, progress=False, echo=msgs.append)
    # the engine the file was written with, kept (jaxdamp.engine.choice.stored_choice)
    stored = "engine jax (as stored in the file: numerics.engine = 'jax')"
    assert msgs == [stored, "resuming sweep at chunk 3/4"]
    with h5py.File(path) as h:
        assert h.attrs["status"] == "finished" and h.attrs["engine"] == "jax"
    msgs.clear()
    again = reuse_or_run(cfg, axes, path, progress=False, echo=msgs.append)
    assert msgs == [stored, "resuming sweep at chunk 4/4"]  # nothing left to compute
    np.testing.assert_array_equal(again.summary["amplitude"], first.summary["amplitude"])
    assert again.summary["wall_time"] >= first.summary["wall_time"] > 0
    other = {k: v[:1] for k, v in axes.items()}
    assert not holds(path, cfg, other)
    msgs.clear()
    res = reuse_or_run(cfg, other, path, progress=False, echo=msgs.append)
    assert not any("resuming" in m for m in msgs) and res.summary["amplitude"].shape == (1, 1)
    assert holds(path, cfg, other) and not holds(path, cfg, axes)


@pytest.mark.long  # ~30 s: runs in CI's second step (examples or long)
def test_sweep_in_waves_equals_one_batch_and_resumes(tmp_path, monkeypatch):
    """A sweep too large for memory runs in waves by itself (here: the memory this process may
    use cut to hold two systems): 2 frequencies × 2 replicates in 2 waves give the samples,
    summaries, steady-state estimates, settling and snapshots of the one batch, bit for bit
    (each system's trajectory does not depend on its batch); killed inside the second wave it
    resumes there, bit-identically; the result's records are read from the file."""
    import h5py

    from jaxdamp.engine import budget
    from jaxdamp.io.sweepfile import StoredRecords, describe_lines
    from jaxdamp.physics.model import config_dt, grain_radii
    from jaxdamp.studies.runner import batch_budget, schedule

    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          SMALL + ["numerics.engine='native'"])
    axes = {"frequency": [12.0, 18.0]}
    kw = dict(progress=False, echo=None, replicates=2, snapshots=2)
    one = sweep(cfg, axes, **kw)
    sched = schedule(cfg, config_dt(cfg, grain_radii(cfg)))
    per = [batch_budget(cfg, sched, n, "x.h5").memory for n in (1, 2, 3)]
    monkeypatch.setattr(budget, "available_memory",
                        lambda: (per[1] + 0.5 * (per[2] - per[1])) / budget.MEMORY_FRACTION)
    said = []
    path = str(tmp_path / "waves.h5")
    res = sweep(cfg, axes, out=path, **dict(kw, echo=said.append))
    assert any("4 systems in 2 waves of 2" in m for m in said)
    assert isinstance(res.records, StoredRecords)
    for k in ("t", "z_box", "work", "z_cm"):
        np.testing.assert_array_equal(np.asarray(res.records[k]), one.records[k])
    np.testing.assert_array_equal(res.records["work"][3], one.records["work"][3])
    for k in one.summary:
        if k != "wall_time":
            np.testing.assert_array_equal(res.summary[k], one.summary[k])
    for q in one.steady:
        np.testing.assert_array_equal(res.steady[q]["mean"], one.steady[q]["mean"])
    for k in ("r", "z_box"):
        np.testing.assert_array_equal(res.snapshots[k], one.snapshots[k])
    with h5py.File(path) as h:
        assert h.attrs["wave_size"] == 2 and h.attrs["status"] == "finished"
        assert h["settle/bed_height"].shape == (4,) and np.isfinite(h["settle/time"][()]).all()
        assert h["checkpoint"].attrs["wave"] == 1
    # killed inside the second wave (4 chunks per wave), resumed there
    part = str(tmp_path / "part.h5")
    assert sweep(cfg, axes, out=part, max_chunks=5, **kw) is None
    with h5py.File(part) as h:
        assert h["checkpoint"].attrs["wave"] == 1 and h["checkpoint"].attrs["chunk"] == 1
        lines = describe_lines(h, part)
    assert "  run in 2 waves of 2 systems" in lines
    assert any("checkpoint after chunk 1 of wave 2/2 (resumable" in x for x in lines)
    said.clear()
    again = sweep(cfg, axes, out=part, resume=True, **dict(kw, echo=said.append))
    assert any("resuming sweep at chunk 1/4 of wave 2/2" in m for m in said)
    np.testing.assert_array_equal(np.asarray(again.records["work"]), one.records["work"])
    np.testing.assert_array_equal(again.summary["amplitude"], one.summary["amplitude"])


def test_wave_must_hold_whole_grid_points():
    cfg, axes = _small_grid()
    with pytest.raises(Exception, match="wave = 3: a wave holds whole grid points"):
        sweep(cfg, axes, replicates=2, wave=3, progress=False, echo=None)
