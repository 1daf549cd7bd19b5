"""What a sweep is: the grid of configurations (× independent replicates) and its result.

Shared by the DEM sweep (:mod:`jaxdamp.studies.sweep`) and the single-particle model's sweep
(:func:`jaxdamp.s3.impact.sweep`), which therefore do not import each other.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
from dataclasses import dataclass

import numpy as np

from jaxdamp.analysis import stats
from jaxdamp.config import Config, ConfigError, apply_overrides
from jaxdamp.physics.containers import container
from jaxdamp.validation import validate


@dataclass
class SweepResult:
    """``axes``: ``{key: values}``; ``configs``: one per point (grid order, last axis fastest);
    ``summary``: ``{name: array shaped like the grid}``; ``records``: per-point samples
    (dict of arrays ``(P, T)``); ``path``: the HDF5 file or ``None``; ``snapshots``: with
    ``sweep(..., snapshots=k)``, ``{"t": (k,), "r": (P, k, N, 3), "v": (P, k, N, 3),
    "z_box": (P, k)}`` at the ends of the last ``k`` chunks, else ``None``.

    With ``R = replicates`` independent beds per grid point, ``records`` and ``snapshots``
    have ``P = grid points × R`` rows (:meth:`point`), ``summary`` holds the mean over the
    replicates of each fixed-window value, ``replicate_summary`` the values of every replicate
    (grid shape + ``(R,)``), and ``steady`` the steady-state estimates over replicates from
    the detected steady state (:func:`jaxdamp.analysis.stats.steady`, as
    :func:`jaxdamp.analysis.stats.to_arrays`: ``{quantity: {"mean", "se", "ci95", "n",
    "values", "batch_se", "start", "stationary"}}``)."""

    axes: dict
    configs: list
    summary: dict
    records: dict
    path: str | None
    snapshots: dict | None = None
    replicates: int = 1
    replicate_summary: dict | None = None
    steady: dict | None = None

    def point(self, index: int, replicate: int = 0) -> int:
        """Row of grid point ``index`` (grid order), replicate ``replicate``, in ``records``
        and ``snapshots`` (replicates are the fastest axis)."""
        return index * self.replicates + replicate


class Points(dict):
    """Sweep axes **zipped into points** instead of crossed into a grid:
    ``Points({"box.Lz": [0.1, 0.12], "box.Lx": [0.03, 0.04]})`` runs point ``i`` at
    ``{key: values[i]}``. Any number of keys, all of one length; a key may be
    ``numerics.seed`` (integers), so that every point has its own bed. Used for designs of
    several variables (:mod:`jaxdamp.design.space`), where the points are scattered, not a
    grid. The sweep's arrays then have shape ``(points,)``."""

    layout = "points"

    def __init__(self, axes: dict):
        super().__init__({k: list(v) for k, v in axes.items()})
        lengths = {len(v) for v in self.values()}
        if len(lengths) > 1:
            raise ConfigError(f"Points: every key needs the same number of values, got "
                              f"{ {k: len(v) for k, v in self.items()} }")


def grid_shape(axes: dict) -> tuple:
    """Shape of a sweep's per-point arrays: one axis per key for a grid, ``(points,)`` for
    :class:`Points`."""
    if isinstance(axes, Points):
        return (len(next(iter(axes.values()))),)
    return tuple(len(v) for v in axes.values())


def _value(key: str, v):
    if isinstance(v, str):  # a name: a material of the table
        return v
    return int(v) if key.endswith(".seed") or key == "cells" else float(v)


def grid_configs(config: Config, axes: dict) -> list[Config]:
    """One configuration per grid point (``itertools.product`` order) — or per point of
    :class:`Points` — each validated."""
    keys = list(axes)
    if isinstance(axes, Points):
        rows = zip(*(axes[k] for k in keys))
    else:
        if len(keys) > 2:
            raise ConfigError(f"a sweep takes at most two axes (or Points), got {keys}")
        rows = itertools.product(*(axes[k] for k in keys))
    return [validate(apply_overrides(config, {k: _value(k, v) for k, v in zip(keys, values)}))
            for values in rows]


