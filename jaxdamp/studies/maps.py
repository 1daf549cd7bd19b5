"""The damper's effective-field maps: the damper alone, its container moved harmonically along
its axis, over an amplitude × frequency grid with independent beds (``jaxdamp map``; issue 40;
Meyer & Seifried, Granular Matter 23, 2021: "effective fields"; Yang's power measurement).

The container moves as ``z = A cos Ωt`` (the prescribed mount, S2; ``Ω = 2π f``), every grid
point and bed in one batch. The grains' force on it along the axis, ``F(t)``, read as a force
``−m_eff z̈ − c_eff ż`` (its first harmonic ``F̂ = (m_eff Ω² − i Ω c_eff) Ẑ``), defines per point
and bed, over whole periods of the bed's steady state:

* the **effective damping** ``c_eff = E_input / (π Ω A²)`` [N s/m], from ``E_input``, the
  container's work on the grains per cycle (the ``input`` work channel, integrated at every
  step): on a harmonic motion only the force's first harmonic does work, ``π c_eff Ω A²`` per
  cycle, so this is exact; ``c_force``, the same read off the force's first harmonic
  (:func:`jaxdamp.analysis.response.grain_force_coefficients` on the force samples), is kept
  as a check — the samples, 64 per period of the fastest drive, alias the impacts' high
  harmonics into it by about a per cent;
* the **effective mass** ``m_eff`` [kg], the force's in-phase part (``m_p`` where the bed
  moves with the container, less where it flies, negative where it strikes in antiphase);
  ``phase = arg(F̂/Ẑ)``;
* the **dissipated energy per cycle** ``E_diss`` [J]: the grains' contact losses from the work
  channels (:func:`jaxdamp.analysis.stats.per_period`). In a steady state it equals
  ``E_input``; over a finite window they differ by the bed's energy change (a bed that still
  creeps spends its own potential energy in friction);
* the **specific damping capacity** ``ψ = E_diss / (½ m_p (Ω A)²)``: the loss per cycle over
  the largest kinetic energy of the grains moving with the container (Friend & Kinra's measure,
  taken per unit of the granulate), and the **loss factor** ``η = ψ / 2π`` (the linear
  relation between the two; not ``c_eff / (Ω m_eff)``, which diverges where the bed's
  effective mass passes through zero, as a flying bed's does).

Each bed's steady state is detected from its own per-period losses (MSER,
:func:`jaxdamp.analysis.stats.steady`; a bed not found stationary falls back to the whole
periods of the run's final ``analysis_window``); every quantity is kept per bed and reported
as mean ± SE over beds. The maps feed the harmonic balance of
:mod:`jaxdamp.analysis.harmonic_balance` (the map inserted into a structure).

Example (a small map of the thesis' damper; about a minute on 2 cores)::

    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.studies import maps
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), ["numerics.settle_time=0.1"])
    m = maps.measure(cfg, [0.005, 0.01], [14.0, 15.0], periods=3, transient=1, replicates=2)
    m.mean("c_eff"), m.se("c_eff")   # (2, 2) each: amplitude × frequency
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from jaxdamp.config import Config, ConfigError, Drive

#: The map's quantities per grid point and bed, with their units.
UNITS = {"E_diss": "J", "E_input": "J", "m_eff": "kg", "c_eff": "N s/m", "phase": "rad",
         "psi": "1", "eta": "1", "c_force": "N s/m"}
#: What each quantity is (the files' ``what`` attributes; the figures' labels).
LABELS = {"E_diss": "dissipated energy per cycle E_diss", "m_eff": "effective mass m_eff",
          "c_eff": "effective damping c_eff", "phase": "phase of F̂/Ẑ",
          "psi": "specific damping capacity ψ", "eta": "loss factor η",
          "E_input": "the container's work on the grains per cycle",
          "c_force": "effective damping from the force's first harmonic (a check of c_eff)"}
#: Samples per period of the fastest drive (the force's first harmonic and the cycle edges).
SAMPLES_PER_PERIOD = 64


def alone(config: Config, amplitude: float | None = None) -> Config:
    """The damper of ``config`` alone: its container(s) and grains under the prescribed motion
    ``z = A cos Ωt`` (system ``driven``; all its cells, which must then share one degree of
    freedom: the map is the whole damper's), the primary, structure and any base excitation
    dropped. ``amplitude`` [m]: the drive's (default: the config's drive, or the primary's
    ``U``)."""
    if config.system == "impact":
        raise ConfigError("map: a damper of grains is needed (system = 'impact' models a "
                          "single particle; use a box or container preset)")
    if not config.grains:
        raise ConfigError("map: the configuration has no grains (grains = [])")
    from jaxdamp.physics.structure import attachments

    if len(set(attachments(config))) > 1:
        raise ConfigError(f"map: the {config.cells} cells sit on degrees of freedom "
                          f"{list(attachments(config))} (structure.attach): a map moves the "
                          "whole damper as one; map the cells of one degree of freedom (set "
                          "cells and structure.attach to them)")
    if amplitude is None:
        amplitude = (config.drive.amplitude if config.drive is not None
                     else config.primary.U if config.primary is not None else 0.0)
    return config.replace(system="driven", drive=Drive(amplitude=float(amplitude)),
                          primary=None, structure=None, random=None, shock=None)


def grid_errors(amplitudes, frequencies) -> list[str]:
    """What is wrong with a map's grid, one line per fault (empty: nothing)."""
    out = []
    for name, v, unit in (("amplitudes", amplitudes, "m"), ("frequencies", frequencies, "Hz")):
        v = np.asarray(v, float)
        if v.ndim != 1 or v.size < 1:
            out.append(f"{name}: give at least one value [{unit}]")
        elif not np.all(np.isfinite(v)) or v.min() <= 0:
            out.append(f"{name} {v.tolist()}: every value must be a finite number > 0 {unit}")
        elif len(np.unique(v)) != v.size:
            out.append(f"{name} {v.tolist()}: values repeat")
    return out


