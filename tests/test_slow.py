"""Long tests (``pytest -m slow``): the experiments in their full mode, with the checks of what
their summaries claim. Deselected by default (``addopts = -m 'not slow'`` in pyproject.toml).

Each test runs one experiment's ``main`` into a temporary directory (fresh raw sweeps; the
committed results in ``experiments/*/`` are not touched). Wall times on 2 free cores, from the
experiments' own summaries: restitution curve ~10 s (plus compilation), stiffness ~5 min,
universal response ~5 min, bed dynamics ~11 min, gap scan ~40 min.
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
    """The optimal damper near resonance (5 frequencies, 2.5 s each) at E = 2.03e11, 2.03e9 and
    2.03e8 Pa: dt follows t_c ∝ λ^-2/5 exactly; every run closes its energy balance; the grains
    damp at every modulus (resonant Z/U below 10, against 28–31 for the rigid masses M and
    M + m_p); the thesis modulus and the preset's reduced one agree on the resonant amplitude
    and on the granular loss per cycle at 15 Hz within 10 % (summary: +2.7 %, +4 %), and the
    1000× softer grains within 20 % (summary: +9.9 %)."""
    from jaxdamp.analysis.response import frf_amplitude

    rows = _load("stiffness").main(["--out", str(tmp_path), "--no-progress"])
    assert set(rows) == {1.0, 0.01, 0.001}
    hard, ref, soft = rows[1.0], rows[0.01], rows[0.001]
    for lam, r in rows.items():
        assert r["dt"] / hard["dt"] == pytest.approx(lam ** -0.4, rel=1e-9), lam
        assert np.all(r["balance"] < 1e-3), lam
        U = r["config"].primary.U
        assert r["Z_max"] / U < 10.0, lam
    p = ref["config"].primary
    rigid = frf_amplitude(np.array([14.5, 15.16]), p.M, p.K, p.C, p.U).max() / p.U
    assert rigid > 25.0  # the comparison above is meaningful
    assert hard["Z_max"] == pytest.approx(ref["Z_max"], rel=0.10)
    assert soft["Z_max"] == pytest.approx(ref["Z_max"], rel=0.20)
    freqs = (14.0, 14.5, 15.0, 15.5, 16.0)
    k15 = freqs.index(15.0)
    assert len(ref["loss"]) == len(freqs)
    assert hard["loss"][k15] == pytest.approx(ref["loss"][k15], rel=0.10)
    assert np.all(np.asarray(ref["loss"]) > 0)
    assert (tmp_path / "figure.png").stat().st_size > 10_000


def test_universal_response_full(tmp_path):
    """Thesis fig. 5.2 (12 frequencies, 2.5 s each, 4 damping cases; S3 10 s): the FRF at the
    optimal box is nearly unchanged with γ_n or γ_s switched off (within 25 %; summary: 6.7 %,
    17.2 %) but not with both (then the bed is a rigid-ish added mass, resonant Z/U > 15); with
    γ_n = 0 the loss is all frictional, with γ_s = 0 all collisional; S3 with e = 0 matches the
    reference DEM's resonance (peak within 10 %, frequency within 0.5 Hz) and the smooth S3
    model matches the exact event-driven one within 5 % from 14.5 to 16 Hz."""
    mod = _load("universal_response")
    out = mod.main(["--out", str(tmp_path), "--no-progress"])
    dem, s3 = out["dem"], out["s3"]
    ref, no_gn, no_gs, none = (dem[k] for k in ((3660.0, 10980.0), (0.0, 10980.0),
                                                 (3660.0, 0.0), (0.0, 0.0)))
    U = ref["cfg"].primary.U
    for key, d in dem.items():
        assert np.all(d["balance"] < 2e-3), key
        assert len(d["Z"]) == 12, key
    assert no_gn["dev"] < 0.25 and no_gs["dev"] < 0.25
    assert none["dev"] > 1.0 and none["Z_peak"] / U > 15.0
    assert ref["Z_peak"] / U < 10.0
    assert np.all(no_gn["coll"] < 1e-3 * no_gn["total"])
    assert np.all(no_gs["fric"] < 1e-3 * no_gs["total"])
    assert np.all((ref["coll"] > 0) & (ref["fric"] > 0))
    ev, sm = s3["event"], s3["smooth"]
    assert ev["Z_peak"] == pytest.approx(ref["Z_peak"], rel=0.10)
    assert abs(ev["f_peak"] - ref["f_peak"]) < 0.5
    f = np.asarray(mod.F_FULL)
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
    """Thesis figs. 3.6–3.8 (10 heights × 12 frequencies × 2.5 s, C = 7.6 and 26.3 N s/m): the
    energy balance closes at every point; for C = 7.6 the largest C_ef/C and the smallest
    resonant amplitude fall at the thesis' optimum Lz = 0.1225 m (± one scan step), where M_ef is
    within 5 % of M and C_ef/C exceeds 3; no height loses damping (C_ef > 0.9 C); at the smallest box M_ef exceeds
    M + m_p (overshoot) and at the tallest it is below M_ef of the smallest."""
    from jaxdamp.physics.model import grain_mass

    mod = _load("gap_scan")
    res = mod.main(["--out", str(tmp_path), "--no-progress"])
    assert set(res) == {7.6, 26.3}
    for C, r in res.items():
        assert np.all(r["res"].summary["balance_error"] < 1e-3), C
        assert np.all(np.isfinite(r["fits"]["C_ef"])), C
        assert np.all(r["fits"]["C_ef"] > 0.9 * C), C  # summary: C_ef/C ≥ 1.02
    r = res[7.6]
    lz = list(mod.LZ_FULL)
    C_ef = np.asarray(r["fits"]["C_ef"])
    assert C_ef[lz.index(0.1225)] > 3.0 * 7.6  # summary: 3.97
    assert r["optimum"]["max_C_ef"] in (0.1095, 0.1225, 0.147)
    assert r["optimum"]["min_peak"] in (0.1095, 0.1225, 0.147)
    M, m_p = r["cfg"].primary.M, grain_mass(r["cfg"])
    M_ef = np.asarray(r["fits"]["M_ef"])
    assert len(M_ef) == len(lz)
    assert M_ef[lz.index(0.1225)] == pytest.approx(M, rel=0.05)
    assert M_ef[0] > M + m_p
    assert M_ef[-1] < M_ef[0]
    for name in ("fig3_6.png", "fig3_7_3_8.png"):
        assert (tmp_path / name).stat().st_size > 10_000
