"""The dependencies compute what they claim. jax/jaxlib 0.10.2 returns wrong numbers on the CPU
for a jitted, vmapped small matrix-vector product followed by a reduction over more than
~16 k rows (jax-ml/jax#39103) — the pattern of a rotation applied grain by grain and squared,
as in the contact laws and the energies. pyproject.toml excludes 0.10.2; this test fails if
an environment gets it (or a later release that regresses the same way)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxdamp  # noqa: F401  (float64 on, as in every run)


@pytest.mark.parametrize("dtype, rows", [(jnp.float64, 16_385), (jnp.float32, 32_769)])
def test_jitted_vmapped_matvec_then_sum_is_exact(dtype, rows):
    k = jnp.arange(rows, dtype=dtype)
    x = jnp.stack((k, jnp.zeros_like(k), jnp.zeros_like(k)), axis=1)  # (rows, 3)
    rotation = jnp.eye(3, dtype=dtype)

    def squared_norms(x):
        return jax.vmap(lambda row: jnp.sum((rotation @ row) ** 2))(x)

    assert x.dtype == dtype
    kk = np.arange(rows, dtype=dtype)
    exact = (kk * kk).astype(np.float64)  # k² rounded once to the dtype, as the sum of k², 0, 0
    got = np.asarray(jax.jit(squared_norms)(x), dtype=np.float64)
    bad = np.flatnonzero(got != exact)
    assert bad.size == 0, (f"jax {jax.__version__}: {bad.size} of {rows} rows wrong, e.g. row "
                           f"{bad[-1]}: {got[bad[-1]]} instead of {exact[bad[-1]]}")


@pytest.mark.long
def test_the_cuda_extra_resolves_to_jax_cuda_wheels_of_the_installed_jax():
    """``pip install ".[cuda]"`` (README, "On a GPU") names JAX's CUDA plugin at the version of
    the JAX installed here and numba-cuda, checked without a GPU by pip's resolver (a dry
    run)."""
    import os
    import subprocess
    import sys

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    done = subprocess.run([sys.executable, "-m", "pip", "install", "--dry-run", "--quiet",
                           "--report", "-", f"{root}[cuda]"], capture_output=True, text=True,
                          timeout=600, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    import json

    names = {item["metadata"]["name"].lower(): item["metadata"]["version"]
             for item in json.loads(done.stdout)["install"]}
    plugin = [n for n in names if n.startswith("jax-cuda") and n.endswith("-plugin")]
    assert plugin, sorted(names)
    assert names[plugin[0]] == jax.__version__, (plugin[0], names[plugin[0]], jax.__version__)
    # the fused device step's compiler with it (numerics.engine = "fused")
    import importlib.metadata

    installed = {d.metadata["Name"].lower() for d in importlib.metadata.distributions()}
    assert "numba-cuda" in names or "numba-cuda" in installed, sorted(names)
