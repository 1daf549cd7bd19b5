"""Running the physics: neighbour lists, the jitted chunk, the compiled CPU kernel, the driver.

* :mod:`~jaxdamp.engine.driver` — the one simulation driver: start/restore/checkpoint a batch,
  advance it (neighbour-list allocation and overflow, the non-finite policy). Everything that
  advances grains goes through it.
* :mod:`~jaxdamp.engine.simulate` — the jitted ``lax.scan`` chunk for either engine.
* :mod:`~jaxdamp.engine.native` — the compiled CPU engine (numba) of the same step.
* :mod:`~jaxdamp.engine.neighbors` — neighbour lists (host cell lists to allocate, all pairs in JAX to rebuild), rebuilt per system.
* :mod:`~jaxdamp.engine.packing` — initial lattice and settling (batched over beds).
"""
