"""S3, the single-particle impact damper (``docs/physics.md`` §1).

* :mod:`~jaxdamp.s3.impact` — the event-driven (exact) and smooth (differentiable) models.
* :mod:`~jaxdamp.s3.periodic` — periodic orbits of the smooth model, Floquet multipliers and
  exact steady-state derivatives by implicit differentiation.
"""
