"""Small systems for tests: build configs, place grains by hand, step them."""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np
import pytest

from jaxdamp.config import Box, Config, Drive, Material, Numerics, Primary, Species
from jaxdamp.engine import driver
from jaxdamp.engine.simulate import chunk_fn
from jaxdamp.physics.model import build

STEEL = Material(E=2e9, nu=0.3, density=7850.0, mu=0.0, gamma_n=0.0, gamma_s=0.0)


def config(n=2, radius=2.5e-3, material=STEEL, box=(0.05, 0.05, 0.05), system="driven",
           gravity=0.0, frequency=10.0, amplitude=0.0, primary=None, contact_law="hertz",
           **numerics) -> Config:
    num = dict(duration=0.01, chunk=0.005, record_dt=1e-4)
    num.update(numerics)
    return Config(
        system=system,
        frequency=frequency,
        grains=(Species(count=n, radius=radius, material=material),) if n else (),
        box=Box(*box),
        drive=Drive(amplitude) if system == "driven" else None,
        primary=primary if system == "primary" else None,
        numerics=Numerics(**num),
        gravity=gravity,
        contact_law=contact_law,
        name="test",
    )


def start(cfg: Config, r, v, w=None, z=0.0, zd=0.0, dt=None, **param_changes):
    """Model, batched params, batched initial state and neighbour lists for given kinematics."""
    model, params = build(cfg)
    if dt is not None:
        params = dataclasses.replace(params, dt=jnp.asarray(dt))
    if param_changes:
        params = dataclasses.replace(params, **{k: jnp.asarray(v_) for k, v_ in param_changes.items()})
    n = model.n
    r = np.asarray(r, float).reshape(n, 3)
    v = np.asarray(v, float).reshape(n, 3)
    w = np.zeros((n, 3)) if w is None else np.asarray(w, float).reshape(n, 3)
    q = np.zeros((n, 4))
    q[:, 0] = 1.0
    pb = driver.batched(params)
    x0 = [np.full(1, x) if np.ndim(x) == 0 else np.asarray(x, float)[None] for x in (z, zd)]
    b = driver.start(model, pb, r[None], v[None], w[None], q[None], *x0, engine="jax",
                     multiplier=cfg.numerics.capacity_multiplier)
    return model, pb, b.states, b.nbrs


#: The implementations of the step the physics tests run on: the three engines
#: (``numerics.engine``) and the JAX engine with its contact laws in float32
#: (``numerics.precision = "float32"``, :func:`engine_model`). The fused device step runs in
#: numba-cuda's CUDA simulator here (tests/conftest.py), ~1–2 ms per step of a 2-grain bed:
#: its physics tests (2–40 s each) are ``long``.
ENGINES = ("jax", "native", pytest.param("fused", marks=pytest.mark.long), "float32")
#: :data:`ENGINES` without the fused step, for the physics tests that take 10⁵ steps or a settled
#: damper (hours in the simulator); the fused step matches the native kernel to round-off on
#: every path of the step (tests/test_fused.py), and ``benchmarks/device_check.py`` compares it
#: with the CPU on a device.
ENGINES_UNSIMULATED = ("jax", "native", "float32")


def engine_model(model, engine: str):
    """``(model, engine)`` for a test's ``engine`` of :data:`ENGINES`: ``"float32"`` is the JAX
    engine with ``model.precision = "float32"``."""
    if engine == "float32":
        return dataclasses.replace(model, precision="float32"), "jax"
    return model, engine


def engine_overrides(engine: str) -> list[str]:
    """Configuration overrides selecting a test's ``engine`` of :data:`ENGINES`."""
    if engine == "float32":
        return ["numerics.engine='jax'", "numerics.precision='float32'"]
    return [f"numerics.engine='{engine}'"]


def run_steps(model, pb, st, nbrs, n_records, record_every, engine="jax"):
    """Advance with ``engine`` (re-allocating neighbour lists on overflow) and return
    (final batched state, nbrs, records of system 0 as numpy)."""
    b, recs = advance(model, st, nbrs, pb, n_records, record_every, engine=engine)
    return b.states, b.nbrs, {k: np.asarray(v[0]) for k, v in recs.items()}


def advance(model, st, nbrs, pb, n_records, record_every, engine="jax", on_realloc=None):
    """One driver chunk from given states and lists (no non-finite check: tests may blow
    up on purpose): ``(batch, records)``."""
    model, engine = engine_model(model, engine)
    b = driver.Batch(model, pb, st, nbrs, driver.resolve_engine(
        engine, model.precision, tangential=model.tangential), 1.5)
    return driver.advance(b, n_records, record_every, on_realloc=on_realloc, check=False)


