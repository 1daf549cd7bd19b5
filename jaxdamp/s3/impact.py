"""S3: the single-particle impact damper (docs/physics.md §1 S3; thesis §2.1.3, §5.3.2).

The whole bed is replaced by one point mass ``m`` that moves vertically between the floor
(``y = z``) and the lid (``y = z + gap``) of the box, which is the primary ``M`` on the spring
``K`` and damper ``C`` of S1, driven through the base ``u = U cos Ωt``. ``z = 0`` is the static
equilibrium of the empty box, so gravity ``g`` acts on the particle only. SI units throughout.

Two models of the same system:

* **Event-driven** (:mod:`jaxdamp.s3.event`, :func:`~jaxdamp.s3.event.simulate_event`), exact
  up to round-off. Collisions are instants
  (:func:`collide`, restitution ``e``, momentum conserved). Between events every motion is in
  closed form: the particle flies on a parabola, the primary obeys
  ``M_ef z'' = -C(z' - u') - K(z - u) + F0`` (free: ``M_ef = M, F0 = 0``; particle resting on
  the floor or pressed against the lid: ``M_ef = M + m, F0 = -m g``), i.e. homogeneous
  (under-, critically or over-damped) + particular harmonic + constant. Events (impacts, lift
  off) are roots of smooth gap / contact-force functions, bracketed by sampling every
  ``min(1/f, 2π sqrt(M/K)) / 64`` (with a check of every local minimum between samples, so
  grazing contacts are not skipped) and refined by Brent's method to ~1e-14 s. The particle
  leaves the floor when ``z'' < -g`` and the lid when ``z'' > -g``. For ``e > 0`` the
  geometric series of ever smaller bounces (inelastic collapse, "chattering") is cut: when the
  relative speed after an impact is below ``impactor.stick_speed`` and the contact force
  would be compressive, the particle sticks (a perfectly inelastic impact; its small extra
  loss ``½ m/(1+m/M) v_rel²`` is booked as impact loss so the energy balance still closes).
  Work integrals use 8-point Gauss–Legendre on sub-intervals ≤ 1/64 of the fastest period,
  which is exact to round-off for these analytic integrands. Compiled with numba.

* **Smooth** (:mod:`jaxdamp.s3.smooth`, :func:`~jaxdamp.s3.smooth.smooth_run`), for ``jax.grad``: the particle is a point mass with
  penalty contacts (linear spring-dashpot, force clipped ≥ 0, onset smoothed over a length
  ``smooth_width`` by a softplus/sigmoid so that the trajectory is a smooth function of the
  parameters), integrated by velocity Verlet with a fixed step in a jitted ``lax.scan`` and
  batched with ``vmap``. The dashpot's damping ratio ``ζ`` is calibrated
  (:func:`contact_damping_ratio`) so that a free binary collision of the clipped law has
  restitution ``e`` (clamped to ``≥ SMOOTH_E_MIN``: a clipped linear dashpot cannot reach
  ``e = 0``); the stiffness follows from the contact duration ``impactor.contact_time``.
  Defaults, from measurements on the thesis case (``sanchez2012-impact``, e = 0):
  ``contact_time = 3e-4 s`` (1e-3 s is too soft: with the strongly over-damped dashpot the
  particle creeps out of the wall for ~18 contact times and the response at 16.6 Hz became
  irregular, +24 %), 20 steps per contact (dt ≈ 1.5e-5 s; balance error ~1e-6), and
  ``smooth_width = 3e-5 m``: the onset must span a few steps at typical impact speeds
  (w ≳ v dt), else the tangent dynamics explode (1e-6 m: d z/d gap grew ×10 per 0.1 s;
  1e-5 m still diverged; 3e-5 m bounded) although the forward run is fine. Measured
  agreement with the event-driven model: amplitude within 1 % around resonance
  (14.5–16.6 Hz), within 3.5 % over 5–25 Hz except in irregular (non-periodic) responses,
  where the windowed amplitude itself fluctuates by ±5 % (6 % at 20.8 Hz).

Every run starts with the particle resting on the floor and the box at rest at the static
equilibrium ``z = -m g/K``.

Both return the summary of the DEM sweeps (:func:`jaxdamp.s3.common.summarize`): ``amplitude`` (half
peak-to-peak of ``z`` over the analysis window), ``amplitude_ratio``, ``phase``,
``granular_loss_per_cycle`` (= impact loss per drive period), ``input_per_cycle``,
``primary_damping_per_cycle``, ``balance_error``, ``window_start``, ``window_cycles`` plus
``impacts_per_cycle``. Work channels (:data:`CHANNELS`): ``input`` (base through spring and
damper), ``primary_damping`` (loss in C), ``impact`` (dissipated at impacts / in the contact).
Energy ``E = ½ M z'² + ½ m y'² + ½ K (z - u)² + m g y (+ ½ k s² of the penalty springs)``; the
balance ``W_input = E - E(0) + W_primary_damping + W_impact``.

Note on the collision law: docs/physics.md §1 and thesis eq. 2.1.26 print ``v_p+ = ((1 - e) v_z- + ...)``;
momentum conservation (and the thesis' own code, appendix B) need ``(1 + e) v_z-``, used here.
"""

