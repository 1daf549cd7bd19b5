"""HDF5 sweep files: many systems of one damper (a grid × replicates), DEM or S3.

Layout (``docs/output.md``, "Sweep file schema")::

    /                       attrs: format, jaxdamp_version, created, base_config (JSON), axes
                                   (JSON), replicates, configs (JSON list), dt, duration,
                                   engine, engine_reason (the engine that ran it and why:
                                   jaxdamp.engine.choice), devices, wave_size (systems per
                                   wave: jaxdamp.studies.sweep), status, message, wall_time
    /axes/<key>             the swept values
    /records/<name>         (P, T, ...) samples of every point × replicate (replicates fastest)
    /checkpoint             batched state and neighbour lists after the last finished chunk
                            (attrs chunk, wave: of the running wave's systems)
    /snapshots/...          t (S,), r, v (P, S, N, 3), z_box (P, S)
    /summary/<name>         grid-shaped mean over replicates of each fixed-window scalar
    /replicate_summary/...  grid + (R,)
    /system_summary/<name>  (P,) per system, written at the end of its wave (sweeps in waves)
    /steady/<quantity>/...  steady-state estimates over replicates (:func:`write_steady`)
    /settle/...             per system: settled (bool), time, max_speed, bed_height; attr
                            unsettled (count of beds that did not settle)
    /fit/...                FRF fits (``jaxdamp frf``; ok/failure flag failed fits)
    /impacts/<point>/...    S3 event-driven only
    /efficiency/...         ``jaxdamp efficiency`` only (:mod:`jaxdamp.io.efficiency`)
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping

import h5py
import numpy as np

from jaxdamp.analysis.response import FIT_MAX_RELATIVE_SE, fit_failure
from jaxdamp.config import is_stored
from jaxdamp.io import claims
from jaxdamp.io.common import (
    damaged_checkpoint,
    damaged_message,
    damaged_series,
    outdated_checkpoint,
    put,
    stamp,
    write_checkpoint,
    write_steady,
)

FORMAT = "jaxdamp-sweep/1"
SNAPSHOT_UNITS = {"r": "m", "v": "m/s", "z_box": "m"}


def axes_json(axes: dict, replicates: int = 1) -> str:
    """The ``axes`` attribute: ``{key: values}`` (plus ``replicates`` when > 1, and
    ``"layout": "points"`` for zipped axes, :class:`jaxdamp.studies.grid.Points`)."""
    d = {k: list(map(float, v)) for k, v in axes.items()}
    if getattr(axes, "layout", "grid") == "points":
        d["layout"] = "points"
    if replicates > 1:
        d["replicates"] = int(replicates)
    return json.dumps(d)


def holds(path: str, config, axes: dict, replicates: int = 1) -> bool:
    """Whether the sweep file ``path`` exists, holds the sweep ``(config, axes, replicates)``
    and has a checkpoint to continue from or reuse."""
    if not os.path.exists(path):
        return False
    try:
        with h5py.File(path, "r") as h5:
            return (is_stored(h5.attrs.get("base_config"), config)
                    and h5.attrs.get("axes") == axes_json(axes, replicates)
                    and "checkpoint" in h5)
    except OSError:  # not an HDF5 file (e.g. cut short while being created)
        return False


class SweepFile:
    """A sweep file open for writing, claimed by this process while open
    (:mod:`jaxdamp.io.claims`)."""

    def __init__(self, h5: h5py.File):
        self.h5 = h5
        self.path = h5.filename

    @staticmethod
    def _open(path: str, mode: str) -> h5py.File:
        claims.claim(path)
        try:
            return h5py.File(path, mode)
        except BaseException:
            claims.release(path)
            raise

    @classmethod
    def create(cls, path: str, config, axes: dict, configs: list, dt: float, duration: float,
               engine: str, replicates: int = 1, devices: int = 1,
               engine_reason: str = "", wave_size: int | None = None) -> "SweepFile":
        """A new sweep file; ``engine`` computes it and ``engine_reason`` says why
        (:func:`jaxdamp.engine.choice.choose`); ``wave_size`` systems run at once (all of
        them when ``None``)."""
        h5 = cls._open(path, "w")
        stamp(h5, FORMAT, base_config=config.to_json(), axes=axes_json(axes, replicates),
              replicates=int(replicates), configs=json.dumps([c.to_json() for c in configs]),
              dt=float(dt), duration=float(duration), engine=engine,
              engine_reason=engine_reason, devices=int(devices),
              wave_size=int(len(configs) if wave_size is None else wave_size),
              status="running", message="")
        h5.create_group("records")
        ag = h5.create_group("axes")
        for k, v in axes.items():
            put(ag, k, np.asarray(v, float))
        return cls(h5)

    def write_settle(self, beds, settle_speed, rows: range | None = None,
                     total: int | None = None) -> None:
        """``/settle``: per system (point × replicate, in ``configs`` order) the settled bed's
        ``settled`` flag (every grain below ``settle_speed`` before ``settle_time`` ran out),
        ``time`` [s], ``max_speed`` [m/s] and ``bed_height`` [m]; the group's attribute
        ``unsettled`` counts the systems whose bed did not settle. ``rows`` of ``total``: one
        wave's systems (the others keep theirs; not yet settled: ``settled`` false, NaN)."""
        g = self.h5.require_group("settle")
        values = {"settled": (np.array([bool(b.settled) for b in beds]), "1"),
                  "time": (np.array([b.time for b in beds], float), "s"),
                  "max_speed": (np.array([b.max_speed for b in beds], float), "m/s"),
                  "bed_height": (np.array([b.height for b in beds], float), "m"),
                  "settle_speed": (np.asarray(settle_speed, float), "m/s")}
        for k, (v, unit) in values.items():
            if rows is None:
                put(g, k, v, unit)
                continue
            if k not in g:
                put(g, k, np.zeros(total, bool) if v.dtype == bool else np.full(total, np.nan),
                    unit)
            g[k][rows.start:rows.stop] = v
        settled_yet = np.isfinite(g["time"][()])  # waves not yet started: NaN
        g.attrs["unsettled"] = int((~g["settled"][()] & settled_yet).sum())
        self.h5.flush()

    @classmethod
    def resume(cls, path: str, config, axes: dict, replicates: int, records_per_chunk: int,
               rows: range | None = None):
        """Open ``path`` to continue the sweep: ``(file, checkpoint arrays, chunk, compute time
        so far)``; samples after the checkpoint are dropped (in the first wave; a later wave,
        ``rows``, overwrites its rows). Refuses a different sweep."""
        from jaxdamp.config import ConfigError

        arrays, chunk, wall = cls.checkpoint_of(path, config, axes, replicates)
        first = rows is None or rows.start == 0
        with h5py.File(path, "r") as h5:
            n = chunk * records_per_chunk
            t = (h5["records/t"][slice(None) if rows is None else slice(rows.start, rows.stop)]
                 if "t" in h5["records"] else None)
            why = (damaged_series(t, n) if t is not None
                   else f"its checkpoint counts {n} samples but the file holds none" if n
                   else None)
        if why is not None:
            raise ConfigError(damaged_message(path, why))
        h5 = cls._open(path, "a")
        if first:
            for ds in h5["records"].values():
                ds.resize(chunk * records_per_chunk, axis=1)
        return cls(h5), arrays, chunk, wall

    @staticmethod
    def wave_of(path: str) -> int:
        """The wave the checkpoint of the sweep file ``path`` belongs to (0 without waves)."""
        with h5py.File(path, "r") as h5:
            return int(h5["checkpoint"].attrs.get("wave", 0))

    @staticmethod
    def attrs_of(path: str) -> dict:
        """The root attributes of the sweep file ``path`` (read only)."""
        with h5py.File(path, "r") as h5:
            return dict(h5.attrs)

    @staticmethod
    def checkpoint_of(path: str, config, axes: dict, replicates: int):
        """``(checkpoint arrays, chunk, compute time so far)`` of the sweep in ``path``, read
        only (every process of a sweep across hosts reads it; one writes). Refuses a different
        sweep."""
        from jaxdamp.config import ConfigError

        with h5py.File(path, "r") as h5:
            if (not is_stored(h5.attrs["base_config"], config)
                    or h5.attrs["axes"] != axes_json(axes, replicates)):
                raise ConfigError(f"--resume: {path} holds a different sweep")
            g = h5["checkpoint"]
            chunk = int(g.attrs["chunk"])
            wall = float(h5.attrs.get("wall_time", h5["summary/wall_time"][()]
                                      if "summary/wall_time" in h5 else 0.0))
            arrays = {}
            g.visititems(lambda n, o: arrays.__setitem__(n, o[()])
                         if isinstance(o, h5py.Dataset) else None)
            series = list(h5["records"].keys()) if "records" in h5 else []
        if (why := damaged_checkpoint(arrays)) is not None:
            raise ConfigError(damaged_message(path, why))
        if (refusal := outdated_checkpoint(arrays, path, series)) is not None:
            raise ConfigError(refusal)
        return arrays, chunk, wall

    # -- while running --------------------------------------------------------------------
    def append_records(self, recs: dict, at: int | None = None, rows: range | None = None,
                       total: int | None = None) -> None:
        """Write samples ``(P, T, ...)`` at sample ``at`` (default: after the last) along the
        time axis; ``rows`` of ``total`` systems: one wave's."""
        from jaxdamp.physics.energy import RECORD_UNITS

        g = self.h5["records"]
        for k, v in recs.items():
            v = np.asarray(v)
            systems = v.shape[0] if rows is None else total
            if k not in g:
                ds = g.create_dataset(k, shape=(systems, 0) + v.shape[2:], dtype=v.dtype,
                                      maxshape=(systems, None) + v.shape[2:], chunks=True)
                ds.attrs["units"] = RECORD_UNITS.get(k, "")
            ds = g[k]
            n0 = ds.shape[1] if at is None else at
            if ds.shape[1] < n0 + v.shape[1]:
                ds.resize(n0 + v.shape[1], axis=1)
            if rows is None:
                ds[:, n0:n0 + v.shape[1]] = v
            else:
                ds[rows.start:rows.stop, n0:n0 + v.shape[1]] = v

    def write_checkpoint(self, arrays: dict, chunk: int, wall_time: float,
                         wave: int = 0) -> None:
        """``/checkpoint`` after ``chunk`` chunks of wave ``wave``, written whole after the
        samples before it (:func:`jaxdamp.io.common.write_checkpoint`)."""
        self.h5.attrs["wall_time"] = wall_time
        write_checkpoint(self.h5, arrays, {"chunk": chunk, "wave": wave})

    def append_snapshot(self, t: float, per_point: dict, rows: range | None = None,
                        total: int | None = None) -> None:
        """Append the batch's ``r``, ``v`` ``(P, N, 3)`` and ``z_box`` ``(P,)`` at time ``t``
        (resumable: a snapshot at or before the last stored time overwrites from there);
        ``rows`` of ``total`` systems: one wave's, at the time the first wave stored."""
        g = self.h5.require_group("snapshots")
        P = next(iter(per_point.values())).shape[0] if rows is None else total
        if rows is not None and rows.start > 0:  # a later wave: the times are stored
            n = int(np.searchsorted(g["t"][()], t - 1e-12))
            for k, x in per_point.items():
                g[k][rows.start:rows.stop, n] = x
            self.h5.flush()
            return
        if "t" not in g:
            g.create_dataset("t", shape=(0,), maxshape=(None,), dtype="f8").attrs["units"] = "s"
            for k, x in per_point.items():
                g.create_dataset(k, shape=(P, 0) + x.shape[1:], maxshape=(P, None) + x.shape[1:],
                                 chunks=True, dtype="f8").attrs["units"] = SNAPSHOT_UNITS[k]
        n = g["t"].shape[0]
        if n and float(g["t"][n - 1]) >= t:  # a resumed sweep re-running a stored chunk
            n = int(np.searchsorted(g["t"][()], t))
        g["t"].resize(n + 1, axis=0)
        g["t"][n] = t
        for k, x in per_point.items():
            g[k].resize(n + 1, axis=1)
            g[k][slice(None) if rows is None else slice(rows.start, rows.stop), n] = x
        self.h5.flush()

    def set_status(self, status: str, message: str = "") -> None:
        self.h5.attrs["status"] = status
        self.h5.attrs["message"] = message
        self.h5.flush()

    # -- results --------------------------------------------------------------------------
    def records(self, rows: range | None = None) -> dict:
        """Every sample, or the samples of the systems ``rows``."""
        part = slice(None) if rows is None else slice(rows.start, rows.stop)
        return {k: self.h5["records"][k][part] for k in self.h5["records"]}

    def write_system_summary(self, summaries: list[dict], units: dict, rows: range,
                             total: int) -> None:
        """``/system_summary/<name>`` ``(total,)``: the fixed-window summaries of the systems
        ``rows`` (one wave's, NaN until their wave ends)."""
        g = self.h5.require_group("system_summary")
        for k in summaries[0]:
            if k not in g:
                put(g, k, np.full(total, np.nan), units.get(k, ""))
            g[k][rows.start:rows.stop] = [s[k] for s in summaries]
        self.h5.flush()

    def system_summaries(self) -> tuple[list[dict], dict]:
        """The per-system summaries of ``/system_summary`` and their units."""
        g = self.h5["system_summary"]
        values = {k: g[k][()] for k in g}
        n = len(next(iter(values.values())))
        return ([{k: float(v[i]) for k, v in values.items()} for i in range(n)],
                {k: str(g[k].attrs.get("units", "")) for k in g})

    def snapshots(self) -> dict:
        if "snapshots" not in self.h5:
            return {}
        return {k: self.h5["snapshots"][k][()] for k in self.h5["snapshots"]}

    def write_summary(self, summary: dict, units: dict, per_replicate: dict | None = None,
                      steady: dict | None = None, replicates: int = 1, steady_units=None) -> None:
        """``/summary/<name>`` (grid-shaped), ``/replicate_summary/<name>`` (grid + ``(R,)``)
        and ``/steady`` (:func:`write_steady`)."""
        sg = self.h5.require_group("summary")
        for k, v in summary.items():
            put(sg, k, v, units.get(k, "s" if k == "wall_time" else ""))
        if per_replicate is not None:
            rg = self.h5.require_group("replicate_summary")
            rg.attrs["replicates"] = replicates
            for k, v in per_replicate.items():
                put(rg, k, v, units.get(k, ""))
        if steady is not None:
            write_steady(self.h5, steady, replicates, steady_units)

    def write_records(self, records: dict, units: dict, channels=None) -> None:
        """All samples at once (S3 sweeps)."""
        rg = self.h5.require_group("records")
        for k, v in records.items():
            put(rg, k, v, units.get(k, ""))
        if channels is not None and "work" in rg:
            rg["work"].attrs["channels"] = json.dumps(list(channels))

    def finish(self, wall_time: float) -> None:
        self.h5.attrs["wall_time"] = wall_time
        self.set_status("finished")

    def close(self) -> None:
        try:
            self.h5.close()
        finally:
            claims.release(self.path)


