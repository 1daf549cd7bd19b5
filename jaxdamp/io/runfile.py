"""HDF5 run files: configuration, time series, snapshots, summary and checkpoint.

Schema of a run file (every dataset has a ``units`` attribute; see ``docs/output.md``)::

    /                       attrs: format, jaxdamp_version, created, config (JSON), system,
                                   preset, status ('running' | 'finished' | 'diverged' |
                                   'interrupted' | 'partial'), message, dt, duration, engine,
                                   engine_reason (the engine that ran it and why:
                                   jaxdamp.engine.choice; --resume keeps it)
    /grains/radius (N,)     m        /grains/mass (N,) kg      /grains/species (N,)
    /settle                 attrs: bed_height [m], time [s], max_speed [m/s], settled (bool:
                            every grain below numerics.settle_speed before settle_time ran out);
                            r0 (N,3) settled positions (box frame) [m]
    /series/<name> (T,)     sampled time series (see jaxdamp.physics.energy.RECORD_UNITS);
    /series/work (T, 10)    cumulative work channels, attr 'channels'
    /snapshots/t (S,)       s;  /snapshots/r (S,N,3) m;  /snapshots/q (S,N,4) unit quaternions
    /summary                attrs: steady-state scalars (units in attr 'units' JSON)
    /steady/<quantity>/...  steady-state estimates from the detected steady state
                            (:func:`jaxdamp.io.common.write_steady`; as in sweep files)
    /checkpoint             the full state and neighbour list after the last finished chunk
"""

from __future__ import annotations

import json

import h5py
import numpy as np

from jaxdamp.config import Config
from jaxdamp.io import claims
from jaxdamp.io.common import append as _append
from jaxdamp.io.common import damaged_series, stamp
from jaxdamp.io.common import write_checkpoint as _write_checkpoint

FORMAT = "jaxdamp-run/1"


class RunFile:
    """A run file open for writing (single system), claimed by this process while open
    (:mod:`jaxdamp.io.claims`: a second writer is refused before it can truncate it)."""

    def __init__(self, path: str, mode: str = "a"):
        self.path = path
        claims.claim(path)
        try:
            self.h5 = h5py.File(path, mode)
        except BaseException:
            claims.release(path)
            raise

    # -- creation -------------------------------------------------------------------------
    @classmethod
    def create(cls, path: str, config: Config, radii, masses, species, bed, extra_attrs=None):
        f = cls(path, "w")
        h = f.h5
        stamp(h, FORMAT, config=config.to_json(), system=config.system, preset=config.name,
              status="running", message="", **(extra_attrs or {}))
        g = h.create_group("grains")
        g.create_dataset("radius", data=np.asarray(radii)).attrs["units"] = "m"
        g.create_dataset("mass", data=np.asarray(masses)).attrs["units"] = "kg"
        g.create_dataset("species", data=np.asarray(species))
        g.attrs["species_names"] = json.dumps([s.name for s in config.grains])
        s = h.create_group("settle")
        s.attrs["bed_height"] = bed.height
        s.attrs["time"] = bed.time
        s.attrs["max_speed"] = bed.max_speed
        s.attrs["settled"] = bool(getattr(bed, "settled", True))
        s.attrs["units"] = json.dumps({"bed_height": "m", "time": "s", "max_speed": "m/s"})
        s.create_dataset("r0", data=bed.r).attrs["units"] = "m"
        h.create_group("series")
        h.create_group("snapshots")
        h.create_group("summary")
        h.flush()
        return f

    # -- appending -------------------------------------------------------------------------
    def append_records(self, recs: dict, n: int | None = None) -> None:
        """Append samples (dict of arrays with leading time axis); only the first ``n``."""
        from jaxdamp.physics.energy import RECORD_UNITS  # JAX: imported when a run writes
        from jaxdamp.physics.model import CHANNELS

        g = self.h5["series"]
        for name, values in recs.items():
            values = np.asarray(values)[:n] if n is not None else np.asarray(values)
            if name == "work":
                _append(g, name, values, RECORD_UNITS[name], channels=json.dumps(CHANNELS))
            else:
                _append(g, name, values, RECORD_UNITS[name])

    def n_records(self) -> int:
        g = self.h5["series"]
        return g["t"].shape[0] if "t" in g else 0

    def append_snapshot(self, t, r, q) -> None:
        g = self.h5["snapshots"]
        _append(g, "t", np.asarray([t]), "s")
        _append(g, "r", np.asarray(r)[None], "m")
        _append(g, "q", np.asarray(q)[None], "1")

    def truncate(self, n_records: int, n_snapshots: int) -> None:
        """Drop samples written after the last checkpoint (a killed run's tail)."""
        for gname, n in (("series", n_records), ("snapshots", n_snapshots)):
            for ds in self.h5[gname].values():
                if ds.shape[0] > n:
                    ds.resize(n, axis=0)

    # -- checkpoint --------------------------------------------------------------------------
    def write_checkpoint(self, arrays: dict, attrs: dict) -> None:
        """Store ``arrays`` (exact float64/int copies) and ``attrs`` under ``/checkpoint``,
        after the samples before it are flushed (:func:`jaxdamp.io.common.write_checkpoint`)."""
        _write_checkpoint(self.h5, arrays, attrs)

    def read_checkpoint(self) -> tuple[dict, dict] | None:
        if "checkpoint" not in self.h5:
            return None
        g = self.h5["checkpoint"]
        arrays = {}
        g.visititems(lambda name, obj: arrays.__setitem__(name, obj[()])
                     if isinstance(obj, h5py.Dataset) else None)
        return arrays, dict(g.attrs)

    # -- end ---------------------------------------------------------------------------------
    def write_summary(self, summary: dict, units: dict) -> None:
        g = self.h5["summary"]
        for k, v in summary.items():
            g.attrs[k] = v
        g.attrs["units"] = json.dumps(units)

    def set_status(self, status: str, message: str = "") -> None:
        self.h5.attrs["status"] = status
        self.h5.attrs["message"] = message
        self.h5.flush()

    def flush(self):
        self.h5.flush()

    def close(self):
        try:
            self.h5.close()
        finally:
            claims.release(self.path)


