"""Long tests (``pytest -m slow``): the experiments in their full mode, with the checks of what
their summaries claim. Deselected by default (``addopts = -m 'not slow'`` in pyproject.toml).

Each test runs one experiment's ``main`` into a temporary directory (fresh raw sweeps; the
committed results in ``experiments/*/`` are not touched). Wall times on 2 free cores, from the
experiments' own summaries: restitution curve ~10 s (plus compilation), stiffness ~5 min,
universal response ~25 min, bed dynamics ~11 min, gap scan ~1.5 h (2 shared cores).
"""


import numpy as np
import pytest
from helpers import load_experiment

pytestmark = pytest.mark.slow



_load = load_experiment


def test_restitution_curve_full(tmp_path):
    """12 impact speeds from 0.1 to 5 m/s for the paper's and the thesis' grains (grain–grain and
    grain–wall): the DEM step reproduces the integrated force law's restitution within 0.2 % and
    its contact time within 4 % at every speed, the restitution falls with speed, and the
    reduced-modulus similarity rule holds in the DEM (thesis modulus vs λ = 0.01)."""
    cases = _load("restitution_curve").main(["--out", str(tmp_path)])
    assert len(cases) >= 3
    for name, c in cases.items():
        assert len(c["eps"]) == 12, name
        assert np.all(np.abs(c["eps"] - c["eps_ref"]) / c["eps_ref"] < 2e-3), name
        assert np.all(np.abs(c["contact"] - c["duration_ref"]) / c["duration_ref"] < 0.04), name
        assert np.all(np.diff(c["eps"]) < 0), name
        assert np.all((c["eps"] > 0) & (c["eps"] < 1)), name
    a, b = cases["thesis_pair_E2.03e11"]["eps"], cases["thesis_pair_E2.03e9"]["eps"]
    assert np.max(np.abs(a - b)) < 1e-6
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    assert "Command" in (tmp_path / "summary.md").read_text()


def test_stiffness_full(tmp_path):
    """The optimal damper near resonance (3 frequencies x 3 beds, 1.8 s each) at E = 2.03e11,
    2.03e9 and 2.03e8 Pa: dt follows t_c ∝ λ^-2/5 exactly; every run closes its energy
    balance; the grains damp at every modulus (resonant Z/U below 10, against 28–31 for the
    rigid masses M and M + m_p); the thesis modulus and the preset's reduced one agree on the
    resonant amplitude and on the granular loss per cycle at 15 Hz within 10 %, the 1000×
    softer grains within 20 %; every change is reported with a finite Welch interval."""
    from jaxdamp.analysis.response import frf_amplitude

    rows = _load("stiffness").main(["--out", str(tmp_path), "--no-progress"])
    assert set(rows) == {1.0, 0.01, 0.001}
    hard, ref, soft = rows[1.0], rows[0.01], rows[0.001]
    for lam, r in rows.items():
        assert r["dt"] / hard["dt"] == pytest.approx(lam ** -0.4, rel=1e-9), lam
        assert np.all(r["balance"] < 1e-3), lam
        U = r["config"].primary.U
        assert r["Z_max"] / U < 10.0, lam
        assert r["Z"].shape == (3, 3) and np.isfinite(r["d_peak_ci"]), lam
    p = ref["config"].primary
    rigid = frf_amplitude(np.array([14.5, 15.16]), p.M, p.K, p.C, p.U).max() / p.U
    assert rigid > 25.0  # the comparison above is meaningful
    assert abs(hard["d_peak"]) < 0.10 and abs(soft["d_peak"]) < 0.20
    assert abs(hard["d_loss"]) < 0.10
    assert np.all(ref["loss"] > 0)
    assert (tmp_path / "figure.png").stat().st_size > 10_000


def test_universal_response_full(tmp_path):
    """Thesis fig. 5.2 (4 damping cases x 8 frequencies x 3 beds in one batch; S3 10 s): the
    resonant amplitude changes by less than 25 % with γ_n or γ_s switched off but not with both
    (then the bed is a rigid-ish added mass, resonant Z/U > 15); with γ_n = 0 the loss is all
    frictional, with γ_s = 0 all collisional; S3 with e = 0 lies within 15 % of the reference
    DEM's resonant amplitude and the smooth S3 model matches the exact event-driven one within
    5 % from 14.5 to 16 Hz."""
    from jaxdamp.analysis.response import resonance

    mod = _load("universal_response")
    out = mod.main(["--out", str(tmp_path), "--no-progress"])
    a, v, s3 = out["dem"], out["verdicts"], out["s3"]
    U = out["cfg"].primary.U
    assert a["Z"].shape == (4, len(mod.F_FULL), 3)
    assert np.all(a["balance"] < 2e-3)
    ref, no_gn, no_gs, none = v["cases"]
    assert abs(no_gn["d_peak_rel"]) < 0.25 and abs(no_gs["d_peak_rel"]) < 0.25
    assert none["peak"] > 15.0 and none["peak_changed"]
    assert ref["peak"] < 10.0
    sp = a["split"]
    assert np.all(sp["pp_normal"][1] + sp["pw_normal"][1] < 1e-3 * a["E"][1])
    assert np.all(sp["pp_friction"][2] + sp["pw_friction"][2] < 1e-3 * a["E"][2])
    f = np.asarray(mod.F_FULL)
    ev, sm = s3["event"], s3["smooth"]
    assert resonance(f, ev["Z"])[1] / U == pytest.approx(ref["peak"], rel=0.15)
    near = (f >= 14.5) & (f <= 16.0)
    np.testing.assert_allclose(sm["Z"][near], ev["Z"][near], rtol=0.05)
    assert (tmp_path / "fig5_2.png").stat().st_size > 10_000


