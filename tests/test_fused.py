"""The fused device step (numba-cuda) computes the same step as the JAX and native engines.

On a CPU these run the kernel in numba-cuda's CUDA simulator (tests/conftest.py sets
``NUMBA_ENABLE_CUDASIM=1``): the kernel's own Python, thread by thread, with the same scalar
forms of the physics compiled for the CPU. That tests its logic — the block's threads, its
barriers, its sums, its lists — not its lowering; :func:`test_the_kernel_compiles_for_a_device`
compiles it to PTX for an H100/H200 (numba-cuda's compiler, no GPU needed). The beds are small:
the simulator runs ~1 ms per thread and step.
"""

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from helpers import BASE_EXTRAS, STRUCTURE, mixture, mixture_bed, start

from jaxdamp.config import apply_overrides
from jaxdamp.engine import fused, native
from jaxdamp.engine.simulate import chunk_fn

pytestmark = pytest.mark.skipif(not fused.available()[0] or not native.AVAILABLE,
                                reason="numba-cuda (the cuda extra) or numba not installed")

FIELDS = ("r", "v", "w", "q", "a", "alpha", "z", "zd", "zdd", "y", "yd", "ydd", "work",
          "work_cell", "power_cell", "e_elastic", "f_box", "f_floor_lid", "n_floor", "n_lid",
          "n_side", "step", "z_max", "z_min")


def _bed(system="primary", mixing="arithmetic", law="hertz", extras=None, n=12, copies=2):
    """A small two-species bed (``n`` grains, half of each) as ``copies`` systems with
    different drive frequencies: the block index must pick each system's own rows."""
    import dataclasses

    import jax.numpy as jnp

    half = n // 2
    cfg = apply_overrides(mixture(system, mixing, law, counts=(half, n - half)), extras or {})
    model, pb, st, nbrs = start(cfg, *mixture_bed(n, spacing=0.0042))
    tile = lambda t: __import__("jax").tree_util.tree_map(  # noqa: E731
        lambda x: jnp.concatenate([x] * copies), t)
    pb, st, nbrs = tile(pb), tile(st), tile(nbrs)
    pb = dataclasses.replace(pb, omega=pb.omega * jnp.linspace(1.0, 1.5, copies))
    return model, pb, st, nbrs


def _agree(got, ref, records_got, records_ref, rtol=1e-9):
    """States to ``rtol`` (absolute floor 1e-12 of the field's scale) and samples to 10 ×
    ``rtol``: the criterion of the native kernel against the JAX engine
    (tests/test_native.py)."""
    for f in FIELDS:
        a, b = np.asarray(getattr(ref, f)), np.asarray(getattr(got, f))
        np.testing.assert_allclose(b, a, rtol=rtol,
                                   atol=1e-12 * max(1.0, np.abs(a).max(initial=0.0)), err_msg=f)
    for k in records_ref:
        a = np.asarray(records_ref[k])
        np.testing.assert_allclose(np.asarray(records_got[k]), a, rtol=10 * rtol,
                                   atol=1e-12 * max(1.0, float(np.abs(a).max(initial=0.0))),
                                   err_msg=k)


#: CI runs the driven and the cylinder case (long); the others, in the CUDA simulator half a
#: minute to two minutes each, are `slow` (CI's time budget): `pytest -m slow tests/test_fused.py`
@pytest.mark.parametrize("system, mixing, law, extras", [
    pytest.param("primary", "arithmetic", "hertz", {}, marks=pytest.mark.slow),
    pytest.param("driven", "harmonic", "hertz", {}, marks=pytest.mark.long),
    pytest.param("driven", "geometric", "hertz", {}, marks=pytest.mark.slow),
    pytest.param("primary", "harmonic", "linear", {}, marks=pytest.mark.slow),
    pytest.param("primary", "arithmetic", "hertz", BASE_EXTRAS, marks=pytest.mark.slow),
    pytest.param("primary", "arithmetic", "hertz", STRUCTURE, marks=pytest.mark.slow),
    pytest.param("primary", "arithmetic", "hertz", ["container.shape=cylinder",
                                                    "container.radius=0.012",
                                                    "container.Lz=0.02"],
                 marks=pytest.mark.long),
])
def test_fused_equals_native_on_a_mixture(system, mixing, law, extras):
    """Two species, friction, rotation (three spins too fast for the series), both mounts and
    a structure, all mixing rules, both contact laws, random + shock base motion, the box and
    the cylinder; two systems in two blocks: states and samples agree with the native kernel
    (itself checked against the JAX engine, tests/test_native.py) to round-off after 600
    steps, through the production chunk."""
    model, pb, st, nbrs = _bed(system, mixing, law, extras)
    out = {e: chunk_fn(model, 6, 100, engine=e)(st, nbrs, pb) for e in ("native", "fused")}
    (sa, _, ra), (sb, _, rb) = out["native"], out["fused"]
    work = np.asarray(sa.work)
    assert (work[:, 2] > 0).all() and (work[:, 4] > 0).all()  # pair and wall contacts
    assert np.ptp(np.asarray(sa.zd)) > 0  # the two systems differ (their frequencies)
    _agree(sb, sa, rb, ra)


