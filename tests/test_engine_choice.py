"""The engine chosen by workload (``numerics.engine = "auto"``, :mod:`jaxdamp.engine.choice`):
the rule on every kind of machine, the measured crossover, and the choice printed, stored in
run and sweep files and kept by ``--resume``."""

import h5py
import pytest
from helpers import small_config

from jaxdamp import cli
from jaxdamp.engine import choice
from jaxdamp.engine.choice import Choice, Crossover, choose, stored_choice
from jaxdamp.studies.runner import run

GPU = dict(backend="gpu", device_kind="NVIDIA H200", have_native=True)


def test_an_explicit_engine_wins_everywhere():
    for backend in ("cpu", "gpu"):
        for b in (1, 10**6):
            c = choose("jax", "float64", b, backend=backend, device_kind="x", have_native=True)
            assert c == Choice("jax", "numerics.engine = 'jax'")
            assert choose("native", "float64", b, backend=backend, device_kind="x",
                          have_native=True).engine == "native"
    with pytest.raises(ValueError, match="native kernel computes in float64"):
        choose("native", "float32")
    with pytest.raises(ValueError, match="fused kernel computes in float64"):
        choose("fused", "float32")
    with pytest.raises(ValueError, match="expected one of"):
        choose("warp", "float64")
    assert choose("fused", "float64", 1, backend="cpu", device_kind="cpu").engine == "fused"


def test_auto_on_a_cpu_is_the_native_kernel_at_every_batch():
    for b in (1, 32, 100_000):
        assert choose("auto", "float64", b, backend="cpu", device_kind="cpu",
                      have_native=True) == Choice("native", "auto: JAX runs on the CPU")
    assert choose("auto", "float64", 1, backend="cpu", device_kind="cpu",
                  have_native=False).engine == "jax"
    assert choose("auto", "float32", 1, backend="cpu", device_kind="cpu",
                  have_native=True).engine == "jax"


def test_auto_on_the_measured_h200_is_native_in_float64_and_the_device_in_float32():
    """On the H200 of issue 32 the native kernel on 16 host cores (0.71-1.05 µs per
    system-step at batch 32-1024) beat the XLA step (0.82-3.29) at every batch measured:
    float64 stays on the host, one system included; float32 has only the device."""
    rec = choice.MEASURED["NVIDIA H200"]
    assert rec.float64_from is None
    assert all(rec.native[b] < rec.xla[b] for b in rec.native if b in rec.xla)
    for b in (1, 32, 4096, 16384, 10**6):
        c = choose("auto", "float64", b, **GPU)
        assert c.engine == "native" and "measured on this device" in c.reason
        assert choose("auto", "float32", b, **GPU).engine == "jax"


def test_auto_switches_at_a_recorded_crossover_and_names_a_borrowed_measurement(monkeypatch):
    monkeypatch.setitem(choice.MEASURED, "Fast GPU 9000", Crossover(
        "Fast GPU 9000", 8, {1024: 0.5}, {1024: 0.6}, 1024, "test"))
    gpu = dict(backend="gpu", device_kind="Fast GPU 9000", have_native=True)
    assert choose("auto", "float64", 1023, **gpu).engine == "native"
    c = choose("auto", "float64", 1024, **gpu)
    assert c.engine == "jax" and "1024" in c.reason and "measured on this device" in c.reason
    # a device without its own record uses the nearest name, and says so
    c = choose("auto", "float64", 4096, backend="gpu", device_kind="Fast GPU 9100",
               have_native=True)
    assert c.engine == "jax" and "measured on Fast GPU 9000, not on this Fast GPU 9100" in c.reason
    assert choice.nearest("NVIDIA H100 80GB HBM3") == (choice.MEASURED["NVIDIA H200"], False)


def test_auto_takes_the_fused_step_where_it_was_measured_and_can_run(monkeypatch):
    """A device whose record has a fused crossover (``fused_from``, written by
    benchmarks/device_check.py only where the fused step agreed with the CPU): the native
    kernel below it, the fused step from it when numba-cuda finds a GPU, else the rule without
    it (here the XLA step from its own crossover)."""
    monkeypatch.setitem(choice.MEASURED, "Fast GPU 9000", Crossover(
        "Fast GPU 9000", 8, {1024: 0.5}, {1024: 0.6, 256: 0.7}, 1024, "test",
        fused={256: 0.3, 1024: 0.1}, fused_from=256))
    gpu = dict(backend="gpu", device_kind="Fast GPU 9000", have_native=True)
    assert choose("auto", "float64", 255, have_fused=True, **gpu).engine == "native"
    c = choose("auto", "float64", 256, have_fused=True, **gpu)
    assert c.engine == "fused" and "256" in c.reason and "fused" in c.reason
    assert choose("auto", "float64", 256, have_fused=False, **gpu).engine == "native"
    assert choose("auto", "float64", 4096, have_fused=False, **gpu).engine == "jax"
    assert choose("auto", "float32", 4096, have_fused=True, **gpu).engine == "jax"
    # the H200's record has no fused measurement yet: auto never picks it there
    assert choice.MEASURED["NVIDIA H200"].fused_from is None
    assert choose("auto", "float64", 10**6, have_fused=True, **GPU).engine == "native"


def test_resume_keeps_the_engine_stored_in_the_file(tmp_path):
    """The run file stores the engine and why; ``--resume`` continues on the stored engine
    (bit-identical continuation needs the same engine) and says so."""
    cfg = small_config()
    path = tmp_path / "part.h5"
    said = []
    run(cfg, out=str(path), progress=False, echo=said.append, max_chunks=1)
    assert "engine native (auto: JAX runs on the CPU)" in said
    with h5py.File(path, "a") as h:
        assert h.attrs["engine"] == "native"
        assert h.attrs["engine_reason"] == "auto: JAX runs on the CPU"
        h.attrs["engine_reason"] = "auto: chosen on another machine"
    said.clear()
    run(cfg, out=str(path), resume=True, progress=False, echo=said.append)
    assert any("engine native (as stored in the file: auto: chosen on another machine)" in s
               for s in said), said
    assert stored_choice({}, Choice("jax", "now")) == Choice("jax", "now")  # an older file


def test_info_devices_lists_the_devices_and_the_choice_by_batch(capsys):
    assert cli.main(["info", "--devices", "--batch", "1", "--batch", "2400"]) == 0
    text = capsys.readouterr().out
    assert "default backend cpu" in text and "cpu:0" in text
    assert "float64, batch      1: native" in text and "float64, batch   2400: native" in text
    assert "float32, batch   2400: jax" in text and "precision:" in text
    assert cli.main(["info"]) == 2
    assert "give a FILE.h5 to summarise, or --devices" in capsys.readouterr().err