def check(amplitudes, frequencies, periods: int, transient: int) -> None:
    """Refuse a map's grid or timing in one :class:`ConfigError` naming every fault and its
    limit (no compute, no JAX)."""
    faults = grid_errors(amplitudes, frequencies)
    for name, value, low in (("periods", periods, 2), ("transient", transient, 0)):
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            faults.append(f"{name} = {value!r}: must be an integer ≥ {low}")
    if faults:
        raise ConfigError("map: " + "; ".join(faults))


def protocol(config: Config, amplitudes, frequencies, periods: int = 20,
             transient: int = 5) -> Config:
    """``config`` alone (:func:`alone`) with the timing of a map: ``transient + periods``
    periods of the slowest drive (faster ones run more), ``SAMPLES_PER_PERIOD`` samples per
    period of the fastest, one time step for the whole batch (the collision time at the
    loudest point, the largest ``A Ω``), the fixed-window fallback over the last ``periods``.
    Raises :class:`ConfigError` naming the parameter and its limit, before any compute."""
    check(amplitudes, frequencies, periods, transient)
    from jaxdamp.physics.model import config_dt, grain_radii

    f_lo, f_hi, a_hi = min(frequencies), max(frequencies), max(amplitudes)
    loud = alone(config, a_hi).replace(frequency=float(f_hi))
    dt = config_dt(loud, grain_radii(loud))
    record_dt = 1.0 / (f_hi * SAMPLES_PER_PERIOD)
    dt = record_dt / math.ceil(record_dt / dt * (1 - 1e-12))  # the samples on the step grid
    total = transient + periods
    num = dataclasses.replace(loud.numerics, dt=dt, record_dt=record_dt, duration=total / f_lo,
                              chunk=min(loud.numerics.chunk, total / f_lo),
                              analysis_window=periods / total)
    return alone(config).replace(numerics=num)


@dataclasses.dataclass(frozen=True)
class EffectiveField:
    """A measured map (:func:`measure`; read back by :func:`read`).

    Attributes:
      amplitudes: drive amplitudes ``A`` [m], ``(A,)``.
      frequencies: drive frequencies ``f`` [Hz], ``(F,)``.
      values: per quantity of :data:`UNITS`, per point and bed ``(A, F, R)``.
      stationary: whether each bed's steady state was detected ``(A, F, R)``.
      start: each bed's steady start [s] (where the fallback window began otherwise).
      grain_mass: the granulate's mass ``m_p`` [kg].
      config: the map's configuration (the damper alone, its timing).
      wall_time: the batch's compute time [s] (settling excluded).
    """

    amplitudes: np.ndarray
    frequencies: np.ndarray
    values: dict
    stationary: np.ndarray
    start: np.ndarray
    grain_mass: float
    config: Config
    wall_time: float = float("nan")

    @property
    def replicates(self) -> int:
        return int(self.stationary.shape[-1])

    def mean(self, q: str) -> np.ndarray:
        """Mean over beds ``(A, F)``."""
        return np.asarray(self.values[q]).mean(axis=-1)

    def se(self, q: str) -> np.ndarray:
        """Standard error over beds ``(A, F)`` (NaN for one bed)."""
        from jaxdamp.analysis.uncertainty import standard_error

        return standard_error(np.asarray(self.values[q]), axis=-1)

    def bed(self, r: int) -> "EffectiveField":
        """The map of bed ``r`` alone (``R = 1``): the harmonic balance per bed."""
        k = slice(r, r + 1)
        return dataclasses.replace(self, values={q: v[..., k] for q, v in self.values.items()},
                                   stationary=self.stationary[..., k], start=self.start[..., k])


