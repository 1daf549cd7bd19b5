"""Experiments run in their --quick mode and reproduce what their summaries claim."""

import importlib.util
import pathlib

import numpy as np

EXPERIMENTS = pathlib.Path(__file__).parent.parent / "experiments"


def _load(name):
    spec = importlib.util.spec_from_file_location(name, EXPERIMENTS / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_restitution_curve_quick(tmp_path):
    cases = _load("restitution_curve").main(["--quick", "--out", str(tmp_path)])
    for name, c in cases.items():
        # DEM restitution equals the integrated force law within 0.2 % at every speed (dt = t_c/50)
        assert np.all(np.abs(c["eps"] - c["eps_ref"]) / c["eps_ref"] < 2e-3), name
        # contact time within 2 steps of 50
        assert np.all(np.abs(c["contact"] - c["duration_ref"]) / c["duration_ref"] < 0.04), name
        assert np.all(np.diff(c["eps"]) < 0), name  # restitution falls with speed
    a, b = cases["thesis_pair_E2.03e11"]["eps"], cases["thesis_pair_E2.03e9"]["eps"]
    assert np.max(np.abs(a - b)) < 1e-6  # the reduced-modulus similarity rule holds in the DEM
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    assert (tmp_path / "data.h5").exists() and (tmp_path / "summary.md").exists()