class StoredRecords(Mapping):
    """The samples of a sweep file read on demand: ``records[name]`` is a view whose
    ``[rows]`` (an index, a slice) reads those systems' samples, and ``np.asarray`` the whole
    dataset — the ``records`` of a sweep that ran in waves (:func:`jaxdamp.studies.sweep.sweep`),
    whose samples need not fit in memory together."""

    def __init__(self, path: str):
        self.path = path
        with h5py.File(path, "r") as h5:
            self._names = tuple(h5["records"])

    def __getitem__(self, name: str) -> "_StoredRows":
        if name not in self._names:
            raise KeyError(name)
        return _StoredRows(self.path, name)

    def __iter__(self):
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)


class _StoredRows:
    """One record of a sweep file, read by rows (:class:`StoredRecords`)."""

    def __init__(self, path: str, name: str):
        self.path, self.name = path, name
        with h5py.File(path, "r") as h5:
            self.shape = h5["records"][name].shape

    def __len__(self) -> int:
        return self.shape[0]

    def __getitem__(self, key):
        with h5py.File(self.path, "r") as h5:
            ds = h5["records"][self.name]
            if isinstance(key, (list, np.ndarray)):  # h5py wants increasing unique indices
                key = np.asarray(key)
                order, back = np.unique(key, return_inverse=True)
                return ds[order][back]
            return ds[key]

    def __array__(self, dtype=None, copy=None):
        with h5py.File(self.path, "r") as h5:
            x = h5["records"][self.name][()]
        return x if dtype is None else x.astype(dtype)


