"""The compiled CPU engine (numba) computes the same step as the pure-JAX reference."""

import numpy as np
import pytest
from helpers import BASE_EXTRAS, STRUCTURE, mixture, mixture_bed, start

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.engine import native
from jaxdamp.physics.contact import LAWS
from jaxdamp.studies.runner import run

pytestmark = pytest.mark.skipif(not native.AVAILABLE, reason="numba not installed")

@pytest.mark.parametrize("system, mixing, law, extras", [
    ("primary", "arithmetic", "hertz", {}), ("driven", "harmonic", "hertz", {}),
    ("driven", "geometric", "hertz", {}), ("primary", "harmonic", "linear", {}),
    ("primary", "arithmetic", "hertz", BASE_EXTRAS), ("primary", "arithmetic", "hertz", STRUCTURE)])
def test_native_equals_jax_on_a_mixture(system, mixing, law, extras):
    """Two species (5 % radius spread, different materials and walls), friction, rotation,
    both systems, all mixing rules, both contact laws, random + shock base motion and a 3-DOF
    structure, three grains spinning too fast for the kernel's series rotation: states and
    samples agree to round-off after 600 steps."""
    cfg = apply_overrides(mixture(system, mixing, law), extras)
    r, v, w = mixture_bed(50)
    model, pb, st, nbrs = start(cfg, r, v, w)
    half_angle = 0.5 * np.linalg.norm(w[:3], axis=1) * float(np.asarray(pb.dt).ravel()[0])
    assert (half_angle**2 > 1e-4).all()
    from jaxdamp.engine.simulate import chunk_fn

    out = {e: chunk_fn(model, 6, 100, engine=e)(st, nbrs, pb) for e in ("jax", "native")}
    (sa, _, ra), (sb, _, rb) = out["jax"], out["native"]
    work = np.asarray(sa.work[0])
    assert work[2] > 0 and work[3] > 0 and work[4] > 0 and work[5] > 0  # pp and pw contacts
    for f in ("r", "v", "w", "q", "z", "zd", "y", "yd", "ydd", "work", "work_cell", "e_elastic",
              "f_box"):
        a, b = np.asarray(getattr(sa, f)), np.asarray(getattr(sb, f))
        np.testing.assert_allclose(b, a, rtol=1e-9, atol=1e-12 * max(1.0, np.abs(a).max(initial=0.0)),
                                   err_msg=f)
    for k in ra:
        np.testing.assert_allclose(np.asarray(rb[k]), np.asarray(ra[k]), rtol=1e-8,
                                   atol=1e-12 * max(1.0, float(np.abs(np.asarray(ra[k])).max(initial=0.0))),
                                   err_msg=k)


@pytest.mark.long  # half a minute (the marker's definition)
def test_runs_with_both_engines_agree():
    """A damper run through the runner gives the same result with either engine over 0.02 s
    (grains dropped from the lattice, no settling: a settling bed is chaotic and amplifies
    round-off differences beyond any tolerance within ~0.1 s)."""
    base = apply_overrides(presets.get("sanchez2012-optimal"),
                           ["grains.0.count=30", "box.Lz=0.05", "numerics.duration=0.02",
                            "numerics.chunk=0.01", "numerics.settle_time=0"])
    res = {e: run(apply_overrides(base, [f"numerics.engine='{e}'"]), progress=False, echo=None)
           for e in ("jax", "native")}
    np.testing.assert_allclose(np.asarray(res["native"].state.r), np.asarray(res["jax"].state.r),
                               rtol=0, atol=1e-10)
    for key in ("amplitude", "granular_loss_per_cycle", "input_per_cycle"):
        assert res["native"].summary[key] == pytest.approx(res["jax"].summary[key], rel=1e-6), key
    assert res["native"].summary["balance_error"] < 1e-3


def test_cell_grid_pair_list_is_complete_and_grows():
    """The kernel's half list equals the brute-force set of pairs within the cutoff, including
    in a tall sparse box (grid capped) and when the pair arrays start too small."""
    rng = np.random.default_rng(4)
    n = 300
    for box in ((0.02, 0.02, 0.02), (0.02, 0.02, 0.6)):
        r = rng.uniform(0, 1, (n, 3)) * np.array(box)
        cutoff = 0.003
        ones = np.ones(n)
        ref = np.empty((n, 3))
        pi, pj, pc = np.empty(1, np.int64), np.empty(1, np.int64), np.empty((1, 5))
        table = np.ones((1, 1, len(LAWS["hertz"].columns)))
        k, pi, pj, pc = native._pairs(r, 0.0, 0.0, 0.0, cutoff, pi, pj, pc, ref, ones * 1e-3, ones,
                                      np.zeros(n, np.int64), table, LAWS["hertz"].id)
        pairs = [tuple(sorted((int(a), int(b)))) for a, b in zip(pi[:k], pj[:k])]
        got = set(pairs)
        assert len(got) == len(pairs)  # a half list: every pair once
        d = np.linalg.norm(r[:, None] - r[None], axis=-1)
        want = {(i, j) for i in range(n) for j in range(i + 1, n) if d[i, j] < cutoff}
        assert got == want and len(want) > 10
        np.testing.assert_allclose(pc[:k, 0], 2e-3)  # R_i + R_j


def test_kernel_caches_are_keyed_on_the_physics_sources():
    """The kernels inline scalar forms from contact.py, excitation.py, integrate.py, mounts.py,
    tangential.py and the container modules (and call one, the walls' spring); numba's
    own cache would only notice edits to native.py and keep a stale law (checked by hand:
    an edited elastic energy was ignored), so every kernel's cache key holds their hash."""
    import os

    from jaxdamp.physics import contact, excitation, integrate, mounts, tangential
    from jaxdamp.physics.containers import _scalar, box, cylinder

    digest = native._source_hash()
    kernels = [native._build_pairs, native._pairs, native._wall_constants, native.grain_walls,
               native.walls_of, native._pair_forces, native._advance_one, native._advance,
               native._sweep_par, native._sweep_ser, native._springs_in, native._springs_out,
               tangential.mindlin_called]
    for k in kernels:
        key = k._cache._index_key((), k.targetctx.codegen())
        assert key[-1].startswith(digest), k.py_func.__name__
    # one function compiled over the cores and in the calling thread: two cache entries
    par = native._sweep_par._cache._index_key((), native._sweep_par.targetctx.codegen())
    ser = native._sweep_ser._cache._index_key((), native._sweep_ser.targetctx.codegen())
    assert par[-1] == digest + ":parallel" and ser[-1] == digest
    files = set(native._source_files())
    for mod in (contact, excitation, integrate, mounts, tangential, box, cylinder, _scalar,
                native):
        assert os.path.abspath(mod.__file__) in files, mod.__name__
