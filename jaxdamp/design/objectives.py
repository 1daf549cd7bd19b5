"""Design objectives of a particle damper (``docs/physics.md`` §7).

An objective maps the steady response of the primary at one or more frequencies to a number
a designer wants large or small. Each is defined once here from the two steady-state
quantities every model reports per frequency ``f`` (``Ω = 2π f``): the amplitude ``Z`` [m]
of the primary and the energy ``E`` [J] the grains dissipate per drive period.

* ``damping`` (default, maximised) — the **equivalent viscous damping added by the grains**,
  ``C_eq = E / (π Ω Z²)`` [N s/m]: a dashpot ``C_eq`` moving at amplitude ``Z`` dissipates
  ``π C_eq Ω Z²`` per period. At the resonance of the loaded primary it is the thesis'
  ``C_ef − C`` from a single frequency; it has an interior optimum in the gap (too small a
  box, the bed moves with it; too large, it hardly hits the lid).
* ``amplitude`` (minimised) — ``Z`` at one frequency.
* ``band`` (minimised) — the smooth maximum of ``Z`` over a band of frequencies,
  ``(Σ_f Z_f^p)^{1/p}`` (``p = 16``).
* ``dissipation`` (maximised) — ``E`` at one frequency. Documented hazard: on the thesis'
  damper at ``f0`` it grows monotonically with ``Lz`` over every box tried (a taller box lets
  the bed fall further and hit harder while the primary's amplitude grows), so maximising it
  drives the design to the upper bound; it stays available, and the optimiser warns when an
  objective's optimum sits on a bound.

Example::

    >>> from jaxdamp.design.objectives import Objective
    >>> obj = Objective("damping", frequency=15.0)
    >>> round(float(obj.combine(Z=[0.03], E=[7.0])), 3)  # 7 J per period at 3 cm, 15 Hz
    26.268
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.config import Config, ConfigError
from jaxdamp.physics.model import primary_frequency

OBJECTIVES = ("damping", "amplitude", "band", "dissipation")
#: Objectives that are maximised (the others are minimised).
MAXIMISE = ("damping", "dissipation")
#: The objective used when none is named.
DEFAULT = "damping"
#: Exponent of the p-norm smooth maximum of the band objective.
BAND_P = 16.0
#: Units of the objectives.
UNITS = {"damping": "N s/m", "amplitude": "m", "band": "m", "dissipation": "J"}


def smooth_max(z, p=BAND_P):
    """``(Σ z^p)^(1/p)`` of positive ``z`` (scaled, no overflow; differentiable)."""
    z = jnp.asarray(z)
    s = jax.lax.stop_gradient(jnp.max(z))
    return s * jnp.sum((z / s) ** p) ** (1.0 / p)


def equivalent_damping(E, Z, frequency):
    """``C_eq = E / (π Ω Z²)`` [N s/m] from the dissipation per period ``E`` [J] at amplitude
    ``Z`` [m] and frequency [Hz] (arrays broadcast)."""
    return np.asarray(E) / (math.pi * 2 * math.pi * np.asarray(frequency) * np.asarray(Z) ** 2)


@dataclass(frozen=True)
class Objective:
    """What to optimise: ``kind`` in :data:`OBJECTIVES`; ``frequency`` [Hz] for the
    single-frequency objectives (``None``: the primary's ``f0 = sqrt(K/M)/2π``); ``band`` [Hz]
    the frequencies of the ``band`` objective (``None``: 9 points over ``f0 ± 10 %``); ``p``
    the exponent of its smooth maximum."""

    kind: str = DEFAULT
    frequency: float | None = None
    band: tuple | None = None
    p: float = BAND_P

    def __post_init__(self):
        if self.kind not in OBJECTIVES:
            raise ConfigError(f"objective {self.kind!r}: expected one of {OBJECTIVES}")

    @property
    def maximise(self) -> bool:
        return self.kind in MAXIMISE

    @property
    def unit(self) -> str:
        return UNITS[self.kind]

    def frequencies(self, config: Config) -> tuple:
        f0 = primary_frequency(config) or config.frequency
        if self.kind == "band":
            if self.band:
                return tuple(float(f) for f in self.band)
            return tuple(float(f) for f in np.linspace(0.9 * f0, 1.1 * f0, 9))
        return (float(self.frequency or f0),)

    def combine(self, Z, E, frequencies=None):
        """The objective from per-frequency amplitudes ``Z`` [m] and dissipations ``E`` [J per
        period], arrays whose first axis runs over :meth:`frequencies` (further axes, e.g.
        replicates, are kept). ``frequencies`` defaults to ``(self.frequency,)``. Pure
        ``jax.numpy``: differentiable, and numpy inputs give numpy-convertible output."""
        Z = jnp.asarray(Z)
        E = jnp.asarray(E)
        f = jnp.asarray(frequencies if frequencies is not None else (self.frequency,), Z.dtype)
        f = f.reshape((-1,) + (1,) * (Z.ndim - 1))
        if self.kind == "damping":
            return E[0] / (math.pi * 2 * math.pi * f[0] * Z[0] ** 2)
        if self.kind == "dissipation":
            return E[0]
        if self.kind == "amplitude":
            return Z[0]
        s = jax.lax.stop_gradient(jnp.max(Z, axis=0))
        return s * jnp.sum((Z / s) ** self.p, axis=0) ** (1.0 / self.p)

    def to_json(self, config: Config) -> str:
        return json.dumps({"kind": self.kind, "frequencies": list(self.frequencies(config)),
                           "p": self.p, "maximise": self.maximise, "unit": self.unit})


@dataclass
class Estimate:
    """One evaluation of a problem at a design point: objective ``value`` and derivative
    ``grad`` w.r.t. the design variable [unit/m] with their standard errors (0 for exact
    values, NaN where there is no error estimate); ``sim_seconds``: simulated
    system-seconds it cost; ``wall`` [s]; ``extra``: per-replicate values etc."""

    value: float
    value_se: float
    grad: float
    grad_se: float
    sim_seconds: float
    wall: float
    extra: dict = field(default_factory=dict)