def test_threads_arriving_together_share_the_blocks_arrays(monkeypatch):
    """numba-cuda's simulator looks up a block's shared array and stores a new one without a
    lock; with the lookup made slow (as on a loaded machine) every thread would get its own
    array and the block's sums would read memory no thread wrote (a CI run went non-finite
    so). With the lookup under the lock :mod:`jaxdamp.engine.fused` installs, the kernel
    still equals the native one."""
    import time

    from numba.cuda.simulator import kernelapi

    class Slow(dict):
        def get(self, key, default=None):
            found = dict.get(self, key, default)
            time.sleep(0.002)  # hands the interpreter to the block's other threads
            return found

    made = kernelapi.FakeCUDAShared.__init__

    def slow_init(self, *args, **kwargs):
        made(self, *args, **kwargs)
        self._allocations = Slow()

    monkeypatch.setattr(kernelapi.FakeCUDAShared, "__init__", slow_init)
    model, pb, st, nbrs = _bed(n=6, copies=1)
    out = {e: chunk_fn(model, 2, 20, engine=e)(st, nbrs, pb) for e in ("native", "fused")}
    (sa, _, ra), (sb, _, rb) = out["native"], out["fused"]
    _agree(sb, sa, rb, ra)


@pytest.mark.long
def test_fused_equals_jax_on_fifty_grains():
    """The 50-grain bed of tests/test_native.py: the fused step against the JAX engine (the
    reference) directly, to the native kernel's tolerance."""
    cfg = mixture("primary", "arithmetic")
    model, pb, st, nbrs = start(cfg, *mixture_bed(50))
    out = {e: chunk_fn(model, 6, 100, engine=e)(st, nbrs, pb) for e in ("jax", "fused")}
    (sa, _, ra), (sb, _, rb) = out["jax"], out["fused"]
    _agree(sb, sa, rb, ra)


@pytest.mark.long  # half a minute (the marker's definition)
def test_overflowing_lists_rerun_the_chunk_identically(monkeypatch):
    """Lists with room for one neighbour overflow; the chunk runs again from its inputs with
    room for the most any grain needed, and the result is bit for bit the one with room to
    spare; the same call twice gives the same bits (the block's sums are a fixed tree)."""
    model, pb, st, nbrs = _bed(n=10)
    lay = native.layout(st), native.layout(pb)
    sp, pp = np.asarray(native.pack(st)), np.asarray(native.pack(pb))
    roomy = fused.advance_packed(model, sp, pp, *lay, 2, 50)
    again = fused.advance_packed(model, sp, pp, *lay, 2, 50)
    monkeypatch.setattr(fused, "NEIGHBOURS", 1)
    tight = fused.advance_packed(model, sp, pp, *lay, 2, 50)
    for a, b, c in zip(roomy, again, tight, strict=True):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(a, c)


def test_a_blow_up_is_reported_as_on_the_cpu():
    """A grain thrown at 1e200 m/s makes the state non-finite: the fused step stops at the
    step it happens (positions and velocities NaN, the time where it stopped) and the driver
    reports it as for the native kernel, naming the same system and first bad sample."""
    import dataclasses

    from jaxdamp.engine import driver

    model, pb, st, nbrs = _bed(n=6, copies=1)
    st = dataclasses.replace(st, v=st.v.at[0, 0, 2].set(1e200))
    caught = {}
    for e in ("native", "fused"):
        b = driver.Batch(model, pb, st, nbrs, e, 1.5)
        with pytest.raises(driver.SimulationDiverged) as err:
            driver.advance(b, 2, 10)
        caught[e] = err.value
    assert (caught["fused"].system, caught["fused"].index) == (caught["native"].system,
                                                                 caught["native"].index)
    sb, _, _ = chunk_fn(model, 2, 10, engine="fused")(st, nbrs, pb)
    assert np.isnan(np.asarray(sb.r)).all() and np.isnan(np.asarray(sb.v)).all()
    assert float(sb.t[0]) == 0.0  # the first step blew up: the clock did not move


