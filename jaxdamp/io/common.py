"""What every jaxdamp file shares: attributes with provenance, datasets with units, appendable
datasets, and the steady-state estimates group. (The checkpoint form of a state is the
driver's: :func:`jaxdamp.engine.driver.checkpoint`.)"""

from __future__ import annotations

import json
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
