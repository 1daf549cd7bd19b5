"""The ``/decay`` group of a free-decay sweep file (``jaxdamp decay``; ``docs/output.md``)."""

from __future__ import annotations

import h5py
import numpy as np

from jaxdamp.analysis.decay import UNITS

CURVE_UNITS = {"Z": "m", "zeta": "1", "zeta_se": "1", "f": "Hz", "f_se": "Hz", "zeta_g": "1",
               "zeta_g_se": "1", "n": "1"}


def write(path: str, result) -> None:
    """Store ``result`` (:class:`jaxdamp.studies.decay.DecayResult`) in ``/decay`` of the sweep
    file ``path``: ``z0`` (P,) [m]; ``cycles/<name>`` (P, R, K) per bed and cycle, NaN-padded
    (``t`` cycle start [s], ``Z`` [m], ``zeta``, ``f`` [Hz], ``zeta_g`` the granular ratio ΔW/(2πKZ²)); ``curve/<name>`` (P, G) the mean
    over beds on a common amplitude grid with its SE and the number of beds ``n``; attrs
    ``zeta_struct``, ``f_n``, ``replicates``, ``method``."""
    P, R = len(result.z0), result.replicates
    K = max([len(c["Z"]) for per in result.cycles for c in per] + [0])
    G = max([len(c["Z"]) for c in result.curves] + [0])
    with h5py.File(path, "a") as h5:
        if "decay" in h5:
            del h5["decay"]
        g = h5.create_group("decay")
        g.attrs["method"] = ("logarithmic decrement of successive positive peaks (parabola-"
                             "refined): zeta = d / sqrt(4 pi^2 + d^2), d = ln(X_k / X_k+1); "
                             "Z = sqrt(X_k X_k+1); f = 1 / (t_k+1 - t_k)")
        g.attrs["zeta_struct"] = result.zeta_struct
        g.attrs["f_n"] = result.f_n
        g.attrs["replicates"] = R
        g.create_dataset("z0", data=result.z0).attrs["units"] = "m"
        cyc = g.create_group("cycles")
        for name, unit in UNITS.items():
            a = np.full((P, R, K), np.nan)
            for i, per in enumerate(result.cycles):
                for r, c in enumerate(per):
                    a[i, r, :len(c[name])] = c.get(name, np.nan)
            cyc.create_dataset(name, data=a).attrs["units"] = unit
        cur = g.create_group("curve")
        for name, unit in CURVE_UNITS.items():
            a = np.full((P, G), np.nan)
            for i, c in enumerate(result.curves):
                a[i, :len(c["Z"])] = c.get(name, np.nan)
            cur.create_dataset(name, data=a).attrs["units"] = unit


def read(path: str) -> dict:
    """``{"z0", "cycles": {name: (P, R, K)}, "curve": {name: (P, G)}, attrs...}`` of
    :func:`write`."""
    with h5py.File(path, "r") as h5:
        g = h5["decay"]
        return dict(z0=g["z0"][()], cycles={k: g["cycles"][k][()] for k in g["cycles"]},
                    curve={k: g["curve"][k][()] for k in g["curve"]}, **dict(g.attrs))
