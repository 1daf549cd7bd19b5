"""jaxdamp: a JAX-accelerated, differentiable DEM simulator of granular (particle) dampers.

Float64 is switched on at import (energy accounting over millions of steps needs it); set
``JAXDAMP_X64=0`` in the environment before importing to keep JAX's float32 default.

Modules, by concept:

* :mod:`jaxdamp.config`, :mod:`jaxdamp.presets` — what to simulate (SI units, validated).
* :mod:`jaxdamp.restitution` — restitution, collision time, damping calibration (numpy).
* :mod:`jaxdamp.model` — configuration → JAX pytrees (``Params``, ``State``).
* :mod:`jaxdamp.contact` — the contact laws (normal Hertz + viscoelastic, Coulomb-capped friction).
* :mod:`jaxdamp.walls` — sphere–wall contacts with the six moving box walls.
* :mod:`jaxdamp.neighbors` — jax-md neighbour lists, batch-aware rebuilds.
* :mod:`jaxdamp.integrate` — the velocity-Verlet step of grains and box (S1 primary or S2 drive).
* :mod:`jaxdamp.energy` — energies, work channels and the energy balance.
* :mod:`jaxdamp.packing` — initial FCC lattice and settling under gravity.
* :mod:`jaxdamp.runner` — chunked runs: records, overflow handling, checkpoints, resume.
* :mod:`jaxdamp.io` — HDF5 output.
* :mod:`jaxdamp.analysis` — analytic FRF and steady-state quantities.
* :mod:`jaxdamp.cli` — the ``jaxdamp`` command line.
"""

import os as _os

import jax as _jax

if _os.environ.get("JAXDAMP_X64", "1") != "0":
    _jax.config.update("jax_enable_x64", True)

__version__ = "0.1.0"
