"""Twin runs: the simulator's own measure of sensitive dependence on initial conditions.

Two copies of one driven damper run side by side in one batch; at ``t_perturb`` one grain of
the second copy is moved by ``delta`` (along x); from then on the distance between the two
copies' observables (``z_box``, ``z_cm``, …) grows exponentially with the largest Lyapunov
exponent of the whole simulated system if the motion is chaotic, and stays at the level of
the perturbation if it is regular (:func:`jaxdamp.analysis.dynamics.divergence_exponent`).

Unlike an exponent estimated from one scalar series (Kantz's method on a delay embedding,
:func:`jaxdamp.analysis.dynamics.lyapunov_kantz`), this needs no embedding, so it is not
limited by the embedding dimension a short series supports — a bed of N grains has 6N + 2
phase-space dimensions (≈ 1500 for 250 grains) and no scalar record resolves an attractor of
high dimension. What it cannot tell: the exponent belongs to the whole system, so a bed whose
grains rattle chaotically while the box motion stays nearly periodic shows the grains'
divergence, transmitted to the box only as far as the grains' forces reach it; and it
includes the amplification of round-off, which is the same process (a perturbation of
1e-9 m and one of 1e-16 m grow alike).

Example::

    from jaxdamp.cases import presets
    from jaxdamp.studies.twin import twin_sweep
    res = twin_sweep(presets.get("sanchez2012-optimal"), [14.5], t_perturb=2.0,
                     out="twin.h5")                  # rows 0, 1: reference, perturbed
"""

from __future__ import annotations

import os

import h5py

from jaxdamp.config import Config, ConfigError
from jaxdamp.io.sweepfile import perturb_checkpoint
from jaxdamp.studies.grid import Points, SweepResult
from jaxdamp.studies.sweep import sweep

#: Root attribute of the sweep file once the perturbation has been applied to its checkpoint.
PERTURBED = "twin_perturbed"


def twin_axes(frequencies) -> Points:
    """Every frequency twice (reference, perturbed), as zipped points."""
    return Points({"frequency": [float(f) for f in frequencies for _ in (0, 1)]})


def twin_sweep(config: Config, frequencies, t_perturb: float, out: str, delta: float = 1e-9,
               grain: int = 0, progress: bool = True) -> SweepResult:
    """Run reference/perturbed pairs at every frequency; rows ``2i`` and ``2i + 1`` of the
    result's records are the pair at ``frequencies[i]``.

    The batch runs to the chunk boundary at ``t_perturb`` [s] (a multiple of
    ``numerics.chunk``), the checkpoint in ``out`` is changed (grain ``grain`` of every
    second system moved by ``delta`` [m] along x; the file records it), and the batch
    resumes to ``numerics.duration``. A killed run resumes where it stopped, before or
    after the perturbation; a finished file is read back.
    """
    n = config.numerics
    k = t_perturb / n.chunk
    if not (0 < t_perturb < n.duration) or abs(k - round(k)) > 1e-9:
        raise ConfigError(f"t_perturb = {t_perturb} s: must lie inside (0, numerics.duration "
                          f"= {n.duration} s) on a chunk boundary (numerics.chunk = {n.chunk} s)")
    if not 0 < delta < 1e-3 * min(g.radius for g in config.grains):
        raise ConfigError(f"delta = {delta} m: must be > 0 and far below the grain radius")
    if not 0 <= grain < config.n_grains:
        raise ConfigError(f"grain = {grain}: the bed has {config.n_grains} grains")
    axes = twin_axes(frequencies)
    perturbed = False
    if os.path.exists(out):
        with h5py.File(out, "r") as h:
            perturbed = bool(h.attrs.get(PERTURBED, False))
    if not perturbed:
        sweep(config, axes, out=out, resume=os.path.exists(out), progress=progress,
              max_chunks=int(round(k)), echo=print if progress else None)
        perturb_checkpoint(out, grain, delta, int(round(k)), PERTURBED,
                           f"grain {grain} of rows 1, 3, ... moved by {delta:g} m along x "
                           f"at t = {t_perturb:g} s")
    return sweep(config, axes, out=out, resume=True, progress=progress,
                 echo=print if progress else None)