def perturb_checkpoint(path: str, grain: int, delta: float, chunk: int, flag: str,
                       note: str) -> None:
    """Move grain ``grain`` of every second system (rows 1, 3, …) of the checkpoint in
    ``path`` by ``delta`` [m] along x, and mark the file (root attribute ``flag`` = True,
    ``"twin"`` = ``note``). Refuses a checkpoint not at ``chunk``. Used by twin runs
    (:mod:`jaxdamp.studies.twin`)."""
    with h5py.File(path, "a") as h:
        at = int(h["checkpoint"].attrs["chunk"])
        if at != int(chunk):
            raise RuntimeError(f"{path}: checkpoint at chunk {at}, expected {chunk} "
                               "(the file holds another run)")
        r = h["checkpoint/state/r"]
        r[1::2, grain, 0] = r[1::2, grain, 0] + delta
        h.attrs[flag] = True
        h.attrs["twin"] = note


def write_fit(h5, fits: dict, used: str) -> None:
    """``/fit`` of an FRF sweep file: ``M_ef``, ``C_ef`` (the ``used`` weighting), their
    standard errors across replicates ``se_M_ef``, ``se_C_ef``, the fit of the mean FRF
    ``M_ef_of_mean``, ``C_ef_of_mean`` with its Jacobian errors ``fit_se_M_ef``,
    ``fit_se_C_ef``, ``ok`` (bool: the fit is a result by the one rule,
    :func:`jaxdamp.analysis.response.fit_failure`) and ``failure`` (why not, ``""`` when ok),
    and ``<weighting>/...`` for every weighting (:data:`jaxdamp.analysis.response.RESIDUALS`),
    one entry per ``Lz``. The group's attribute ``failed`` counts the failed fits of the
    ``used`` weighting, ``max_relative_se`` states the rule's limit; the values of a failed fit
    are kept as computed, for diagnosis only."""
    if "fit" in h5:
        del h5["fit"]
    g = h5.create_group("fit")
    g.attrs["residuals"] = used
    g.attrs["replicates"] = int(fits[used][0]["replicates"])
    g.attrs["max_relative_se"] = FIT_MAX_RELATIVE_SE

    def fill(grp, fl):
        for name, key, unit in (("M_ef", "M_ef", "kg"), ("C_ef", "C_ef", "N s/m"),
                                ("se_M_ef", "se_M", "kg"), ("se_C_ef", "se_C", "N s/m"),
                                ("M_ef_of_mean", "M_mean_fit", "kg"),
                                ("C_ef_of_mean", "C_mean_fit", "N s/m"),
                                ("fit_se_M_ef", "fit_se_M", "kg"),
                                ("fit_se_C_ef", "fit_se_C", "N s/m")):
            put(grp, name, np.array([f[key] for f in fl]), unit)
        why = [fit_failure(f) for f in fl]
        put(grp, "ok", np.array([not w for w in why]), "1")
        put(grp, "failure", np.array(why, dtype=h5py.string_dtype()), "")
        grp.attrs["failed"] = int(sum(bool(w) for w in why))

    fill(g, fits[used])
    for w, fl in fits.items():
        fill(g.create_group(w), fl)