def trajectory(model, pb, st, nbrs, n_steps, every=1, engine="jax"):
    """States of system 0 after every ``every`` steps with ``engine``, as a list of numpy
    dicts (slow: tests)."""
    out = []
    model, engine = engine_model(model, engine)
    fn = chunk_fn(model, 1, every, engine=engine)
    for _ in range(n_steps // every):
        st, nbrs, _ = fn(st, nbrs, pb)
        s0 = driver.take(st, 0)
        out.append({k: np.asarray(getattr(s0, k)) for k in ("r", "v", "w", "t", "e_elastic")})
    return st, out


def gas(n=27, side=0.02, seed=1):
    """``(r, v, w)`` of ``n`` grains on a jittered cubic lattice filling ``side`` [m] from the
    corner, fast (0.5 m/s) and spinning (50 rad/s): a granular gas."""
    rng = np.random.default_rng(seed)
    k = round(n ** (1 / 3))
    grid = np.stack(np.meshgrid(*[np.arange(k)] * 3, indexing="ij"), -1).reshape(-1, 3) + 0.5
    r = grid * (side / k) + rng.uniform(-5e-4, 5e-4, (n, 3))
    return r, rng.normal(0, 0.5, (n, 3)), rng.normal(0, 50.0, (n, 3))


def load_experiment(name):
    """The study ``experiments/<name>.py``, imported as the module ``experiments.<name>``
    (the repository root is on the tests' path: ``pythonpath`` in pyproject.toml)."""
    import importlib

    return importlib.import_module(f"experiments.{name}")


# -- a two-species bed that exercises every path of a kernel (tests/test_native.py, test_fused.py)

MIX_STEEL = Material(E=2e9, nu=0.3, density=7850.0, mu=0.3, gamma_n=40.0, gamma_s=120.0)
MIX_GLASS = Material(E=5e9, nu=0.22, density=2500.0, mu=0.5, gamma_s=50.0, restitution=0.8,
                     v_ref=1.0)


def mixture(system, mixing, law="hertz", counts=(20, 30)) -> Config:
    """Two species (5 % radius spread, different materials and walls) with friction in a 2 cm
    box: ``counts`` big steel and small glass grains, for :func:`mixture_bed`."""
    steel, glass = MIX_STEEL, MIX_GLASS
    if law == "linear":  # the linear law takes a stiffness and a restitution, no gamma_n
        steel = dataclasses.replace(steel, gamma_n=None, restitution=0.6, linear_stiffness=2e4)
        glass = dataclasses.replace(glass, linear_stiffness=5e3)
    grains = (Species(count=counts[0], radius=2e-3, radius_spread=0.05, material=steel,
                      name="big"),
              Species(count=counts[1], radius=1e-3, material=glass, name="small"))
    return Config(
        system=system, frequency=30.0, grains=grains, box=Box(0.02, 0.02, 0.02, wall=glass),
        primary=Primary(M=0.5, K=2e4, C=3.0, U=0.002) if system == "primary" else None,
        drive=Drive(0.003) if system == "driven" else None,
        numerics=Numerics(v_impact=2.0), mixing=mixing, contact_law=law, name="mixture",
    )


def mixture_bed(n: int, seed: int = 2, spacing: float = 0.0045):
    """``(r, v, w)`` of ``n ≤ 64`` grains on a jittered 4×4×4 lattice of ``spacing`` [m] in the
    2 cm box, fast and spinning, the first three too fast for the kernels' series rotation
    (a small bed needs a closer lattice, 4.2 mm, for pair contacts within 600 steps)."""
    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(*[np.arange(4)] * 3, indexing="ij"), -1).reshape(-1, 3)[:n]
    r = (grid + 0.5) * spacing + rng.uniform(-3e-4, 3e-4, (n, 3))
    r[:, 2] += 0.001
    v = rng.normal(0, 0.5, (n, 3))
    w = rng.normal(0, 100.0, (n, 3))
    w[:3] *= 500.0  # three fast spins: the kernel's exact rotation, not its series
    return r, v, w


#: Random base motion (120 lines, 10–600 Hz) and a shock pulse that starts, peaks and ends
#: inside the 600 steps, on top of the harmonic drive.
BASE_EXTRAS = {"random.psd": [[10.0, 50.0], [600.0, 20.0]], "random.resolution": 5.0,
               "shock.peak": -30.0, "shock.duration": 1e-4, "shock.start": 2e-5}

#: A 3-DOF chain carrying the box on its middle mass, a harmonic force on the top one.
STRUCTURE = {"structure.M": [[0.4, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.3]],
             "structure.K": [[4e4, -2e4, 0.0], [-2e4, 4e4, -2e4], [0.0, -2e4, 2e4]],
             "structure.C": [[6.0, -3.0, 0.0], [-3.0, 6.0, -3.0], [0.0, -3.0, 3.0]],
             "structure.attach": 1, "structure.force": 40.0, "structure.force_dof": 2}


#: A short run of the thesis' optimal damper (30 grains, 0.08 s in 4 chunks): runner, CLI and
#: engine-choice tests.
SMALL_RUN = ["grains.0.count=30", "box.Lz=0.05", "numerics.duration=0.08", "numerics.chunk=0.02",
             "numerics.settle_time=0.2", "numerics.record_dt=1e-3"]


def small_config(*extra) -> Config:
    """The thesis' optimal damper shortened to :data:`SMALL_RUN`, with ``extra`` overrides."""
    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides

    return apply_overrides(presets.get("sanchez2012-optimal"), SMALL_RUN + list(extra))