def test_bed_dynamics_full(tmp_path):
    """Thesis ch. 4 along the FRF of the optimal damper (12 frequencies, 14 s each): the energy
    balance closes; at 5.5 and 7 Hz the bed's centre of mass is periodic-1 (as the thesis) and
    never reaches the lid; from 14 to 15.5 Hz the bed hits the lid more than once per period and
    holds the amplitude far below the rigid-mass resonance; every point gets a regime label and
    the sections have one point per period."""
    from jaxdamp.analysis.response import frf_amplitude

    out = _load("bed_dynamics").main(["--out", str(tmp_path), "--no-progress"])
    res, rows, cfg = out["result"], out["rows"], out["config"]
    freqs = [float(f) for f in res.axes["frequency"]]
    assert len(freqs) == 12 and len(rows) == 12
    assert np.all(res.summary["balance_error"] < 1e-3)
    by_f = dict(zip(freqs, rows))
    for f in (5.5, 7.0):
        c = by_f[f]["z_cm"]
        assert c["label"] == "periodic" and c["period"] == 1, f
        assert by_f[f]["lid_hits_per_period"] == 0.0, f
    for f in (14.0, 14.5, 15.5):
        assert by_f[f]["lid_hits_per_period"] > 1.0, f
    p = cfg.primary
    Z = dict(zip(freqs, res.summary["amplitude"]))
    assert Z[14.5] < 0.5 * frf_amplitude(14.5, p.M + out["grain_mass"], p.K, p.C, p.U)
    assert Z[15.5] < 0.5 * frf_amplitude(15.16, p.M, p.K, p.C, p.U)
    for r in rows:
        for sig in ("z_cm", "z_rel"):
            assert r[sig]["label"] in ("periodic", "quasi-periodic", "chaotic", "undetermined")
    for f, d in out["details"].items():
        n_periods = (d["t"][-1] - d["t"][0]) * f
        assert abs(len(d["sec_t"]) - n_periods) <= 1.01
    assert (tmp_path / "fig4_1.png").stat().st_size > 10_000


def test_gap_scan_full(tmp_path):
    """Thesis figs. 3.6–3.8 (10 heights × 9 frequencies × 3 beds × 1.5 s, C = 7.6 N s/m): the
    energy balance closes at every point; with both residual weightings every height adds
    damping (C_ef > 0.9 C) and C_ef/C exceeds 3 at the thesis' optimum 0.1225 m; the smallest
    box adds more than the grains' mass (M_ef > M + m_p); the optimum located from the beds'
    vertices lies between 0.1095 and 0.147 m with a finite interval."""
    from jaxdamp.physics.model import grain_mass

    mod = _load("gap_scan")
    res = mod.main(["--out", str(tmp_path), "--no-progress"])
    r = res[7.6]
    assert np.all(r["res"].summary["balance_error"] < 1e-3)
    lz = list(mod.LZ_FULL)
    M, m_p = r["cfg"].primary.M, grain_mass(r["cfg"])
    for w in ("absolute", "relative"):
        C_ef = np.array([x["C_ef"] for x in r["fits"][w]])
        M_ef = np.array([x["M_ef"] for x in r["fits"][w]])
        assert np.all(C_ef > 0.9 * 7.6), w
        assert C_ef[lz.index(0.1225)] > 3.0 * 7.6, w
        assert M_ef[0] > M + m_p, w
        o = r["optimum"][f"max_C_ef_{w}"]
        assert 0.1095 <= o["mean"] <= 0.147 and np.isfinite(o["ci95"]), w
    for name in ("fig3_6.png", "fig3_7_3_8.png"):
        assert (tmp_path / name).stat().st_size > 10_000


def test_tangential_law_quick(tmp_path):
    """The thesis optimum under both tangential laws at test size (2 frequencies × 2 beds ×
    0.7 s per law, ~3 min; slow rather than an example: its first spring run compiles the
    native kernel's spring form for the coupled structure, minutes on a cold cache): the
    budget's reader gives both laws' per-bed values, every shift is finite, and the summary is
    rewritten byte for byte from data.h5."""
    study = _load("tangential_law")
    systematics = _load("systematics")
    out = study.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    assert set(out) == {"viscous", "mindlin"}
    stored = systematics._stored_tangential(str(tmp_path / "data.h5"))
    for law in ("viscous", "mindlin"):
        np.testing.assert_array_equal(stored[law]["Z_res"], out[law]["Z_res"])
        assert stored[law]["Z"].shape == (2,)
    values, shifts = study.shifts(str(tmp_path))
    assert all(np.isfinite([s["delta"], s["ci95"], s["u"]]).all() for s in shifts.values())
    first = (tmp_path / "summary.md").read_text()
    assert "resonant amplitude Z_res" in first and "Quick mode" in first
    study.main(["--from-data", "--out", str(tmp_path)])
    assert (tmp_path / "summary.md").read_text() == first
