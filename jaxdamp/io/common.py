"""What every jaxdamp file shares: attributes with provenance, datasets with units, appendable
datasets, the steady-state estimates group, and the safety of every resumable file: its
checkpoint replaced whole (:func:`write_checkpoint`), room checked before each chunk
(:func:`ensure_space`), damage found before a resume (:func:`damaged_series`). (The checkpoint form of a state is the
driver's: :func:`jaxdamp.engine.driver.checkpoint`.)"""

from __future__ import annotations

import json
import os
import time

import numpy as np

from jaxdamp import __version__


def stamp(h5, fmt: str, **attrs) -> None:
    """Root attributes of every file: ``format``, ``jaxdamp_version``, ``created``, ``units``
    and ``attrs`` (JSON-encoded unless a string or number)."""
    h5.attrs["format"] = fmt
    h5.attrs["jaxdamp_version"] = __version__
    h5.attrs["created"] = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    h5.attrs["units"] = "SI (m, kg, s, N, J, W); angles in rad"
    for k, v in attrs.items():
        h5.attrs[k] = v if isinstance(v, (str, int, float, np.number)) else json.dumps(v)


def put(group, name: str, data, units: str = "", replace: bool = True, **attrs):
    """A dataset ``name`` in ``group`` with a ``units`` attribute (replacing one there)."""
    if replace and name in group:
        del group[name]
    ds = group.create_dataset(name, data=np.asarray(data))
    ds.attrs["units"] = units
    for k, v in attrs.items():
        ds.attrs[k] = v
    return ds


def append(group, name, values, units=None, **attrs):
    values = np.asarray(values)
    if name not in group:
        ds = group.create_dataset(
            name, data=values, maxshape=(None,) + values.shape[1:], chunks=True
        )
        if units is not None:
            ds.attrs["units"] = units
        for k, v in attrs.items():
            ds.attrs[k] = v
        return
    ds = group[name]
    n0 = ds.shape[0]
    ds.resize(n0 + values.shape[0], axis=0)
    ds[n0:] = values



def write_steady(h5, steady: dict, replicates: int, units) -> None:
    """``/steady/<quantity>/{mean, se, ci95, n, values, batch_se, start, stationary}``: the
    steady-state estimates of :func:`jaxdamp.analysis.stats.to_arrays` (grid-shaped ``mean`` … ``n``,
    grid + ``(R,)`` for the rest), with units, the number of replicates and the method in
    attributes. ``units(quantity)`` gives the unit of a quantity. Used by run and sweep files."""
    from jaxdamp.analysis.stats import DETECT_ON

    if "steady" in h5:
        del h5["steady"]
    st = h5.create_group("steady")
    st.attrs["replicates"] = int(replicates)
    st.attrs["method"] = (
        "per-period series; start of the steady state by MSER on " + ", ".join(DETECT_ON)
        + " (the later of the two; at least 1 period dropped, 5 kept); mean +- standard error "
        "across independent replicates (Student-t 95 % half-width in ci95; NaN for one "
        "replicate); batch_se: within-run batch means (5 batches)")
    for q, fields in steady.items():
        g = st.create_group(q)
        g.attrs["units"] = units(q)
        for f, v in fields.items():
            d = g.create_dataset(f, data=np.asarray(v))
            d.attrs["units"] = "s" if f == "start" else "1" if f in ("n", "stationary") else units(q)


def has_checkpoint(path) -> bool:
    """Whether ``path`` is a readable jaxdamp file with a ``/checkpoint`` to continue from
    (run and sweep files)."""
    import h5py

    try:
        with h5py.File(path, "r") as h5:
            return "checkpoint" in h5
    except OSError:
        return False


class DiskFull(OSError):
    """The disk holding an output file has no room for the next chunk."""

    def __str__(self) -> str:
        return self.strerror or super().__str__()


#: Room kept free beyond a chunk's estimated size (HDF5 metadata, the checkpoint rewritten
#: beside the old one before the old one is dropped).
SPACE_MARGIN = 1 << 18


def ensure_space(path, nbytes: int) -> None:
    """Raise :class:`DiskFull` unless the disk holding ``path`` has room for ``nbytes`` of
    new data (counted twice: HDF5 does not reuse a dropped checkpoint's space at once) plus
    :data:`SPACE_MARGIN`. Checked before each chunk is written, so that a full disk stops a
    run between chunks, never in the middle of an HDF5 write (where it leaves the file with
    holes that read back as zeros)."""
    import errno
    import shutil

    from jaxdamp.engine.budget import size

    folder = os.path.dirname(os.path.abspath(os.fspath(path)))
    free = shutil.disk_usage(folder).free
    need = 2 * int(nbytes) + SPACE_MARGIN
    if free < need:
        raise DiskFull(errno.ENOSPC,
                       f"the disk holding {path} is full: {size(free)} free, the next chunk "
                       f"needs about {size(need)}; the file keeps every chunk finished before "
                       "it — free some space, then continue it (--resume, or for `efficiency` "
                       "the same command)")


