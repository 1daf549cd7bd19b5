"""The physics of a particle damper (``docs/physics.md`` §1–4), written once for both engines.

* :mod:`~jaxdamp.physics.contact` — the contact laws (Hertz + viscoelastic, linear
  spring–dashpot; Coulomb-capped viscous friction), registered by name, each with its JAX form
  and its scalar (numba) form side by side.
* :mod:`~jaxdamp.physics.model` — configuration → arrays: the static ``Model``, the
  ``Params`` pytree (per-species contact tables built once) and the ``State``.
* :mod:`~jaxdamp.physics.pairs`, :mod:`~jaxdamp.physics.walls` — how a law is mapped over
  grain pairs and over the six box walls.
* :mod:`~jaxdamp.physics.excitation` — base motion (S1) and prescribed box motion (S2).
* :mod:`~jaxdamp.physics.integrate` — the velocity-Verlet step of grains and box.
* :mod:`~jaxdamp.physics.energy` — energies, work channels, the energy balance, the records.
* :mod:`~jaxdamp.physics.restitution` — restitution, collision time and damping calibration.
"""