def describe_lines(h, path: str) -> list[str]:
    """Human-readable overview of an open sweep file (``jaxdamp info``)."""
    cfg = json.loads(h.attrs["base_config"])
    axes = json.loads(h.attrs.get("axes", "{}"))
    R = int(h.attrs.get("replicates", 1))
    layout = axes.pop("layout", "grid")
    axes.pop("replicates", None)
    n = len(json.loads(h.attrs.get("configs", "[]")))
    lines = [f"{path}: {h.attrs.get('format', '?')} (sweep file), jaxdamp "
             f"{h.attrs.get('jaxdamp_version', '?')}",
             f"  {cfg.get('name')} ({cfg.get('system')}), engine {h.attrs.get('engine')}, "
             f"status {h.attrs.get('status')} {h.attrs.get('message', '')}".rstrip(),
             f"  {n} systems = {layout} of "
             + (" × " if layout == "grid" else ", ").join(
                 f"{k} ({len(v)}: {min(v):.5g} … {max(v):.5g})" for k, v in axes.items())
             + (f" × {R} replicates" if R > 1 else "")
             + f"; {float(h.attrs.get('duration', 0)):.4g} s each, dt {float(h.attrs.get('dt', 0)):.3g} s"]
    W = int(h.attrs.get("wave_size", n))
    waves = -(-n // W) if W else 1
    if waves > 1:
        lines.append(f"  run in {waves} waves of {W} systems")
    if "checkpoint" in h and h.attrs.get("status") != "finished":
        wave = int(h["checkpoint"].attrs.get("wave", 0))
        lines.append(f"  checkpoint after chunk {int(h['checkpoint'].attrs.get('chunk', 0))}"
                     + (f" of wave {wave + 1}/{waves}" if waves > 1 else "")
                     + " (resumable with --resume)")
    parts = [g for g in ("summary", "replicate_summary", "steady", "fit", "efficiency",
                         "snapshots", "impacts") if g in h]
    if parts:
        lines.append("  groups: " + ", ".join(f"/{g}" for g in parts))
    if "summary" in h:
        keys = sorted(k for k in h["summary"] if k != "wall_time")
        lines.append("  summary: " + ", ".join(keys))
    if "settle" in h and int(h["settle"].attrs.get("unsettled", 0)):
        lines.append(f"  {int(h['settle'].attrs['unsettled'])} of {h['settle/settled'].shape[0]} "
                     "beds did NOT settle (/settle/settled)")
    if "fit" in h:
        lines.append("  FRF fit: " + ", ".join(sorted(h["fit"])))
        failed = int(h["fit"].attrs.get("failed", 0))
        if failed:
            lines.append(f"  FRF fit FAILED for {failed} curve(s): "
                         + "; ".join(str(w, "utf-8") if isinstance(w, bytes) else str(w)
                                     for w in h["fit/failure"][()] if w))
    return lines
