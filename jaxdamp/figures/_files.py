"""Helpers shared by the ``*_from_file`` figures: open a file or a path, a run's title, a
time window of its series. (Reading and checking output files is :mod:`jaxdamp.io.export`'s.)"""

from __future__ import annotations

import os

import numpy as np

from jaxdamp.io.export import OutputFileError, open_output


def open_file(h5_or_path):
    """``(h5, close)``: an open output file and whether we opened it (and must close it)."""
    if isinstance(h5_or_path, (str, os.PathLike)):
        return open_output(h5_or_path), True
    return h5_or_path, False


def run_title(h5, cfg) -> str:
    """``"<name>: <file>, N = <n> grains"`` of a run file with configuration dict ``cfg``."""
    n = cfg.get("cells", 1) * sum(s["count"] for s in cfg["grains"])  # every cell's
    return f"{cfg.get('name', '')}: {os.path.basename(h5.filename)}, N = {n} grains"


def time_window(t, t0, t1, frequency=None, periods=None, what="figure", path=""):
    """Boolean mask of samples in ``[t0, t1]``; defaults: the whole run, or with ``periods``
    the last ``periods`` drive periods of ``frequency`` [Hz]."""
    t = np.asarray(t)
    lo, hi = float(t[0]), float(t[-1])
    if t1 is None:
        t1 = hi
    if t0 is None:
        t0 = max(lo, t1 - periods / frequency) if periods and frequency else lo
    if not t0 < t1:
        raise OutputFileError(f"{path}: {what}: empty time window t0 = {t0:g} s ≥ t1 = {t1:g} s")
    mask = (t >= t0) & (t <= t1)
    if mask.sum() < 2:
        raise OutputFileError(f"{path}: {what}: fewer than 2 samples in t = {t0:g} … {t1:g} s; "
                              f"the run's samples span {lo:.6g} … {hi:.6g} s")
    return mask