def read_config(path: str) -> Config:
    """The configuration stored in a run file."""
    from jaxdamp.config import from_json

    with h5py.File(path, "r") as h:
        return from_json(h.attrs["config"])


def _container_words(cfg: dict) -> str:
    """The container of a stored configuration in words: ``box 0.04 × 0.04 × 0.12 m``."""
    if cfg.get("box") is not None:
        b = cfg["box"]
        return f"box {b['Lx']} × {b['Ly']} × {b['Lz']} m"
    c = cfg.get("container") or {}
    dims = ", ".join(f"{k} {v} m" for k, v in c.items() if k not in ("shape", "Lz", "wall"))
    return f"{c.get('shape', '?')} ({dims}), height {c.get('Lz', '?')} m"


def describe_lines(h, path: str) -> list[str]:
    """Human-readable overview of an open run file (``jaxdamp info``)."""
    lines = []
    cfg = json.loads(h.attrs["config"])
    lines.append(f"{path}: {h.attrs.get('format', '?')} (run file), jaxdamp "
                 f"{h.attrs.get('jaxdamp_version', '?')}")
    lines.append(f"  preset {h.attrs.get('preset')}, system {h.attrs.get('system')}, "
                 f"status {h.attrs.get('status')} {h.attrs.get('message', '')}".rstrip())
    lines.append(f"  frequency {cfg['frequency']} Hz, {_container_words(cfg)}, "
                 f"{sum(s['count'] for s in cfg['grains'])} grains")
    if "settle" in h:
        lines.append(f"  settled bed height {h['settle'].attrs['bed_height']:.5g} m "
                     f"after {h['settle'].attrs['time']:.4g} s"
                     + ("" if h["settle"].attrs.get("settled", True) else
                        f" — NOT settled (fastest grain still at "
                        f"{h['settle'].attrs['max_speed']:.3g} m/s)"))
    if "series" in h and "t" in h["series"]:
        t = h["series/t"]
        if t.shape[0]:
            lines.append(f"  {t.shape[0]} samples, t = {t[0]:.5g} … {t[-1]:.5g} s; series: "
                         + ", ".join(sorted(h["series"])))
    if "snapshots" in h and "t" in h["snapshots"]:
        lines.append(f"  {h['snapshots/t'].shape[0]} snapshots")
    if (why := damage(h)) is not None:
        lines.append(f"  WARNING: this file is damaged: {why}; its numbers cannot be trusted")
    if "summary" in h and len(h["summary"].attrs):
        units = json.loads(h["summary"].attrs.get("units", "{}"))
        lines.append("  summary:")
        for k, v in h["summary"].attrs.items():
            if k != "units":
                lines.append(f"    {k} = {v} {units.get(k, '')}".rstrip())
    return lines


#: Larger than any physical value a run file holds in SI units (metres, joules, newtons).
IMPOSSIBLE = 1e100


def damage(h) -> str | None:
    """Why the open run file ``h`` cannot hold the samples of a run — its sampled times not
    increasing (:func:`jaxdamp.io.common.damaged_series`: a disk that filled leaves zeros), or
    series with non-finite or impossibly large values (overwritten bytes; HDF5 keeps no
    checksums here) — or ``None``."""
    g = h.get("series")
    if g is None or "t" not in g:
        return None
    n = g["t"].shape[0]
    if h.attrs.get("status") == "diverged":
        return damaged_series(g["t"][()], n)  # its last samples may be non-finite: the reason
    bad = [k for k, ds in g.items()
           if ds.dtype.kind == "f" and ds.size
           and not (np.isfinite(v := ds[()]).all() and np.abs(v).max() < IMPOSSIBLE)]
    why = damaged_series(g["t"][()], n)
    if bad:
        why = (why + "; " if why else "") + "non-finite or impossible values in " + ", ".join(bad)
    return why
