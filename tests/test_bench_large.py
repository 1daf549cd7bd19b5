"""``benchmarks/bench_large.py``: the scaled bed, the warm-state cache, the step choice, the
LAMMPS deck of a scaled bed and the summary's arithmetic, at N = 300 without running LAMMPS
or timing anything (a few seconds: one evaluation of the initial forces)."""

import dataclasses
import math
import os
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "benchmarks"))

import bench_large as bg  # noqa: E402

from jaxdamp.cases import presets  # noqa: E402
from jaxdamp.config import ConfigError  # noqa: E402


def test_scaled_bed_keeps_the_grains_per_area_and_is_the_driven_box():
    """N = 300: the base side is 0.03675 m × sqrt(300/250) (the preset's grains per base area,
    same depth), the primary scaled by N/250, the box driven at 3 cm and 15 Hz, and the
    settling, engine and precision as asked."""
    ref = presets.get("sanchez2012-optimal")
    cfg = bg.bed_config(300, 0.02, "jax", "float32")
    assert cfg.n_grains == 300 and cfg.system == "driven"
    assert cfg.box.Lx == cfg.box.Ly == pytest.approx(0.03675 * math.sqrt(1.2), rel=1e-5)
    assert cfg.box.Lz == ref.box.Lz
    per_area = ref.n_grains / (ref.box.Lx * ref.box.Ly)
    assert 300 / (cfg.box.Lx * cfg.box.Ly) == pytest.approx(per_area, rel=2e-5)
    assert cfg.primary.M == pytest.approx(ref.primary.M * 1.2, rel=1e-5)
    assert cfg.primary.K == pytest.approx(ref.primary.K * 1.2, rel=1e-5)
    assert (cfg.frequency, cfg.drive.amplitude) == (15.0, 0.03)
    assert cfg.numerics.settle_time == 0.02
    assert (cfg.numerics.engine, cfg.numerics.precision) == ("jax", "float32")
    assert cfg.grains == (dataclasses.replace(ref.grains[0], count=300),)  # same grains


def test_native_in_float32_is_refused_by_name():
    with pytest.raises(ConfigError, match="numerics.precision"):
        bg.bed_config(300, 0.02, "native", "float32")


def test_cache_key_follows_the_warm_up():
    a = bg.bed_config(300, 0.03)
    key = bg.cache_key(a, 0.04, 100)
    assert key == bg.cache_key(bg.bed_config(300, 0.03), 0.04, 100)
    others = {bg.cache_key(bg.bed_config(301, 0.03), 0.04, 100),
              bg.cache_key(bg.bed_config(300, 0.02), 0.04, 100),
              bg.cache_key(bg.bed_config(300, 0.03, "jax"), 0.04, 100),
              bg.cache_key(a, 0.05, 100), bg.cache_key(a, 0.04, 50)}
    assert key not in others and len(others) == 5
    assert os.path.basename(bg.cache_path("/c", a, 0.04, 100)) == f"large_N300_{key}.npz"


def test_warm_state_round_trip_and_lammps_deck(tmp_path):
    """A real state of the scaled bed (its lattice, initial forces) stored and read back bit
    for bit (another key: nothing), and its LAMMPS deck: 300 grains in the scaled box, the
    asked number of steps."""
    import jax

    from jaxdamp.engine import driver
    from jaxdamp.engine.packing import poured
    from jaxdamp.physics.model import build

    cfg = bg.bed_config(300, 0.0)
    model, params = build(cfg)
    r = poured(params, model, cfg, 0)
    q = np.zeros((model.n, 4))
    q[:, 0] = 1.0
    zero = np.zeros((1, model.n, 3))
    b = driver.start(model, driver.batched(params), r[None], zero, zero, q[None], np.zeros(1),
                     np.zeros(1), engine="jax")
    st = jax.tree_util.tree_map(lambda x: np.asarray(x)[0], b.states)
    path = str(tmp_path / "c" / "s.npz")
    bg.save_state(path, st, dict(key="k1", settle_wall=1.0))
    got, meta = bg.load_state(path, "k1")
    assert meta["settle_wall"] == 1.0
    for f in dataclasses.fields(st):
        a, c = np.asarray(getattr(st, f.name)), getattr(got, f.name)
        assert a.dtype == c.dtype and np.array_equal(a, c), f.name
    assert bg.load_state(path, "k2") is None
    assert bg.load_state(str(tmp_path / "none.npz"), "k1") is None

    deck = bg.bl.lammps_input(cfg, params, st, 700, str(tmp_path))
    text = open(deck).read()
    assert text.rstrip().endswith("run 700")
    data = open(tmp_path / "bed.data").read()
    assert "300 atoms" in data
    xlo, xhi = next(ln for ln in data.splitlines() if ln.endswith("xlo xhi")).split()[:2]
    assert float(xhi) - float(xlo) == pytest.approx(cfg.box.Lx + 0.002, rel=1e-12)


def test_steps_scale_as_one_over_n():
    """At a cost per step proportional to N, 4× the grains get a quarter of the steps (in
    whole records), never fewer than one record."""
    every = 100
    s1 = bg.steps_for(1000 * 50e-9, 4.0, every)
    s4 = bg.steps_for(4000 * 50e-9, 4.0, every)
    assert s1 == 80000 and s4 == 20000 and s1 % every == 0
    assert bg.steps_for(10**7 * 50e-9, 4.0, every) == every
    with pytest.raises(ValueError, match="positive"):
        bg.steps_for(0.0, 4.0, every)
    assert bg.ns_per_particle_step(2.0, 1000, 4000) == pytest.approx(500.0)


def test_summary_takes_the_best_of_the_rounds_and_each_rounds_ratio():
    rows = {1000: {bg.JD: [40.0, 30.0], bg.L1: [60.0, 66.0], bg.L2: [45.0, 48.0]},
            4000: {bg.JD: [35.0, 45.0], bg.L1: [70.0, 63.0], bg.L2: [50.0, 60.0]}}
    s = bg.summarise(rows, [1000, 4000])
    assert s[1000]["best"] == {bg.JD: 30.0, bg.L1: 60.0, bg.L2: 45.0}
    assert s[1000]["lammps2_over_jaxdamp"] == pytest.approx(1.5)
    assert s[1000]["lammps2_over_jaxdamp_per_round"] == pytest.approx([45 / 40, 48 / 30])
    assert s[4000]["lammps1_over_jaxdamp"] == pytest.approx(63 / 35)
    assert s[1000]["relative"] == 1.0 and s[4000]["relative"] == pytest.approx(35 / 30)
    lines = bg.table(s, [1000, 4000], 1000)
    assert lines[2] == "| 1000 | 30 | 60 | 45 | 1.50 (1.12, 1.60) | 1 |"
    # no LAMMPS: its columns are dashes
    s = bg.summarise({1000: {bg.JD: [30.0]}}, [1000])
    assert bg.table(s, [1000], 1000)[2] == "| 1000 | 30 | - | - | - | 1 |"
    mem = bg.memory_table({1000: dict(self_kb=300_000, lammps_kb=20_000),
                           4000: dict(self_kb=330_000, lammps_kb=26_000)}, [1000, 4000],
                          rss0=250_000)
    assert mem[2] == "| 1000 | 293 | 50 | 19.5 | - |"
    assert mem[3] == "| 4000 | 322 | 10 | 25.4 | 2 |"