from __future__ import annotations

import time

import numpy as np

from jaxdamp import interrupt
from jaxdamp.config import Config, ConfigError
from jaxdamp.s3.common import CHANNELS, RECORD_UNITS, SUMMARY_UNITS, ImpactRun, _check
from jaxdamp.s3.event import simulate_event
from jaxdamp.s3.smooth import simulate_smooth, smooth_schedule


def simulate(config: Config) -> ImpactRun:
    """One S3 run with ``impactor.method`` (``"event"`` or ``"smooth"``)."""
    _check(config)
    if config.impactor.method == "smooth":
        return simulate_smooth([config])[0]
    return simulate_event(config)

def sweep(config: Config, axes: dict, out: str | None = None, progress: bool = True,
          echo=print):
    """The S3 counterpart of :func:`jaxdamp.studies.sweep.sweep`: same grid, same
    :class:`~jaxdamp.studies.grid.SweepResult`, same HDF5 layout (``/summary``, ``/axes``,
    ``/records`` ``(P, T)``). ``"smooth"`` runs all points as one ``vmap`` batch; ``"event"``
    loops over them (numba; one core each)."""
    from jaxdamp.io.sweepfile import SweepFile
    from jaxdamp.studies.grid import SweepResult, grid_configs, grid_shape

    for key in axes:
        if key.startswith(("box.", "grains")):
            raise ConfigError(f"sweep axis {key!r}: the impact model (S3) does not use the box or "
                              "grains; sweep impactor.gap, impactor.mass, impactor.restitution, "
                              "primary.*, frequency")
    configs = grid_configs(config, axes)
    method = configs[0].impactor.method
    say = echo or (lambda *a, **k: None)
    wall0 = time.perf_counter()
    if method == "smooth":
        say(f"impact model (smooth): {len(configs)} points in one batch")
        runs = simulate_smooth(configs)
        dt = smooth_schedule(configs)[0]
    else:
        bar = None
        if progress:
            from tqdm.auto import tqdm

            bar = tqdm(total=len(configs), unit="point", desc="impact model (event-driven)")
        runs = []
        try:
            for c in configs:
                interrupt.check()  # a safe point between points (Ctrl-C: nothing is written)
                runs.append(simulate_event(c))
                if bar is not None:
                    bar.update(1)
        finally:
            if bar is not None:
                bar.close()
        dt = 0.0
    wall = time.perf_counter() - wall0
    shape = grid_shape(axes)
    summary = {k: np.array([r.summary[k] for r in runs]).reshape(shape) for k in runs[0].summary}
    summary["wall_time"] = wall
    records = {k: np.stack([r.records[k] for r in runs]) for k in runs[0].records}
    n_rec = records["t"].shape[1] - 1
    duration = n_rec * configs[0].numerics.record_dt
    if out:
        sf = SweepFile.create(out, config, axes, configs, dt, duration, f"impact-{method}",
                              engine_reason=f"the S3 impact model ({method})")
        sf.write_summary(summary, SUMMARY_UNITS)
        sf.write_records(records, RECORD_UNITS, channels=CHANNELS)
        if method == "event":
            ig = sf.h5.create_group("impacts")
            for i, r in enumerate(runs):
                g = ig.create_group(str(i))
                for k, v in r.impacts.items():
                    g.create_dataset(k, data=v)
        sf.finish(wall)
        sf.close()
    return SweepResult(axes=axes, configs=configs, summary=summary, records=records, path=out)
