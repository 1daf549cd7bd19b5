"""Small systems for tests: build configs, place grains by hand, step them."""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np

from jaxdamp.config import Box, Config, Drive, Material, Numerics, Species
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
    b = driver.start(model, pb, r[None], v[None], w[None], q[None], np.full(1, z), np.full(1, zd),
                     engine="jax", multiplier=cfg.numerics.capacity_multiplier)
    return model, pb, b.states, b.nbrs


#: The implementations of the step the physics tests run on: the two engines
#: (``numerics.engine``) and the JAX engine with its contact laws in float32
#: (``numerics.precision = "float32"``, :func:`engine_model`).
ENGINES = ("jax", "native", "float32")


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
    b = driver.Batch(model, pb, st, nbrs, driver.resolve_engine(engine, model.precision), 1.5)
    return driver.advance(b, n_records, record_every, on_realloc=on_realloc, check=False)


def trajectory(model, pb, st, nbrs, n_steps, every=1):
    """States of system 0 after every ``every`` steps, as a list of numpy dicts (slow: tests)."""
    out = []
    fn = chunk_fn(model, 1, every)
    for _ in range(n_steps // every):
        st, nbrs, _ = fn(st, nbrs, pb)
        s0 = driver.take(st, 0)
        out.append({k: np.asarray(getattr(s0, k)) for k in ("r", "v", "w", "t", "e_elastic")})
    return st, out


EXPERIMENTS = __import__("pathlib").Path(__file__).parent.parent / "experiments"


def load_experiment(name):
    """The module ``experiments/<name>.py`` (experiments are scripts, not a package)."""
    import importlib.util
    import sys

    if str(EXPERIMENTS) not in sys.path:  # the scripts import experiments/scaffold.py
        sys.path.insert(0, str(EXPERIMENTS))
    spec = importlib.util.spec_from_file_location(name, EXPERIMENTS / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod
