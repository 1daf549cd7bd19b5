"""The physics of a particle damper (``docs/physics.md`` §1–4), written once for both engines.

* :mod:`~jaxdamp.physics.contact` — the contact laws (Hertz + viscoelastic, linear
  spring–dashpot; Coulomb-capped viscous friction), registered by name, each with its JAX form
  and its scalar (numba) form side by side.
* :mod:`~jaxdamp.physics.model` — configuration → arrays: the static ``Model``, the
  ``Params`` pytree (per-species contact tables built once) and the ``State``.
* :mod:`~jaxdamp.physics.containers` — the cavities (the box; registered by name): each
  container's side walls in JAX and scalar forms beside its host geometry (lattice, fit
  checks, outline, base area, the lid height's key).
* :mod:`~jaxdamp.physics.mounts` — how the container moves (1-DOF primary, multi-DOF
  structure, prescribed drive; registered by name): predict, accelerate, powers, energy in
  JAX and scalar forms.
* :mod:`~jaxdamp.physics.pairs`, :mod:`~jaxdamp.physics.walls` — how a law is mapped over
  grain pairs and over the container's walls.
* :mod:`~jaxdamp.physics.excitation` — base motion (S1) and prescribed box motion (S2).
* :mod:`~jaxdamp.physics.integrate` — the velocity-Verlet step of grains and box, one
  skeleton around the mount and the container (the native kernel is the same skeleton in
  loops).
* :mod:`~jaxdamp.physics.energy` — energies, work channels, the energy balance, the records.
* :mod:`~jaxdamp.physics.restitution` — restitution, collision time and damping calibration.
"""
