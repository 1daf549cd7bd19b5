"""The simulation driver: the one place that runs the time loop of the DEM.

Everything that advances grains — a single run (:mod:`jaxdamp.studies.runner`), a sweep
(:mod:`jaxdamp.studies.sweep`), settling (:mod:`jaxdamp.engine.packing`), the optimiser's problems
(:mod:`jaxdamp.design`), experiments and benchmarks — holds a :class:`Batch` and calls
:func:`advance`. The driver owns:

* the start of a batch from positions and velocities (:func:`start`: forces evaluated once,
  neighbour lists allocated) or from a checkpoint (:func:`restore`), and the checkpoint itself
  (:func:`checkpoint`);
* the neighbour lists: allocation, and re-allocation with the chunk redone when a list
  overflowed, so that no contact is ever dropped (nothing else allocates them);
* the engine (``"jax"`` — differentiable, shards over devices — or the compiled ``"native"``
  CPU kernel; ``"auto"`` picks native on a CPU), resolved once per batch;
* one non-finite policy: a chunk whose samples or final state are not finite raises
  :class:`SimulationDiverged` naming the time, the step, the system and the quantity (the grain,
  where it is a grain's), and carrying the samples before it so that the caller can keep them.

The jitted chunk itself (``lax.scan`` over steps, records every ``record_every`` steps) is
:func:`jaxdamp.engine.simulate.chunk_fn`; the physics step is :func:`jaxdamp.physics.integrate.step`.

Example::

    from jaxdamp.engine import driver
    from jaxdamp.cases import presets
    from jaxdamp.physics.model import build
    model, params = build(presets.get("sanchez2012-optimal"))
    batch = driver.start(model, driver.batched(params), r[None], v[None], w[None], q[None],
                         z[None], zd[None])
    batch, records = driver.advance(batch, n_records=100, record_every=10)
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp import interrupt
from jaxdamp.engine import neighbors as nb
from jaxdamp.engine.choice import resolve_engine
from jaxdamp.engine.simulate import chunk_fn, init_states
from jaxdamp.physics.integrate import box_frame
from jaxdamp.physics.model import Model, Params, State


class SimulationDiverged(FloatingPointError):
    """The state became non-finite.

    Attributes:
      system: index of the first offending system in the batch.
      index: index of its first non-finite sample in the chunk (samples before it are good).
      records: the chunk's samples (numpy, batch axis first), for the caller to keep.
    """

    def __init__(self, message: str, system: int = 0, index: int = 0, records=None):
        super().__init__(message)
        self.system = system
        self.index = index
        self.records = records


@dataclass(frozen=True)
class Batch:
    """``B`` independent systems of one :class:`~jaxdamp.physics.model.Model` in flight.

    Attributes:
      model: the static model (shapes and code paths).
      params: batched :class:`~jaxdamp.physics.model.Params` (leading axis ``B``).
      states: batched :class:`~jaxdamp.physics.model.State`.
      nbrs: batched :class:`~jaxdamp.engine.neighbors.Neighbors`.
      engine: ``"jax"`` or ``"native"`` (resolved).
      multiplier: neighbour-list capacity multiplier.
      place: applied to states and lists after every (re-)allocation — e.g. padding and
        sharding over devices (:mod:`jaxdamp.studies.sweep`); identity by default.
    """

    model: Model
    params: Params
    states: State
    nbrs: nb.Neighbors
    engine: str
    multiplier: float = 1.5
    place: Callable | None = None

    @property
    def size(self) -> int:
        return int(self.states.t.shape[0])

    def system(self, i: int) -> State:
        """State of system ``i``."""
        return take(self.states, i)

    def replace(self, **changes) -> "Batch":
        return dataclasses.replace(self, **changes)


def compile_note(engine: str, tangential: str = "viscous") -> str | None:
    """A one-line note when ``engine``'s kernel will be compiled before the first chunk (the
    native kernel without its on-disk cache for ``tangential``'s form, the fused one at its
    first launch in a process), else ``None``: printed before settling, so that a still
    progress bar is explained."""
    if engine == "native":
        from jaxdamp.engine import native

        return native.compile_note(engine, springs=tangential != "viscous")
    if engine == "fused":
        from jaxdamp.engine import fused

        return fused.compile_note()
    return None


def batched(tree):
    """Add a leading batch axis of size 1 to every leaf of a pytree."""
    return jax.tree_util.tree_map(lambda x: jnp.asarray(x)[None], tree)


def stack(tree_list):
    """Stack single-system pytrees into a batch (leading axis)."""
    return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *tree_list)


def take(tree, i):
    """System ``i`` of a batched pytree."""
    return jax.tree_util.tree_map(lambda x: x[i], tree)


def _allocate(model, states, params, multiplier, at_least=0):
    """Lists for the states' box-frame positions; a large bed's cell grid (the JAX engine's
    in-loop builder) reaches from the floor to the lid, so that a bed thrown up stays on it."""
    lz = np.asarray(to_host(params.Lz), np.float64)
    extent = np.zeros(lz.shape + (2, 3))
    extent[..., 1, 2] = lz
    return nb.allocate(model, to_host(box_frame(states, params)), multiplier, at_least=at_least,
                       radius=to_host(params.radius), extent=extent)


def to_host(tree):
    """Numpy copies of a pytree of (batched) arrays. Arrays spread over several processes
    (a sweep across hosts, :mod:`jaxdamp.studies.sweep`) are gathered from all of them first,
    a collective: every process must make the same call."""
    leaves = jax.tree_util.tree_leaves(tree)
    if any(isinstance(x, jax.Array) and not x.is_fully_addressable for x in leaves):
        from jax.experimental import multihost_utils

        tree = multihost_utils.process_allgather(tree, tiled=True)
    return jax.tree_util.tree_map(np.asarray, tree)


def start(model: Model, params: Params, r, v, w, q, z, zd, t: float = 0.0, *,
          engine: str = "auto", multiplier: float = 1.5, place: Callable | None = None,
          e_start=None) -> Batch:
    """A batch at time ``t`` from grain kinematics ``(B, N, 3)`` (``q``: ``(B, N, 4)``) and box
    position/velocity ``(B,)`` — or, for a structure of ``model.dofs`` degrees of freedom,
    ``(B, dofs)`` in the engines' order, the box first — (ignored for a driven box, which
    follows its drive): forces and
    accelerations evaluated there, neighbour lists allocated. ``e_start`` ``(B,)`` sets the
    reference energy of the balance (default: the energy of this state)."""
    r = jnp.asarray(r)
    # the initial forces over the pairs listed at these positions (host cell lists, linear in
    # N; listed pairs are a superset of the touching ones), never over all N² pairs
    touching = nb.allocate(model, r, 1.0, radius=params.radius).idx
    states = init_states(model, params, r, jnp.asarray(v), jnp.asarray(w),
                         jnp.asarray(q), jnp.asarray(z), jnp.asarray(zd), t, idx=touching)
    if e_start is not None:
        states = dataclasses.replace(states, e_start=jnp.asarray(e_start, jnp.float64))
    nbrs = _allocate(model, states, params, multiplier)
    engine = resolve_engine(engine, model.precision, int(states.t.shape[0]),
                            tangential=model.tangential)
    return _placed(Batch(model, params, states, nbrs, engine, multiplier, place))


def attach(model: Model, params: Params, states: State, *, engine: str = "auto",
           multiplier: float = 1.5, at_least: int = 0, place: Callable | None = None) -> Batch:
    """A batch around existing (batched) states: neighbour lists allocated for them (with at
    least ``at_least`` neighbours per grain)."""
    nbrs = _allocate(model, states, params, multiplier, at_least)
    engine = resolve_engine(engine, model.precision, int(states.t.shape[0]),
                            tangential=model.tangential)
    return _placed(Batch(model, params, states, nbrs, engine, multiplier, place))


def grow(batch: Batch) -> Batch:
    """The batch with neighbour lists re-allocated 1.5× larger (after an overflow flagged by a
    caller's own jitted function of ``batch.nbrs``, e.g. a differentiated window)."""
    old = nb.capacity(batch.nbrs)
    nbrs = _allocate(batch.model, batch.states, batch.params, batch.multiplier,
                     at_least=int(np.ceil(old * 1.5)) + 1)
    return batch.replace(nbrs=batch.place(nbrs) if batch.place is not None else nbrs)


def restore(model: Model, params: Params, arrays: dict, *, engine: str = "auto",
            multiplier: float = 1.5, place: Callable | None = None) -> Batch:
    """A batch from :func:`checkpoint` arrays (bit-identical continuation)."""
    states, nbrs = arrays_to_state(arrays)
    if states.t.ndim == 0:  # a single system's checkpoint
        states, nbrs = batched(states), batched(nbrs)
    engine = resolve_engine(engine, model.precision, int(states.t.shape[0]),
                            tangential=model.tangential)
    return _placed(Batch(model, params, states, nbrs, engine, multiplier, place))


def checkpoint(batch: Batch, systems: int | None = None) -> dict:
    """Exact host copies of the first ``systems`` states and neighbour lists (all by default),
    as ``{"state/<field>", "nbrs/<field>"}`` arrays (:func:`state_to_arrays`)."""

    n = batch.size if systems is None else systems
    host = lambda tree: jax.tree_util.tree_map(lambda x: x[:n], to_host(tree))  # noqa: E731
    return state_to_arrays(host(batch.states), host(batch.nbrs))


def state_to_arrays(state: State, nbrs: nb.Neighbors) -> dict:
    """Checkpoint form of a (batch of) ``State`` and ``Neighbors``: ``{"state/<field>": array,
    "nbrs/<field>": array}``, exact copies."""
    out = {f"state/{f.name}": np.asarray(getattr(state, f.name))
           for f in dataclasses.fields(state)}
    out.update({f"nbrs/{k}": v for k, v in nb.to_numpy(nbrs).items()})
    return out


def arrays_to_state(arrays: dict) -> tuple[State, nb.Neighbors]:
    """Inverse of :func:`state_to_arrays`: ``(State, Neighbors)`` as JAX arrays."""
    st = {k.split("/", 1)[1]: jnp.asarray(v) for k, v in arrays.items() if k.startswith("state/")}
    nbr = {k.split("/", 1)[1]: v for k, v in arrays.items() if k.startswith("nbrs/")}
    for name in ("y", "yd", "ydd"):  # files from before multi-DOF structures: one DOF
        st.setdefault(name, jnp.zeros(st["z"].shape + (0,)))
    return State(**st), nb.from_numpy(nbr)


def _placed(batch: Batch) -> Batch:
    if batch.place is None:
        return batch
    return batch.replace(states=batch.place(batch.states), nbrs=batch.place(batch.nbrs))


def sharded(tree) -> jax.sharding.NamedSharding | None:
    """The sharding of a batched pytree when its batch axis is split over several devices
    (:func:`jaxdamp.studies.sweep` places it so), else ``None``."""
    sh = getattr(jax.tree_util.tree_leaves(tree)[0], "sharding", None)
    if isinstance(sh, jax.sharding.NamedSharding) and len(sh.device_set) > 1:
        return sh
    return None


def advance(batch: Batch, n_records: int, record_every: int, *, systems: int | None = None,
            on_realloc=None, check: bool = True) -> tuple[Batch, dict]:
    """Run ``n_records × record_every`` steps; return the new batch and the samples
    (numpy, ``(B, n_records, ...)``; with ``systems``, the first ``systems`` rows only — the
    rest is padding).

    On neighbour-list overflow the lists are re-allocated 1.5× larger and the chunk is redone
    (``on_realloc(old, new)`` is told the capacities). With ``check`` a non-finite sample or
    state raises :class:`SimulationDiverged` (the batch is left as it was before the chunk)."""
    model = batch.model
    fn = chunk_fn(model, n_records, record_every, engine=batch.engine,
                  sharding=sharded(batch.states))
    nbrs = batch.nbrs
    while True:
        states, new_nbrs, recs = call_chunk(fn, batch.states, nbrs, batch.params)
        if model.n < 2 or not bool(np.any(to_host(new_nbrs.overflow))):
            break
        old = nb.capacity(nbrs)
        nbrs = grow(batch.replace(nbrs=nbrs)).nbrs
        if on_realloc is not None:
            on_realloc(old, nb.capacity(nbrs))
    n = batch.size if systems is None else systems
    recs = {k: v[:n] for k, v in to_host(recs).items()}
    if check:
        check_finite(recs, to_host(states), int(to_host(batch.states.step)[0]), record_every,
                     n)
    return batch.replace(states=states, nbrs=new_nbrs), recs


def run_chunks(batch: Batch, chunks: range, records_per_chunk: int, record_every: int, *,
               systems: int | None = None, on_chunk=None, on_diverged=None, on_realloc=None,
               on_interrupt=None, progress: str | None = None,
               total: int | None = None) -> Batch:
    """The chunk loop of every long run: for each index of ``chunks``, :func:`advance` and
    hand ``(index, batch, records)`` to ``on_chunk`` (append samples, checkpoint, snapshot).

    A non-finite chunk calls ``on_diverged(error)`` (keep what was written, mark the file)
    and re-raises :class:`SimulationDiverged`; Ctrl-C (``KeyboardInterrupt``) calls
    ``on_interrupt()`` (the file keeps every finished chunk and its checkpoint: mark it
    resumable) and re-raises; a Ctrl-C while a chunk is computed stops once it is done
    (:func:`call_chunk`), one while it is being written waits until it is written. ``progress``: the description of a tqdm bar
    over ``total`` chunks (starting at ``chunks.start``), or ``None`` for none. Returns the
    batch after the last chunk."""
    bar = None
    if progress is not None:
        from tqdm.auto import tqdm

        bar = tqdm(total=total if total is not None else len(chunks), initial=chunks.start,
                   unit="chunk", desc=progress, leave=True)
    try:
        for k in chunks:
            try:
                batch, recs = advance(batch, records_per_chunk, record_every, systems=systems,
                                      on_realloc=on_realloc)
                if on_chunk is not None:
                    with interrupt.held():  # never half a chunk in the file
                        on_chunk(k, batch, recs)
                if bar is not None:
                    bar.update(1)
                    bar.set_postfix(t=f"{float(recs['t'][0, -1]):.3f}s")
            except SimulationDiverged as e:
                if on_diverged is not None:
                    on_diverged(e)
                raise
            except KeyboardInterrupt:
                if on_interrupt is not None:
                    on_interrupt()
                raise
    finally:
        if bar is not None:
            bar.close()
    return batch


def call_chunk(fn, *args):
    """``fn(*args)`` for a chunk function of :func:`jaxdamp.engine.simulate.chunk_fn`, with
    Ctrl-C held until it returns, then raised as ``KeyboardInterrupt`` (:mod:`jaxdamp.interrupt`).

    A chunk cannot be stopped midway anyway (XLA and the numba kernel only return to Python
    at its end), and a ``KeyboardInterrupt`` raised inside a host callback (the native engine
    spends nearly all of a chunk in one) would reach the caller wrapped in a runtime error by
    JAX, no longer a Ctrl-C."""
    with interrupt.held():
        return fn(*args)


def run_for(batch: Batch, seconds: float, pieces: int = 1, check: bool = True) -> Batch:
    """Advance by ``seconds`` (rounded to whole steps, at least one) in about ``pieces``
    chunks, discarding the samples (burn-in, transients)."""
    dt = float(to_host(batch.params.dt).ravel()[0])
    steps = max(1, int(round(seconds / dt)))
    per = max(1, steps // pieces)
    done = 0
    while done < steps:
        k = min(per, steps - done)
        batch, _ = advance(batch, 1, k, check=check)
        done += k
    return batch


def _first_bad(values) -> int | None:
    v = np.asarray(values, dtype=float)
    bad = ~np.isfinite(v.reshape(v.shape[0], -1)).all(axis=1)
    return int(np.argmax(bad)) if bad.any() else None


def check_finite(recs: dict, states: State, step0: int, record_every: int, n: int) -> None:
    """Raise :class:`SimulationDiverged` if a sample or a final state of the first ``n``
    systems is not finite. The message names the time, step, system and what went bad."""
    for b in range(n):
        at, names = None, []
        for name, values in recs.items():
            k = _first_bad(values[b])
            if k is not None and (at is None or k < at):
                at, names = k, [name]
            elif k is not None and k == at:
                names.append(name)
        what = []
        for field in ("r", "v", "w", "z", "zd"):
            arr = np.asarray(getattr(states, field))[b]
            if not np.isfinite(arr).all():
                if arr.ndim >= 2:
                    grain = int(np.argmax(~np.isfinite(arr.reshape(arr.shape[0], -1)).all(axis=1)))
                    what.append(f"{field} of grain {grain}")
                else:
                    what.append(field)
        if at is None and not what:
            continue
        if at is None:
            at = len(recs["t"][b]) - 1 if "t" in recs else 0
        desc = ", ".join(what) if what else ", ".join(names)
        if names and what:
            desc += f" (first non-finite samples: {', '.join(names)})"
        t = recs["t"][b]
        t_bad = float(t[at]) if "t" in recs and np.isfinite(t[at]) else float("nan")
        step = step0 + (at + 1) * record_every
        system = f", system {b}" if n > 1 else ""
        raise SimulationDiverged(
            f"simulation went non-finite by t = {t_bad:.6g} s (step {step}{system}): {desc}. "
            "Samples before it are kept; try a smaller numerics.dt.", system=b, index=at,
            records=recs)