def test_fused_is_float64_only_and_named_in_errors():
    from jaxdamp.config import ConfigError
    from jaxdamp.validation import engine_precision_error, validate

    why = engine_precision_error("fused", "float32")
    assert "numerics.precision = 'float32'" in why and "fused" in why
    cfg = apply_overrides(mixture("primary", "arithmetic"), ["numerics.engine='fused'",
                                                             "numerics.precision='float32'"])
    with pytest.raises(ConfigError, match="fused kernel computes in float64"):
        validate(cfg)


def test_fused_without_a_gpu_is_refused_before_any_compute(monkeypatch):
    """numerics.engine = 'fused' where numba-cuda finds no GPU: a ConfigError that says so."""
    from jaxdamp.config import ConfigError
    from jaxdamp.validation import validate

    monkeypatch.setattr(fused, "available", lambda: (False, "numba-cuda finds no CUDA device"))
    cfg = apply_overrides(mixture("primary", "arithmetic"), ["numerics.engine='fused'"])
    with pytest.raises(ConfigError, match="numerics.engine = 'fused': numba-cuda finds no CUDA"):
        validate(cfg)


@pytest.mark.slow  # seven minutes of PTX compiles: not in CI (its time budget)
def test_the_kernel_compiles_for_a_device():
    """The kernel lowers to PTX for compute capability 9.0 (H100/H200) with numba-cuda's
    compiler on this CPU-only machine and links to SASS with nvJitLink (its registers and
    shared memory within an SM's limits), for the thesis bed, for a cylinder and with the
    tangential springs: the device's first minutes are not spent on compile errors. A
    process of its own: numba.cuda cannot leave the simulator once imported."""
    script = textwrap.dedent("""
        import jax, numpy as np
        jax.config.update("jax_enable_x64", True)
        from jaxdamp.cases import presets
        from jaxdamp.config import apply_overrides
        from jaxdamp.engine import driver, fused
        from jaxdamp.physics.model import build
        for over in ([], ["container.shape=cylinder", "container.radius=0.021",
                          "container.Lz=0.1225"], ["tangential_law=mindlin"]):
            cfg = apply_overrides(presets.get("sanchez2012-optimal"), over)
            model, params = build(cfg)
            n = model.n
            pb = driver.batched(params)
            q = np.zeros((1, n, 4)); q[..., 0] = 1
            r = np.random.default_rng(0).uniform(0.005, 0.02, (1, n, 3))
            b = driver.start(model, pb, r, np.zeros((1, n, 3)), np.zeros((1, n, 3)), q,
                             np.zeros(1), np.zeros(1), engine="jax")
            ptx = fused.compile_ptx(model, b.states, b.params)
            assert ".target sm_90" in ptx and ".entry" in ptx, ptx[:400]
            use = fused.resources(model, b.states, b.params)  # linked: no undefined symbol
            assert 0 < use["registers"] <= 255 and use["shared"] < 48 * 1024, use
            print("ptx", len(ptx), use)
    """)
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="0")
    res = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                         text=True, timeout=900)
    assert res.returncode == 0, res.stderr[-3000:]
    assert res.stdout.count("ptx") == 3


@pytest.mark.slow  # two minutes in the CUDA simulator: not in CI (its time budget)
def test_a_fused_run_resumes_bit_identically(tmp_path):
    """``jaxdamp run`` on the fused engine (4 grains at 100 Hz, no settling, 4 chunks): stopped
    after 2 chunks and resumed, the file and the final state are the uninterrupted run's bit
    for bit, and the file says which engine wrote it."""
    import h5py

    from jaxdamp.cases import presets
    from jaxdamp.studies.runner import run

    cfg = apply_overrides(presets.get("sanchez2012-optimal"), [
        "numerics.engine='fused'", "grains.0.count=4", "frequency=100",
        "numerics.duration=0.02", "numerics.chunk=0.005", "numerics.settle_time=0"])
    whole = run(cfg, out=str(tmp_path / "whole.h5"), progress=False, echo=None)
    part = tmp_path / "part.h5"
    run(cfg, out=str(part), progress=False, echo=None, max_chunks=2)
    resumed = run(cfg, out=str(part), resume=True, progress=False, echo=None)
    for field in ("r", "v", "w", "q", "z", "zd", "work", "t"):
        np.testing.assert_array_equal(np.asarray(getattr(resumed.state, field)),
                                      np.asarray(getattr(whole.state, field)), field)
    with h5py.File(part, "r") as h:
        np.testing.assert_array_equal(h["series/z_cm"][()], whole.records["z_cm"])
        assert h.attrs["status"] == "finished" and h.attrs["engine"] == "fused"
    assert whole.summary["balance_error"] < 1e-3
