"""jaxdamp: a JAX-accelerated, differentiable DEM simulator of granular (particle) dampers.

Float64 is switched on at import (energy accounting over millions of steps needs it; JAX
itself is imported only where it is used); set ``JAXDAMP_X64=0`` in the environment before
importing to keep JAX's float32 default.

The physics is in ``docs/physics.md``; file schemas in ``docs/output.md``. Subpackages, from
the bottom layer up (a module imports only from its own layer or below):

* :mod:`jaxdamp.config`, :mod:`jaxdamp.validation` — what to simulate: a validated tree of
  frozen dataclasses (SI units); :mod:`jaxdamp.cases` — the sources' presets and the
  binary-mixture builders; :mod:`jaxdamp.interrupt` — Ctrl-C as a request acted on at safe
  points (between chunks), so that nothing is half written.
* :mod:`jaxdamp.physics` — the physics once for both engines: contact laws (JAX and scalar
  forms side by side, registered by name), pair and wall mappings, excitation, the
  velocity-Verlet step, energies and records, restitution calibration, configuration → arrays.
* :mod:`jaxdamp.engine` — running it: neighbour lists, the jitted chunk, the compiled CPU
  kernel, settling, and the one simulation driver.
* :mod:`jaxdamp.analysis` — FRF and steady-state summaries, replicate statistics and
  steady-state detection, nonlinear dynamics of the bed.
* :mod:`jaxdamp.io` — every output file kind (run, sweep, efficiency, optimiser logs) and
  reading them back.
* :mod:`jaxdamp.studies` — a single run, batched sweeps with replicates, efficiency.
* :mod:`jaxdamp.s3` — the single-particle impact damper (event-driven and smooth) and its
  periodic orbits with exact steady-state derivatives.
* :mod:`jaxdamp.design` — design objectives, problems, searches and optimisers with intervals.
* :mod:`jaxdamp.figures` — every figure.
* :mod:`jaxdamp.peers` — independent codes we check and time against (LAMMPS: the contact
  mapping, its checks, input decks, runs).
* :mod:`jaxdamp.cli` — the ``jaxdamp`` command line.
"""

import os as _os
import sys as _sys

# JAX is not imported here (it takes seconds; `jaxdamp --help` and bad input answer before it):
# JAX reads JAX_ENABLE_X64 when it is first imported; if it already is, it is told directly.
if _os.environ.get("JAXDAMP_X64", "1") != "0":
    if "jax" in _sys.modules:
        _sys.modules["jax"].config.update("jax_enable_x64", True)
    elif _os.environ.get("JAX_ENABLE_X64") is None:
        _os.environ["JAX_ENABLE_X64"] = "1"
        _os.environ["_JAXDAMP_SET_X64"] = "1"  # ours: a child with JAXDAMP_X64=0 undoes it
    else:
        _os.environ["JAX_ENABLE_X64"] = "1"
elif _os.environ.pop("_JAXDAMP_SET_X64", None):
    _os.environ.pop("JAX_ENABLE_X64", None)

__version__ = "0.1.0"