def write_checkpoint(h5, arrays: dict, attrs: dict) -> None:
    """Replace ``/checkpoint`` with ``arrays`` (exact copies) and ``attrs``, never leaving the
    file without a whole one: the samples written before it are flushed first, the new
    checkpoint is written and flushed beside the old (``/checkpoint.new``), and only then
    renamed over it."""
    h5.flush()
    if "checkpoint.new" in h5:
        del h5["checkpoint.new"]
    g = h5.create_group("checkpoint.new")
    for k, v in arrays.items():
        g.create_dataset(k, data=np.asarray(v))
    for k, v in attrs.items():
        g.attrs[k] = v
    h5.flush()
    if "checkpoint" in h5:
        del h5["checkpoint"]
    h5.move("checkpoint.new", "checkpoint")
    h5.flush()


def damaged_series(t, n: int) -> str | None:
    """Why the first ``n`` sampled times ``t`` (a run's or a point's) cannot be the samples
    of a run — missing, not finite, or not increasing (a disk that filled or bytes overwritten
    leave holes that read back as zeros or garbage) — or ``None`` when they can."""
    t = np.asarray(t)
    if t.shape[-1] < n:
        return f"its checkpoint counts {n} samples but the file holds {t.shape[-1]}"
    t = t[..., :n]
    if not np.isfinite(t).all():
        return "its sampled times are not all finite"
    if n > 1 and not (np.diff(t, axis=-1) > 0).all():
        k = int(np.argmax(~(np.diff(t, axis=-1) > 0).reshape(-1, n - 1).all(axis=0))) + 1
        return f"its sampled times stop increasing at sample {k}"
    return None


#: The checkpoint fields that must be finite in any state a run can continue from.
KINEMATICS = ("state/r", "state/v", "state/w", "state/q", "state/z", "state/zd")


def damaged_checkpoint(arrays: dict) -> str | None:
    """Why checkpoint ``arrays`` cannot be a state to continue from (a kinematic field
    missing or not finite), or ``None``."""
    for k in KINEMATICS:
        if k not in arrays:
            return f"its checkpoint lacks {k}"
        if not np.isfinite(np.asarray(arrays[k], dtype=float)).all():
            return f"its checkpoint's {k} is not finite"
    return None


def outdated_checkpoint(arrays: dict, path, series=()) -> str | None:
    """The one-line refusal to continue a file whose checkpoint an older jaxdamp wrote (a
    state field it did not have yet, or fewer work channels), or whose time series (the
    names in ``series``, once samples were written) lack a record this version writes; or
    ``None``. Such a file cannot go on bit-identically: what it lacks has no history."""
    import dataclasses

    from jaxdamp.physics.energy import RECORD_UNITS  # the physics: on use
    from jaxdamp.physics.model import N_CHANNELS, State

    optional = {"y", "yd", "ydd"}  # before multi-DOF structures: one DOF, nothing to restore
    missing = [f.name for f in dataclasses.fields(State)
               if f.name not in optional and f"state/{f.name}" not in arrays]
    work = arrays.get("state/work")
    channels = np.shape(work)[-1] if work is not None else N_CHANNELS
    series = set(series)
    unrecorded = [k for k in RECORD_UNITS if series and k not in series]
    if not missing and channels == N_CHANNELS and not unrecorded:
        return None
    what = (f"its state lacks {', '.join(missing)}" if missing else
            f"it has {channels} work channels, this version {N_CHANNELS}"
            if channels != N_CHANNELS else f"its series lack {', '.join(unrecorded)}")
    return (f"--resume: {path} was written by an older jaxdamp ({what}); it cannot be "
            "continued — start it again with --overwrite")


def damaged_message(path, why: str) -> str:
    """The one-line refusal to continue a damaged file."""
    return (f"--resume: {path} is damaged ({why}); it cannot be continued — start it again "
            "with --overwrite (a disk that filled while it was written, or bytes overwritten, "
            "leave such holes)")


def stop_file(f, message: str) -> None:
    """Mark an open run or sweep file (``set_status``, ``close``) as stopped with
    ``message`` after an error of its disk, as far as the disk still allows; the claim on it
    is released whatever happens. Its last whole checkpoint is what a resume continues."""
    try:
        f.set_status("stopped", message)
    except Exception:  # noqa: BLE001 - the disk that failed may refuse this too
        pass
    try:
        f.close()
    except Exception:  # noqa: BLE001
        from jaxdamp.io import claims

        claims.release(f.path)
