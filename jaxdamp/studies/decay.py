"""Free-decay tests of the primary (S1): ring-downs from given initial displacements, each on
``R`` independently poured beds in one batch, and the damper's characteristic curves ζ(Z),
f(Z) (:mod:`jaxdamp.analysis.decay`).

Example::

    from jaxdamp.cases import presets
    from jaxdamp.studies import decay
    res = decay.measure(presets.get("sanchez2012-optimal"), [0.02], duration=3.0, replicates=3)
    res.curves[0]["zeta"]          # ζ on res.curves[0]["Z"], mean over the 3 beds
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from jaxdamp.analysis.decay import decay_curve, on_amplitudes
from jaxdamp.config import Config, ConfigError, apply_overrides


@dataclasses.dataclass
class DecayResult:
    """Free decays from the initial displacements ``z0`` [m] ``(P,)``: ``cycles[i][r]`` each
    bed's per-cycle arrays (``t, Z, zeta, f`` and the granular ratio ``zeta_g``), ``curves[i]`` their mean ± SE on a common
    amplitude grid (:func:`jaxdamp.analysis.decay.on_amplitudes`); ``zeta_struct`` the empty
    box's ratio ``C / (2√(K (M + m_p)))`` (grains as dead mass), ``f_n`` the undamped
    frequency with the grains as dead mass [Hz]; ``sweep`` the underlying
    :class:`jaxdamp.studies.grid.SweepResult` (records, configuration, file)."""

    z0: np.ndarray
    cycles: list
    curves: list
    zeta_struct: float
    f_n: float
    replicates: int
    sweep: object


def free_decay_config(config: Config, v0: float = 0.0) -> Config:
    """``config`` as a free-decay test: S1 with the base at rest (``primary.U = 0``) and the
    primary's initial velocity ``v0`` [m/s]. Refuses other systems."""
    if config.system != "primary":
        raise ConfigError(f"system = {config.system!r}: a free decay needs the primary (S1, "
                          "system 'primary')")
    if not math.isfinite(v0):
        raise ConfigError(f"v0 = {v0!r}: must be a finite number [m/s]")
    return apply_overrides(config, {"primary.U": 0.0, "primary.v0": float(v0)})


def measure(config: Config, z0, duration: float | None = None, v0: float = 0.0,
            replicates: int = 1, out: str | None = None, resume: bool = False,
            progress: bool = True, echo=print, grid: int = 40,
            reuse: bool = False) -> DecayResult:
    """Ring the primary down from each initial displacement ``z0`` [m] (and velocity ``v0``
    [m/s]), ``replicates`` beds each, as one batch (:func:`jaxdamp.studies.sweep.sweep`; with
    ``out`` the file, resumable, gets a ``/decay`` group). ``duration`` [s]: simulated time
    (default: the configuration's). ``grid``: amplitudes of the common curve. ``reuse``: a
    finished ``out`` of the same test is read back and a partial one resumed, anything else
    replaced (experiments; ``resume`` refuses a different test instead)."""
    from jaxdamp.physics.energy import granular_loss
    from jaxdamp.physics.model import grain_mass
    from jaxdamp.studies.runner import initial_box_position
    from jaxdamp.studies.sweep import sweep

    z0 = np.atleast_1d(np.asarray(z0, float))
    if not np.all(np.isfinite(z0)):
        raise ConfigError(f"z0 = {z0.tolist()}: every initial displacement must be finite [m]")
    if v0 == 0.0 and np.any(z0 == 0.0):
        raise ConfigError(f"z0 = {z0.tolist()}, v0 = 0: nothing to decay — every test needs an "
                          "initial displacement z0 ≠ 0 [m] or a velocity v0 ≠ 0 [m/s]")
    cfg = free_decay_config(config, v0)
    if duration is not None:
        cfg = apply_overrides(cfg, {"numerics.duration": float(duration)})
    p = cfg.primary
    m_p = grain_mass(cfg)
    if p.K <= 0:
        raise ConfigError(f"primary.K = {p.K}: a free decay needs a spring (K > 0)")
    f_n = math.sqrt(p.K / (p.M + m_p)) / (2 * math.pi)
    zeta_struct = p.C / (2.0 * math.sqrt(p.K * (p.M + m_p)))
    R = int(replicates)
    axes = {"primary.z0": list(z0)}
    if reuse and out:
        from jaxdamp.io.sweepfile import holds

        resume = holds(out, cfg, axes, R)
    res = sweep(cfg, axes, out=out, resume=resume, progress=progress,
                echo=echo, replicates=R)
    if res is None:
        return None
    z_eq = initial_box_position(apply_overrides(cfg, {"primary.z0": 0.0}), m_p)
    cycles, curves = [], []
    for i in range(len(z0)):
        per = [decay_curve(res.records["t"][k], res.records["z_box"][k], z_eq, f_n,
                           loss=granular_loss(res.records["work"][k]), K=p.K)
               for k in (res.point(i, r) for r in range(R))]
        cycles.append(per)
        Zs = np.concatenate([c["Z"] for c in per]) if per else np.zeros(0)
        if len(Zs) >= 2:
            Z_grid = np.geomspace(Zs.min(), Zs.max(), grid)
        else:
            Z_grid = np.zeros(0)
        curves.append(on_amplitudes(per, Z_grid))
    result = DecayResult(z0=z0, cycles=cycles, curves=curves, zeta_struct=zeta_struct, f_n=f_n,
                         replicates=R, sweep=res)
    if out:
        from jaxdamp.io import decay as decay_file

        decay_file.write(out, result)
    return result
