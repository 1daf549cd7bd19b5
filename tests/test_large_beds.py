"""Start-up of large beds in memory linear in N: the neighbour lists are allocated from host cell
lists (the same lists as the JAX engine's all-pairs build, entry for entry) and the initial forces are evaluated over
them, never over all N² pairs (which took 4.9 GB at 5000 grains and failed at 20 000)."""

import json
import subprocess
import sys
import tracemalloc

import jax.numpy as jnp
import numpy as np

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.packing import fcc_lattice
from jaxdamp.physics.model import build


def _bed(n, seed=0):
    """The thesis damper scaled to ``n`` grains (base grown at the preset's grains per area):
    model, params and the lattice positions of its grains."""
    side = 0.03675 * (n / 250) ** 0.5
    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          {"grains.0.count": n, "box.Lx": side, "box.Ly": side})
    model, params = build(cfg)
    return model, params, fcc_lattice(np.asarray(params.radius), cfg, seed)


def test_host_lists_are_the_traced_all_pairs_lists():
    """The cell-list allocation lists exactly what the JAX engine's all-pairs build lists, in the same
    order, for a mixture (size-aware cutoff) in two systems: a random gas and a dense one."""
    mix = presets.family("varela2023-b", 0.5)
    m, p = build(mix)
    rng = np.random.default_rng(1)
    pos = jnp.asarray(rng.uniform(0, [mix.box.Lx, mix.box.Ly, 0.03], (2, m.n, 3))
                      * np.array([[[1, 1, 1]], [[1, 1, 0.4]]]))
    new = nb.allocate(m, pos, 1.5, radius=p.radius)
    ref = nb._build(m, nb.capacity(new), pos, nb._radius_array(m, pos, p.radius))
    np.testing.assert_array_equal(np.asarray(new.idx), np.asarray(ref.idx))
    assert not np.asarray(new.overflow).any() and not np.asarray(ref.overflow).any()
    assert (np.asarray(new.idx) < m.n).sum() > 300  # it lists pairs
    # a capacity too small is flagged as overflow, as by the traced build
    model, params, r = _bed(250)
    pts = nb._with_radius(model, jnp.asarray(r)[None], params.radius)
    _, overflow = nb._dense(model, 2, pts)
    assert overflow.all()


def test_allocation_memory_grows_linearly_with_n():
    """Peak host memory of allocating the lists (occupancy, then the dense block) for 2000 and
    8000 grains: 4× the grains take about 4× the memory (an N × N array would take 16×), and
    far less than one N × N byte array."""
    peaks = {}
    for n in (2000, 8000):
        model, params, r = _bed(n)
        pts = nb._with_radius(model, jnp.asarray(r)[None], params.radius)
        tracemalloc.start()
        cap = nb._occupancy(model, pts)
        idx, _ = nb._dense(model, cap, pts)
        peaks[n] = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert idx.shape == (1, n, cap) and cap <= 18
    assert peaks[8000] / peaks[2000] < 6, peaks
    assert peaks[8000] < 8000**2 / 4, peaks


def test_start_up_of_6000_grains_stays_small():
    """`driver.start` of a 6000-grain bed (lists, initial forces) in a fresh process peaks
    below 1 GB; over all pairs the initial forces alone needed several GB."""
    code = """
import json, resource, sys
import numpy as np
sys.path.insert(0, "tests")
from test_large_beds import _bed
from jaxdamp.engine import driver, neighbors as nb
model, params, r = _bed(6000)
q = np.zeros((model.n, 4)); q[:, 0] = 1.0
zero = np.zeros((model.n, 3))
b = driver.start(model, driver.batched(params), r[None], zero[None], zero[None], q[None],
                 np.zeros(1), np.zeros(1), engine="jax")
f = np.asarray(b.states.a)[0]
# the peak of this process's own memory: VmHWM (ru_maxrss would include the RSS of the
# forking parent, the test process, which Linux carries over through exec)
hwm = [int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmHWM")]
peak = hwm[0] * 1024 if hwm else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps([peak / 1024**3, nb.capacity(b.nbrs), bool(np.isfinite(f).all())]))
"""
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=300, check=False)
    assert p.returncode == 0, p.stderr[-2000:]
    peak_gb, capacity, finite = json.loads(p.stdout.strip().splitlines()[-1])
    assert finite and capacity <= 20
    assert peak_gb < 1.0, peak_gb