def analyse(res, grain_mass: float) -> dict:
    """The map's quantities per point and bed ``(A, F, R)`` from a finished sweep over
    ``(drive.amplitude, frequency)`` with replicates (module docstring): every quantity of a
    bed over the same whole periods, from its detected steady start (else from the first
    period edge of the run's final ``analysis_window``) to its last whole period."""
    from jaxdamp.analysis.response import grain_force_coefficients
    from jaxdamp.analysis.stats import per_period

    A = np.asarray(res.axes["drive.amplitude"], float)
    f = np.asarray(res.axes["frequency"], float)
    st = res.steady["granular_loss_per_cycle"]
    stationary = np.asarray(st["stationary"], bool)
    shape = (len(A), len(f), stationary.shape[-1])
    num = res.configs[0].numerics
    fallback = num.duration * (1.0 - num.analysis_window)
    start = np.zeros(shape)
    out = {q: np.zeros(shape) for q in ("E_diss", "E_input", "m_eff", "c_force")}
    rec = res.records
    for i, j, r in np.ndindex(shape):
        k = res.point(i * len(f) + j, r)
        t = np.asarray(rec["t"][k])
        t0 = (float(st["start"][i, j, r]) if stationary[i, j, r]
              else math.ceil(fallback * f[j] - 1e-9) / f[j])
        series = per_period({q: rec[q][k] for q in ("t", "z_box", "work")}, f[j],
                            channels=("input",))
        steady = series["t_start"] >= t0 - 1e-9
        n = int(steady.sum())
        start[i, j, r] = t0
        out["E_diss"][i, j, r] = series["granular_loss_per_cycle"][steady].mean()
        out["E_input"][i, j, r] = series["input_per_cycle"][steady].mean()
        keep = t <= t0 + n / f[j] + 1e-9  # the same whole periods
        g = grain_force_coefficients(t[keep], np.asarray(rec["z_box"][k])[keep],
                                     np.asarray(rec["force_box"][k])[keep], f[j],
                                     t_start=t0, interval=float(t[1] - t[0]))
        out["m_eff"][i, j, r], out["c_force"][i, j, r] = g["m_add"], g["c_add"]
    W = 2.0 * math.pi * f[None, :, None]
    A2 = A[:, None, None] ** 2
    c = out["E_input"] / (math.pi * W * A2)
    kinetic = 0.5 * grain_mass * W * W * A2
    values = dict(out, c_eff=c, phase=np.angle(out["m_eff"] * W * W - 1j * W * c),
                  psi=out["E_diss"] / kinetic, eta=out["E_diss"] / (2.0 * math.pi * kinetic))
    return dict(values={q: values[q] for q in UNITS}, stationary=stationary, start=start)


def measure(config: Config, amplitudes, frequencies, periods: int = 20, transient: int = 5,
            replicates: int = 3, out: str | None = None, progress: bool = True,
            echo=print) -> EffectiveField:
    """Measure the map of ``config``'s damper over ``amplitudes`` [m] × ``frequencies`` [Hz]
    with ``replicates`` independently poured beds, all in one batch (:func:`protocol`'s
    timing). With ``out`` the sweep file is reused or resumed when it holds this very map
    (:func:`jaxdamp.studies.sweep.reuse_or_run`) and the map is written into its ``/map``
    group (:mod:`jaxdamp.io.maps`)."""
    from jaxdamp.physics.model import grain_mass
    from jaxdamp.studies import sweep as sw

    if isinstance(replicates, bool) or not isinstance(replicates, int) or replicates < 1:
        raise ConfigError(f"map: replicates = {replicates!r}: must be an integer ≥ 1")
    A = [float(a) for a in amplitudes]
    F = [float(x) for x in frequencies]
    cfg = protocol(config, A, F, periods, transient)
    axes = {"drive.amplitude": A, "frequency": F}
    kw = dict(progress=progress, echo=echo, replicates=int(replicates))
    res = sw.reuse_or_run(cfg, axes, out, **kw) if out else sw.sweep(cfg, axes, **kw)
    m_p = grain_mass(cfg)
    a = analyse(res, m_p)
    field = EffectiveField(amplitudes=np.asarray(A), frequencies=np.asarray(F),
                           values=a["values"], stationary=a["stationary"], start=a["start"],
                           grain_mass=m_p, config=cfg,
                           wall_time=float(res.summary["wall_time"]))
    if out:
        from jaxdamp.io import maps as map_file

        map_file.write(out, field, periods=periods, transient=transient, units=UNITS,
                       labels=LABELS)
    return field


def read(path: str) -> EffectiveField:
    """The map :func:`measure` stored in the sweep file ``path`` (its ``/map`` group)."""
    from jaxdamp.io import maps as map_file

    return _field(map_file.read(path))


def from_group(g) -> EffectiveField:
    """The map in a ``map`` group (:func:`jaxdamp.io.maps.put_map`): an open h5py group, or a
    study file's as :func:`jaxdamp.io.study.load` reads it."""
    from jaxdamp.io import maps as map_file

    return _field(map_file.fields(g))


def _field(d: dict) -> EffectiveField:
    from jaxdamp.config import from_dict, from_json

    c = d.pop("config")
    return EffectiveField(config=from_json(c) if isinstance(c, str) else from_dict(c), **d)
