"""S3, the single-particle impact damper (``docs/physics.md`` §1).

* :mod:`~jaxdamp.s3.impact` — the model in words, and its entry points :func:`simulate` and
  :func:`sweep` (same result and file layout as the DEM sweeps).
* :mod:`~jaxdamp.s3.common` — the collision law, units, the run record and its summary.
* :mod:`~jaxdamp.s3.event` — the exact event-driven model (numba).
* :mod:`~jaxdamp.s3.smooth` — the smooth penalty model (JAX, differentiable, ``vmap``-batched).
* :mod:`~jaxdamp.s3.periodic` — periodic orbits of the smooth model, Floquet multipliers and
  exact steady-state derivatives by implicit differentiation.
"""
