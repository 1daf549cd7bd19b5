"""What both S3 models share: the collision law, record and summary units, the run record
and its summary (``docs/physics.md`` §1)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from jaxdamp.analysis.response import first_harmonic
from jaxdamp.config import Config, ConfigError

#: Work channels of S3 records, columns of ``work``.
CHANNELS = ("input", "primary_damping", "impact")

RECORD_UNITS = {
    "t": "s",
    "z_box": "m",
    "v_box": "m/s",
    "z_particle": "m",
    "v_particle": "m/s",
    "u": "m",
    "work": "J",
    "energy": "J",
    "balance_residual": "J",
}

SUMMARY_UNITS = {
    "amplitude": "m",
    "amplitude_ratio": "1",
    "phase": "rad",
    "granular_loss_per_cycle": "J",
    "input_per_cycle": "J",
    "primary_damping_per_cycle": "J",
    "impact_per_cycle": "J",
    "impacts_per_cycle": "1",
    "balance_error": "1",
    "window_start": "s",
    "window_cycles": "1",
}

def collide(v_p, v_z, m, M, e):
    """Velocities just after an impact of particle and box (thesis eqs. 2.1.25–26, docs/physics.md §1 S3).

    Momentum ``m v_p + M v_z`` is conserved and the relative velocity reverses with factor
    ``e``: ``v_p+ - v_z+ = -e (v_p- - v_z-)``. Works on floats and (numpy / JAX) arrays.

    Args:
      v_p, v_z: particle and box velocities before the impact [m/s].
      m, M: particle and primary masses [kg]; e: restitution [-].
    Returns:
      ``(v_p+, v_z+)`` [m/s].
    """
    r = m / M
    v_z_new = ((1.0 - e * r) * v_z + r * (1.0 + e) * v_p) / (1.0 + r)
    v_p_new = ((1.0 + e) * v_z + (r - e) * v_p) / (1.0 + r)
    return v_p_new, v_z_new

def impact_loss(v_p, v_z, m, M, e):
    """Kinetic energy dissipated by one impact [J] (thesis eq. 5.3.1):
    ``ΔT = ½ (1 - e²) m/(1 + m/M) (v_p- - v_z-)²``."""
    return 0.5 * (1.0 - e * e) * m / (1.0 + m / M) * (v_p - v_z) ** 2

@dataclass
class ImpactRun:
    """One S3 run. ``records``: sampled series ``(T,)`` (``work`` ``(T, 3)``, columns
    :data:`CHANNELS`); ``impacts``: ``{"t", "loss", "wall" (0 floor, 1 lid), "v_rel"}`` arrays
    ``(I,)`` (event-driven only); ``summary`` and ``units``: :func:`summarize`."""

    records: dict
    impacts: dict
    summary: dict
    units: dict

def _check(config: Config) -> None:
    if config.system != "impact" or config.impactor is None or config.primary is None:
        raise ConfigError("the impact model needs system = 'impact' with [primary] and [impactor]")

def sample_interval(config: Config) -> float:
    """Bracketing interval [s] of the event search: 1/64 of the shorter of the drive period and
    the primary's undamped period (free), which resolves every sign change of the gap and force
    functions, whose fastest components oscillate at those periods."""
    p = config.primary
    return min(1.0 / config.frequency, 2 * math.pi * math.sqrt(p.M / p.K)) / 64.0

def n_records(config: Config) -> int:
    """Samples after t = 0: the run covers ``n_records * record_dt`` ≈ ``duration``."""
    return max(1, int(round(config.numerics.duration / config.numerics.record_dt)))

def _add_energy(config: Config, records: dict, contact_energy) -> None:
    """Mechanical energy and the balance residual ``E - E(0) + losses - input`` per sample."""
    p, m, g = config.primary, config.impactor.mass, config.gravity
    z, vz, y, vy, u = (records[k] for k in ("z_box", "v_box", "z_particle", "v_particle", "u"))
    energy = 0.5 * p.M * vz**2 + 0.5 * m * vy**2 + 0.5 * p.K * (z - u) ** 2 + m * g * y
    if contact_energy is not None:
        energy = energy + contact_energy
    w = records["work"]
    records["energy"] = energy
    records["balance_residual"] = energy - energy[0] + w[:, 1] + w[:, 2] - w[:, 0]

def summarize(config: Config, records: dict, z_max: float, z_min: float, t_window: float,
              impact_times=None) -> tuple[dict, dict]:
    """Steady-state scalars over the analysis window (as the DEM's
    :func:`jaxdamp.analysis.response.steady_state_summary`) and their units.

    ``z_max``, ``z_min``: extremes of ``z`` over ``t ≥ t_window`` (exact for the event-driven
    model, every step for the smooth one). Energies per drive period ``1/f``; ``balance_error``
    is the largest ``|residual|`` over the run over ``|input| + losses`` at its end;
    ``impacts_per_cycle`` counts impacts in the window (event-driven; NaN otherwise)."""
    t = records["t"]
    i0 = min(int(np.searchsorted(t, t_window - 1e-12)), len(t) - 1)
    w = records["work"]
    span = t[-1] - t[i0]
    cycles = span * config.frequency if span > 0 else np.nan
    s = {}
    s["amplitude"] = float(0.5 * (z_max - z_min))
    s["amplitude_ratio"] = s["amplitude"] / config.primary.U if config.primary.U > 0 else np.nan
    _, s["phase"] = first_harmonic(t[i0:], records["z_box"][i0:], config.frequency)
    per = (w[-1] - w[i0]) / cycles
    s["granular_loss_per_cycle"] = float(per[2])
    s["input_per_cycle"] = float(per[0])
    s["primary_damping_per_cycle"] = float(per[1])
    s["impact_per_cycle"] = float(per[2])
    if impact_times is None:
        s["impacts_per_cycle"] = np.nan
    else:
        n = np.count_nonzero((impact_times > t[i0]) & (impact_times <= t[-1]))
        s["impacts_per_cycle"] = float(n / cycles)
    scale = abs(w[-1, 0]) + w[-1, 1] + w[-1, 2]
    resid = float(np.max(np.abs(records["balance_residual"])))
    s["balance_error"] = resid / scale if scale > 0 else resid
    s["window_start"] = float(t[i0])
    s["window_cycles"] = float(cycles)
    return s, dict(SUMMARY_UNITS)
