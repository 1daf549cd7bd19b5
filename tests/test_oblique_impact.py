"""``experiments/oblique_impact.py`` in its quick mode: the Hertz–Mindlin spring's rebound meets
the rigid-body sliding line where the contact slides throughout and the ODE solution of the
no-slip equations at small angles; the tangential force's books close."""

import numpy as np
from helpers import load_experiment


def test_oblique_impact_quick(tmp_path):
    load_experiment("oblique_impact").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    import h5py

    with h5py.File(tmp_path / "data.h5") as h:
        a = dict(h.attrs)
        psi1 = h["psi1"][()]
        imp = {k: h["impact"][k][()] for k in h["impact"]}
    kappa, mu = a["kappa"], a["mu"]
    psi2 = kappa * imp["u"] / (mu * imp["vn"])
    slide = psi1 >= 1.2 * 7 * kappa
    assert slide.sum() >= 2
    np.testing.assert_allclose(psi2[slide], psi1[slide] - 7 * kappa, atol=1e-6)
    np.testing.assert_allclose(imp["spin"][slide] / mu, 5.0, rtol=1e-6)
    small = psi1 <= 0.1
    assert small.sum() >= 1
    np.testing.assert_allclose(psi2[small] / psi1[small], a["stick_limit"], atol=2e-3)
    np.testing.assert_allclose(imp["vn"], 1.0, rtol=2e-3)  # elastic
    books = -imp["work"] - (imp["damping"] + imp["slip"] + imp["spring"] - imp["stiffness"])
    assert np.all(np.abs(books) <= 1e-9 * imp["max_spring"])
    assert (tmp_path / "figure.png").exists() and (tmp_path / "summary.md").exists()