#: What may differ between configurations that share one settled bed (dotted keys of
#: ``Config.to_dict``): the excitation and the mount (a bed is poured into the container at
#: rest, its lid lifted: :func:`jaxdamp.engine.packing.settle_many`), the run's length and
#: sampling, and labels. The container's lid height is free too
#: (:attr:`jaxdamp.physics.containers.Container.lid_key`). Everything else keys the bed, so a
#: new field keys it unless it is added here.
BED_FREE = ("system", "frequency", "primary", "drive", "impactor", "random", "shock",
            "structure", "direction", "name", "notes", "numerics.duration", "numerics.chunk",
            "numerics.record_dt", "numerics.analysis_window")


def geometry_key(cfg: Config) -> str:
    """What the settled bed depends on: the configuration without :data:`BED_FREE` and the
    lid height."""
    d = cfg.to_dict()
    for key in BED_FREE + (container(cfg).lid_key,):
        *path, last = key.split(".")
        node = d
        for part in path:
            node = node[part]
        node.pop(last, None)
    return json.dumps(d, sort_keys=True)


def replicate_configs(grid: list[Config], replicates: int) -> list[Config]:
    """Every grid configuration repeated ``replicates`` times with the seeds of
    :func:`jaxdamp.analysis.stats.replicate_seed` (replicates fastest)."""
    if replicates < 1:
        raise ConfigError(f"replicates = {replicates}: need at least 1")
    return [c if k == 0 else dataclasses.replace(
                c, numerics=dataclasses.replace(
                    c.numerics, seed=stats.replicate_seed(c.numerics.seed, k)))
            for c in grid for k in range(replicates)]


def steady_or_window(res: SweepResult, key: str) -> tuple[np.ndarray, int]:
    """Per-replicate values of ``key`` (grid shape + ``(R,)``): the steady mean over the
    detected steady state where the replicate became stationary, else its fixed-window
    value (``summary``); and how many replicates fell back to the fixed window."""
    steady = res.steady[key]["values"]
    window = res.replicate_summary[key]
    ok = np.asarray(res.steady[key]["stationary"], bool) & np.isfinite(steady)
    return np.where(ok, steady, window), int((~ok).sum())


@dataclass(frozen=True)
class SteadyReplicates:
    """A replicated sweep read at its steady state (:func:`steady_replicates`).

    Attributes:
      values: one array per key, in the order asked, grid shape + ``(R,)``: each replicate's
        steady mean, or its fixed-window value where it was not detected stationary
        (:func:`steady_or_window`).
      fallback: per key, how many replicates fell back to the fixed window.
      stationary: whether each replicate was detected stationary in the first key, grid
        shape + ``(R,)`` (bool).
      wall: the sweep's compute time [s] (``summary["wall_time"]``: settling excluded).
    """

    values: tuple
    fallback: tuple
    stationary: np.ndarray
    wall: float


def steady_replicates(res: SweepResult, *keys: str) -> SteadyReplicates:
    """The steady reading of a sweep with replicates that a study of it starts from: the
    per-replicate values of ``keys`` (:func:`steady_or_window`; e.g. ``"amplitude"``,
    ``"granular_loss_per_cycle"``), how many of each fell back to the fixed window, which
    replicates the first key found stationary, and the sweep's compute time.

    Example::

        st = steady_replicates(res, "amplitude", "granular_loss_per_cycle")
        Z, W = st.values  # (F, R) each, for a sweep over frequency
        f"{st.stationary.sum()} of {st.stationary.size} runs detected stationary"
    """
    if not keys:
        raise ValueError("steady_replicates: name at least one key")
    read = [steady_or_window(res, k) for k in keys]
    return SteadyReplicates(tuple(v for v, _ in read), tuple(n for _, n in read),
                            np.asarray(res.steady[keys[0]]["stationary"], bool),
                            float(res.summary["wall_time"]))
