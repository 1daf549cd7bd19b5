"""Experiments run in their --quick mode and reproduce what their summaries claim."""


import numpy as np
import pytest
from helpers import load_experiment

_load = load_experiment

#: Minutes in total: run by ``pytest -m examples`` (CI's second step), not the default suite.
pytestmark = pytest.mark.examples


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


def test_gap_scan_quick(tmp_path):
    """3 heights x 4 frequencies x 2 beds x 0.4 s of the thesis damper: data, both figures,
    summary; energy balance closes at every point; both residual weightings fitted per bed;
    the grains add damping at every height and, in the smallest box (Lz = 0.057 m, grains nearly
    locked), add mass: M_ef above M; the optimum has a finite interval from the two beds."""
    import h5py

    res = _load("gap_scan").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    r = res[7.6]
    assert np.all(r["res"].summary["balance_error"] < 1e-3)
    assert r["Zr"].shape == (4, 3, 2)
    for w in ("absolute", "relative"):
        M = np.array([x["M_ef"] for x in r["fits"][w]])
        C = np.array([x["C_ef"] for x in r["fits"][w]])
        assert np.all(np.isfinite(M)) and np.all(C > 1.5 * 7.6), w
        assert M[0] > 2.37 + 0.1, w
        assert all(len(x["M_reps"]) == 2 for x in r["fits"][w])
        o = r["optimum"][f"max_C_ef_{w}"]
        assert 0.057 <= o["mean"] <= 0.372 and np.isfinite(o["ci95"]), w
    # the force-phase mechanism (fig. 3.9): finite per run; at the optimum the grains act
    # mostly as a damper (phase within 45° of −90°) and add damping
    fo = r["force"]
    assert all(np.all(np.isfinite(v)) and v.shape == (4, 3, 2) for v in fo.values())
    i = 2  # 15.25 Hz, the sample nearest the resonance at 0.1225 m
    assert np.all(np.abs(np.degrees(fo["phase"][i, 1]) + 90) < 45)
    assert np.all(fo["c_add"][i, 1] > 7.6)
    for name in ("fig3_6.png", "fig3_7_3_8.png", "fig3_9.png"):
        assert (tmp_path / name).stat().st_size > 10_000
    text = (tmp_path / "summary.md").read_text()
    assert "the fit the thesis describes" in text and "R = 2 independently poured beds" in text
    with h5py.File(tmp_path / "data.h5") as h:
        assert h["C_7.6/amplitude"].shape == (4, 3, 2)
        assert h["C_7.6/fit_absolute/M_reps"].attrs["units"] == "kg"


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_stiffness_quick(tmp_path):
    """Thesis modulus and the preset's reduced one: dt follows t_c ∝ E^-2/5 exactly, both
    runs close their energy balance, and the short-run amplitudes agree within 25 %."""
    rows = _load("stiffness").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    hard, soft = rows[1.0], rows[0.01]
    assert soft["dt"] / hard["dt"] == pytest.approx(0.01 ** -0.4, rel=1e-9)
    assert np.all(hard["balance"] < 1e-3) and np.all(soft["balance"] < 1e-3)
    np.testing.assert_allclose(hard["Z"], soft["Z"], rtol=0.25)
    assert (tmp_path / "figure.png").stat().st_size > 10_000


def test_universal_response_quick(tmp_path):
    """Two contact-damping cases x 2 beds in one batch, and S3 (e = 0): the exact event-driven
    and the smooth S3 agree within 5 %; switching off γ_n removes the collisional loss of the
    DEM bed; every case gets a verdict from a Welch interval."""
    out = _load("universal_response").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    ev, sm = out["s3"]["event"], out["s3"]["smooth"]
    np.testing.assert_allclose(sm["Z"], ev["Z"], rtol=0.05)
    a = out["dem"]
    assert a["Z"].shape == (2, 2, 2)
    coll = a["split"]["pp_normal"] + a["split"]["pw_normal"]
    assert np.all(coll[0] > 0) and np.all(coll[1] < 1e-3 * a["E"][1])
    assert np.all(a["balance"] < 1e-3)
    row = out["verdicts"]["cases"][1]
    assert np.isfinite(row["d_peak_ci_rel"]) and row["peak_changed"] in (True, False)
    assert (tmp_path / "fig5_2.png").stat().st_size > 10_000


def test_bed_dynamics_quick(tmp_path):
    """5.5, 14.5, 21 Hz x 1.5 s x 2 beds of the optimal damper: energy balance closes; every
    frequency, bed and observable gets a regime label (with a finite exponent when not periodic); the bed
    never reaches the lid at 5.5 Hz and hits it about once per period at 14.5 Hz, where the
    grains hold the amplitude far below the rigid-mass resonance; one section point per period."""
    import json

    import h5py

    from jaxdamp.analysis.response import frf_amplitude

    out = _load("bed_dynamics").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    res, rows, cfg = out["result"], out["rows"], out["config"]
    freqs = list(res.axes["frequency"])
    assert np.all(res.summary["balance_error"] < 1e-3)
    assert len(rows) == len(freqs)
    for r in rows:
        for sig in ("z_cm", "z_rel"):
            c = r[sig]
            assert c["label"] in ("periodic", "quasi-periodic", "chaotic", "undetermined")
            assert (c["period"] >= 1) if c["label"] == "periodic" else np.isfinite(c["exponent"])
    by_f = dict(zip(freqs, rows))
    assert by_f[5.5]["lid_hits_per_period"] == 0.0
    assert by_f[14.5]["lid_hits_per_period"] > 0.8
    p = cfg.primary
    Z = dict(zip(freqs, res.summary["amplitude"]))
    assert Z[14.5] < 0.5 * frf_amplitude(14.5, p.M + out["grain_mass"], p.K, p.C, p.U)
    for f, d in out["details"].items():
        n_periods = (d["t"][-1] - d["t"][0]) * f
        assert abs(len(d["sec_t"]) - n_periods) <= 1.01
    with h5py.File(tmp_path / "data.h5") as h:
        assert len(json.loads(h.attrs["configs"])) == len(freqs)
        assert h["classification/z_cm/label"].shape == (len(freqs), 2)  # two beds each
    assert len(out["replicates"]) == len(freqs) and all(len(r) == 2 for r in out["replicates"])
    for name in ("fig4_1.png", "fig_details.png"):
        assert (tmp_path / name).stat().st_size > 10_000
    assert "regime z_cm" in (tmp_path / "summary.md").read_text()


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_gap_optimisation_quick(tmp_path):
    """Every part of the gap-optimisation study on tiny settings: S3 exact gradients equal
    central differences (1 %), the DEM window derivative equals central differences of the same
    averaged window objective for a 0.5 ms window (h = 1e-8 m, 2 %), forward mode needs less
    compiled memory than reverse mode, the scan and both optimiser runs are logged. The scan
    runs 2 independently poured beds per height (``sweep(..., replicates=2)``): per-bed values
    (Lz, bed), their means, and the optimum per bed with its mean over beds."""
    import h5py

    out = _load("gap_optimisation").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    r = out["s3"]["dissipation"]
    for row in r["fd"][:2]:  # in the periodic regime
        assert row["ad"] == pytest.approx(row[1e-5], rel=0.01)
    dem = out["dem"]
    for row in dem["fd"]:
        ad, fd = row["ad"].mean(), row["fd"][1e-8].mean()
        assert np.isfinite(ad) and abs(ad - fd) <= 0.02 * abs(fd) + 1e-6
    m = dem["modes"]
    assert m["forward"]["temp_bytes"] < m["reverse"]["temp_bytes"]
    sc = dem["scan"]
    assert sc["beds"] == 2 and sc["balance"].shape == (3, 2)
    assert np.all(sc["balance"] < 1e-3)
    for k in ("amplitude", "dissipation"):
        b = sc[f"{k}_beds"]
        assert b.shape == (3, 2) and np.all(np.isfinite(b))
        assert np.any(b[:, 0] != b[:, 1]), k  # independent beds, not copies
        assert np.allclose(sc[k], b.mean(axis=1)) and np.all(sc[f"{k}_se"] >= 0)
    for k in ("opt_amplitude", "opt_dissipation"):
        o = sc[k]
        assert len(o["vertices"]) == 2 and np.isclose(o["mean"], np.mean(o["vertices"]))
        assert sc["lz"].min() <= o["mean"] <= sc["lz"].max()
    assert set(dem["opt"]) == {0.07, 0.25} and set(r["opt"]) == {0.07, 0.25}
    assert set(dem["opt_amp"]) == {0.07, 0.25}
    with h5py.File(tmp_path / "data.h5") as h:
        assert "config" in h["dem"].attrs and "dem/scan/dissipation" in h
        assert h["dem/scan/amplitude_beds"].shape == (3, 2)
        assert h["dem/scan/opt_amplitude/vertices"].shape == (2,)
        assert h["dem/opt_lz0_0.07/lz"].shape[0] >= 1
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    text = (tmp_path / "summary.md").read_text()
    assert "Forward vs reverse" in text and "2 independently poured beds" in text


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_design_optimisation_quick(tmp_path):
    """Every part of the design-optimisation study on tiny settings: the reference and the
    estimator give finite derivatives with standard errors, the scan, trust region and FD
    optimiser report optima with their simulated seconds, and data, figure and summary are
    written with the command inside."""
    import h5py

    res = _load("design_optimisation").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    out, v = res["out"], res["verdicts"]
    assert all(np.isfinite(r["grad"]) and r["se"] > 0 for r in out["reference"])
    assert all(np.isfinite(e["grad"]) for e in out["estimator"])
    assert out["scan"].sim_seconds > 0 and len(out["trust"]) == 1 and len(out["fd"]) == 1
    assert len(v["estimator_agrees"]) == 2
    with h5py.File(tmp_path / "data.h5") as h:
        assert "design_optimisation.py --quick" in h.attrs["command"]
        assert h["scan/J"].shape[1] == 2
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    assert "## 3–5. Searches" in (tmp_path / "summary.md").read_text()


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_wall_damping_quick(tmp_path):
    """Both grain–wall conventions on the reference box and class a (test-sized): under
    'calibrated' every species bounces off the wall with ε = 0.75 at 1 m/s, under 'mixed' the
    2.5 mm grains with ≈ 0.78 and the 1.25 mm ones with ≈ 0.69; ⟨E_d⟩ is finite for every
    stationary bed; data, figure and summary are written."""
    res = _load("wall_damping").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    for r in res["rows"]:
        if r["convention"] == "calibrated":
            assert np.allclose(r["eps_wall"], 0.75, atol=1e-6), r["eps_wall"]
        else:
            assert r["eps_wall"][0] == pytest.approx(0.777, abs=0.005)
        ok = np.asarray(r["stationary"], bool)
        assert ok.any() and np.isfinite(r["values"][ok]).all()
    assert len(res["verdicts"]) == 2
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    assert "Relative change" in (tmp_path / "summary.md").read_text()


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_design_starts_and_variables_quick(tmp_path):
    """Both parts on tiny settings (~1 min): the multi-fidelity optimiser from both starts reports optima with intervals and
    DEM seconds; SPSA, the equal-budget random search and the confirmation give finite
    values; data, figure and summary are written with the command inside."""
    import h5py

    res = _load("design_starts_and_variables").main(["--quick", "--out", str(tmp_path),
                                                      "--no-progress"])
    a, b, v = res["a"], res["b"], res["verdicts"]
    assert len(a["runs"]) == 2 and all(r["sim"] > 0 and r["lo"] <= r["x"] <= r["hi"]
                                       for r in a["runs"])
    assert set(v["starts"]) == {"0.03", "0.12"}
    assert np.isfinite(b["confirm"]["mean"]).all() and b["random_cost"] <= b["spsa_cost"] + 1e-9
    with h5py.File(tmp_path / "data.h5") as h:
        assert "design_starts_and_variables.py --quick" in h.attrs["command"]
        assert h["three_variables/confirmation/J"].shape == (3, 2)
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    assert "## B. Three design variables" in (tmp_path / "summary.md").read_text()


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
@pytest.mark.skipif(__import__("shutil").which("lmp") is None,
                    reason="LAMMPS (`lmp`) is not on PATH; apt-get install lammps")
def test_lammps_crosscheck_quick(tmp_path):
    """The LAMMPS cross-check at test size (3 cm, 2 + 3 periods, 2 beds, ~30 s): the mapping
    checks pass, each bed (its own seed) is run by both codes from the same settled state, the
    paired difference LAMMPS − jaxdamp has a finite 95 % interval over the beds; a re-run reuses
    every bed from raw/beds; data, figure and summary carry the replicates."""
    import h5py

    lc = _load("lammps_crosscheck")
    res = lc.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    assert all(abs(r["restitution"] / r["ref_restitution"] - 1) < 1e-3
               for r in res["checks"]["pair"] + res["checks"]["wall"])
    beds = res["cases"][0.03]["beds"]
    assert [b["seed"] for b in beds] == [0, 1] and not any(b["reused"] for b in beds)
    assert not np.array_equal(beds[0]["jd"]["bed_r"], beds[1]["jd"]["bed_r"])  # two beds
    r = res["table"][0.03]
    assert r["R"] == 2 and r["n"] == 2
    assert np.isfinite(r["sed"]) and r["hw"] > r["sed"] > 0  # t_{0.975, 1} = 12.7
    assert r["d"] == pytest.approx(np.mean([x["diff"] for x in r["beds"]]))
    assert 0.7 < r["ml"] / r["e_max"] < 0.95 and 0.7 < r["mj"] / r["e_max"] < 0.95
    assert abs(r["rel"]) < 0.05  # the codes agree within 5 % even over 3 periods
    again = lc.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    assert all(b["reused"] for b in again["cases"][0.03]["beds"])
    assert again["table"][0.03]["d"] == r["d"]
    with h5py.File(tmp_path / "data.h5") as h:
        g = h["A_3cm"]
        assert list(g["seed"][()]) == [0, 1] and g["difference_per_bed"].shape == (2,)
        assert g.attrs["difference_ci95"] == pytest.approx(r["hw"])
        assert g["bed_1/lammps/dissipation_per_period"].shape == (5,)
    text = (tmp_path / "summary.md").read_text()
    assert "R = 2 independently poured beds" in text and "paired" in text
    assert (tmp_path / "figure.png").stat().st_size > 10_000


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_binary_mixtures_quick(tmp_path):
    """The 2023 paper's families at test size (σ = 0.5, 2 amplitudes, 1 + 2 periods, 2 beds):
    every family runs, the class builders' conserved quantities hold in the runs, the energy balance
    closes, and data, figures and the claims section are written."""
    runs = _load("binary_mixtures").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    names = [(r["name"], r["sigma"]) for r in runs]
    assert names == [("varela2023-reference", None)] + [(f"varela2023-{k}", 0.5) for k in "abc"]
    mass = {r["name"].split("-")[1]: r["result"].summary["mass"][0] for r in runs}
    ref = mass["reference"]
    assert mass["c"] == pytest.approx(ref, rel=1e-12)
    assert mass["a"] == pytest.approx(ref, rel=2e-3)
    assert mass["b"] == pytest.approx(ref * (1 + 0.125) / 2, rel=1e-12)
    for r in runs:
        s = r["result"].summary
        assert np.all(s["balance_error"] < 2e-3), r["name"]
        assert np.all((s["E_d_mean"] > 0) & (s["E_d_mean"] < 1.5)), r["name"]
    text = (tmp_path / "summary.md").read_text()
    assert "A_opt ≈ 2.8 cm" in text and "class c (σ = 0.5) vs the reference" in text
    assert "Size segregation at 3 cm" in text and "Per damper (J dissipated per period)" in text
    # wall force, speeds and the fig. 3 spread: from each bed, with their spread across beds
    assert "**wall force** (each bed's phase curve) peak" in text
    assert "snapshots of the last period of every bed" in text
    for r in runs:  # two beds per amplitude, each with its own per-period segregation index
        seg = r["result"].replicate_per_period["segregation"]
        assert seg.shape == (2, 2, 3)
        assert np.isfinite(seg).all() == (r["sigma"] is not None), r["name"]
    for name in ("efficiency.png", "contacts_force.png", "phase_plots.png", "snapshots.png",
                 "segregation.png"):
        assert (tmp_path / name).stat().st_size > 10_000
    import h5py

    with h5py.File(tmp_path / "data.h5") as h:
        assert h["varela2023-b/sigma_0.5/phase/vz_cm_species"].shape == (2, 100, 2)


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_bed_dynamics_long_quick(tmp_path):
    """Twin pairs at 14.5 and 21 Hz, 1.2 s, on 2 independently poured beds (the package's
    replicate seeds 0, 1): every pair is bit-identical until the perturbation, the beds differ
    (independent pours); every bed, frequency and signal gets periodicity levels in [0, 1] and
    a twin exponent; the combined values are the beds' means with a standard error, and the
    period-k verdicts are counts of beds. On every bed the twins' box motion separates by
    orders of magnitude from the 1e-9 m perturbation (the grains are chaotic in the periodic
    window too: in the full run the twins separate on every bed at both frequencies, and the
    exponents scatter between beds by more than their difference, so the quick run asserts no
    ordering between the frequencies)."""
    out = _load("bed_dynamics_long").main(["--quick", "--beds", "2", "--out", str(tmp_path),
                                           "--no-progress"])
    rows = out["rows"]
    assert set(rows) == {14.5, 21.0} and out["beds"] == 2 and out["seeds"] == [0, 1]
    for f, r in rows.items():
        assert len(r["beds"]) == 2 and r["identical_before"] == [0.0, 0.0], f
        for name in ("z_box", "z_cm"):
            for d in (b[name] for b in r["beds"]):
                assert 0 <= d["harm1"] <= 1 and d["spread1"] >= 0
                assert np.isfinite(d["div_exponent"])
            c = r["stats"][name]
            assert c["beds"] == 2
            v = c["s1"]["values"]
            assert v[0] != v[1], (f, name)  # independent beds, not copies
            assert np.isclose(c["s1"]["mean"], v.mean()) and c["s1"]["se"] > 0
            for k in (1, 2):
                assert 0 <= c[f"period{k}_0.01"] <= c[f"period{k}_0.05"] <= 2
        for b in r["beds"]:
            assert b["z_box"]["div_grew"] and b["z_box"]["div_exponent"] > 0, f
    assert np.all(out["balance"] < 1e-3)
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    text = (tmp_path / "summary.md").read_text()
    assert "2 independently poured beds" in text and "of 2 beds" in text and "twin" in text
    import h5py

    with h5py.File(tmp_path / "data.h5") as h:
        assert list(h.attrs["seeds"]) == [0, 1]
        assert h["f_14.5/over_beds/z_box/s1"].shape == (2,)
        assert "twin_distance" in h["f_21/bed_1/z_cm"]


def test_inelastic_collapse(tmp_path):
    """Thesis fig. 5.1: collapse below e_c = 3 − 2√2 (found by bisection to 1e-5), escape above;
    the thesis' t∞ formula within 2 % at e ≤ 0.1; data, figure and summary written."""
    out = _load("inelastic_collapse").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    assert out["e_c"] == pytest.approx(3 - 2 * np.sqrt(2), abs=1e-5)
    for row in out["rows"]:
        assert row["outcome"] == ("collapsed" if row["e"] < out["e_c"] else "escaped")
        if row["e"] <= 0.1:
            assert abs(row["formula_error"]) < 0.02
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    assert "3 − 2√2" in (tmp_path / "summary.md").read_text()


def test_cylinder_packing_quick(tmp_path):
    """Two beds poured into a cylinder of D/d = 5 by fill fraction, from the lattice and at
    random: every bed settles; the measured slab fraction lies between a loose and the densest
    random packing; the stated fill gives the count Dixon's φ implies; the report is written
    from the data file and rewritten byte for byte from it."""
    from jaxdamp.cases.filling import random_packing_fraction

    rows = _load("cylinder_packing").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    assert [row["pour"] for row in rows] == ["lattice", "random"]
    d, Rc = 0.006, 0.015
    expected = random_packing_fraction(0.2) * np.pi * Rc**2 * 6 * d / (np.pi / 6 * d**3)
    for row in rows:
        assert row["settled"].all() and np.all((0.5 < row["phi"]) & (row["phi"] < 0.66))
        assert abs(row["count"] - expected) <= 0.5
    first = (tmp_path / "summary.md").read_text()
    _load("cylinder_packing").main(["--from-data", "--out", str(tmp_path)])
    assert (tmp_path / "summary.md").read_text() == first and "Dixon 1988" in first


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_universality_limits_quick(tmp_path):
    """γ_n, γ_s at 0 and 1e4, steel and lead, 50 grains, 2 beds, 0.3 s: switching a damping
    constant off removes its loss channel (collisional share 0 with γ_n = 0, 1 with γ_s = 0);
    every comparison has a finite Welch interval; data, figure, summary written."""
    out = _load("universality_limits").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    g = {(x["scan"], x["gamma"]): x for x in out["gammas"]}
    assert np.all(g[("gamma_n", 0.0)]["coll_share"] < 1e-3)
    assert np.all(g[("gamma_s", 0.0)]["coll_share"] > 1 - 1e-3)
    assert all(np.all(x["E"] > 0) for x in out["gammas"])
    assert np.isfinite(out["materials"][1]["d_peak_ci"])
    assert np.isfinite(out["few"][0]["d_peak_ci"])
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    assert "fig. 5.4" in (tmp_path / "summary.md").read_text()


def test_single_grain_frf_quick(tmp_path):
    """Thesis fig. 6.1 at test size (S3 at 7 frequencies, 2 s; DEM 2 frequencies × 2 beds,
    0.2 s): the energy balance of the event-driven runs closes, e = 0 gives a single smooth
    hump (roughness 1), the bed's amplitudes are finite with a spread across beds, and data,
    figure and summary (with its verdict) are written."""
    r = _load("single_grain_frf").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    e0, e8, dem = r["s3"][0.0], r["s3"][0.8], r["dem"]
    assert e0["jag"]["secondary"] == 0 and e0["jag"]["roughness"] == pytest.approx(1.0)
    assert np.all(np.isfinite(e8["Z"])) and np.all(e8["Z"] > 0)
    assert e8["balance"] < 1e-6 and e0["balance"] < 1e-6
    assert dem["Z"].shape == (2, 2) and np.all(np.isfinite(dem["se"]))
    import h5py

    with h5py.File(tmp_path / "data.h5") as h:
        assert "single_grain_frf.py --quick" in h.attrs["command"]
        assert h["dem/Z_over_U"].shape == (2, 2) and "config" in h["s3_e0.8"].attrs
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    assert "Verdict:" in (tmp_path / "summary.md").read_text()


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_grain_number_quick(tmp_path):
    """Thesis §3.1 on small settings (N = 250, 500; 3 heights × 3 frequencies × 2 beds, 0.3 s):
    the energy balance closes; per N the middle height (0.11 m) damps the resonance more than
    the small and the tall box (an interior optimum) and friction carries most of the loss at
    resonance; contact episodes are counted with nearby contacts merged; files written."""
    mod = _load("grain_number")
    touching = np.array([0, 1, 1, 0, 1, 0, 0, 0, 0, 1, 1], bool)
    assert mod.impacts(touching, gap=2) == 2 and mod.impacts(touching, gap=5) == 1
    assert mod.impacts(np.zeros(5, bool), gap=1) == 0
    out = mod.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    for n, sc in out["scans"].items():
        assert sc["balance"] < 1e-3, n
        Z = sc["Z_res"]
        assert Z.shape == (3, 2) and np.all(np.isfinite(Z)), n
        assert Z[1].mean() < 0.9 * Z[0].mean() and Z[1].mean() < 0.9 * Z[2].mean(), n
        share = sc["fric"] / (sc["coll"] + sc["fric"])
        assert np.all(share > 0.5), n
        assert np.all(sc["bed_top"] < 0.067), n
    assert out["response"]["balance"] < 1e-3
    text = (tmp_path / "summary.md").read_text()
    assert "Settled beds (thesis table 3.2)" in text and "The optimum" in text
    for name in ("figure.png", "fig3_3_3_4.png"):
        assert (tmp_path / name).stat().st_size > 10_000


def test_contact_checks(tmp_path):
    """A sliding sphere ends rolling at 5/7 v0 without slip on both engines, having lost
    (2/7) ½ m v0² in friction; the mixtures' mixed A is the mean of the species' A."""
    out = _load("contact_checks").main(["--out", str(tmp_path), "--no-progress"])
    for r in out["runs"]:
        assert r["ratio"] == pytest.approx(5 / 7, rel=1e-3), r["engine"]
        assert abs(r["no_slip"]) < 1e-6 and r["friction_loss"] == pytest.approx(
            r["loss_expected"], rel=0.02)
    for m in out["mixed"]:
        assert abs(m["rel_diff"]) < 1e-12 and 0.6 < m["restitution_mixed"] < 0.75
    assert (tmp_path / "figure.png").stat().st_size > 10_000


def test_driven_regimes_quick(tmp_path):
    """The reference box at 1.5 and 3.5 cm, 2 beds: the bed crosses more of the gap and its
    centre of mass follows the drive more strongly above A_opt than below; files written."""
    out = _load("driven_regimes").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    m = out["m"]
    assert m["contact"].shape == (2, 2) and np.all(np.isfinite(m["excursion"]))
    assert m["excursion"][1].mean() > m["excursion"][0].mean()
    assert m["com_amp"][1].mean() > m["com_amp"][0].mean()
    assert out["balance"] < 1e-3
    assert (tmp_path / "figure.png").stat().st_size > 10_000


def test_frf_fit_quality(tmp_path):
    """From the committed gap scan: each bed's 1-DOF fit misses its FRF more at the
    intermediate heights (0.117, 0.162 m) than at the extremes, significantly across beds."""
    out = _load("frf_fit_quality").main(["--out", str(tmp_path), "--no-progress"])
    for w, comps in out["comp"].items():
        assert len(comps) == 4
        for c in comps:
            assert c["diff"] > c["ci95"] > 0, (w, c)
    assert (tmp_path / "figure.png").stat().st_size > 10_000


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_decay_vs_sine_quick(tmp_path):
    """Free decay and stepped sine on the thesis damper (2 beds each, short): both give the
    grains' damping ratio ΔW/(2πKZ²) on every bed; the sine points inside the decay's
    amplitude range get a Welch verdict; data, figure and summary are written."""
    r = _load("decay_vs_sine").main(["--quick", "--out", str(tmp_path), "--no-progress"])
    assert r["zeta_sine"].shape == (2, 2, 2) and np.all(r["zeta_sine"] > 0)
    assert np.all(np.isfinite(r["curve"]["zeta_g"]))
    for name in ("mean", "start"):  # both cycle-amplitude conventions
        cm = r["cmp"][name]
        assert cm["covered"].any() and np.isfinite(cm["half"][cm["covered"]]).all()
    text = (tmp_path / "summary.md").read_text()
    assert "Resonant points (cycle at" in text and "ζ_g = ΔW/(2πKZ²)" in text
    assert "cycle at X_k:" in text
    assert (tmp_path / "figure.png").stat().st_size > 10_000


def test_gap_minimum_quick(tmp_path):
    """F7 on a fine scan, test-sized (60 grains, 3 heights × 2 beds × 0.3 s): Z per height and
    bed, both minimum models per bed, no verdict where a bed's minimum is not bracketed;
    data, figure and summary written. The quadratic model's vertex is exact on a parabola."""
    mod = _load("gap_minimum")
    x = np.array([0.105, 0.11, 0.115, 0.12, 0.1225])
    assert mod.quadratic_vertex(x, 3.0 + (x - 0.113) ** 2) == pytest.approx(0.113, rel=1e-9)
    assert np.isnan(mod.quadratic_vertex(x, -(x - 0.113) ** 2))
    r = mod.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    assert r["Z"].shape == (3, 2) and np.all(np.isfinite(r["Z"])) and np.all(r["Z"] > 0)
    assert r["local"]["values"].shape == (2,)
    if r["local_at_edge"]:
        assert r["local"]["contains_thesis"] is None
    text = (tmp_path / "summary.md").read_text()
    assert "Minimum of Z over Lz per bed" in text and "Verdict:" in text
    assert (tmp_path / "figure.png").stat().st_size > 10_000 and (tmp_path / "data.h5").exists()


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_systematics_quick(tmp_path):
    """The budget reads its protocols from the first seconds (periods) of long runs: a run of
    the protocol's own length gives the same per-bed values, to round-off, at both points; and
    every measured term has a finite shift, interval and standard uncertainty."""
    mod = _load("systematics")
    out = mod.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    s = mod.settings(True)
    from jaxdamp.cases import presets
    from jaxdamp.studies import efficiency as ef
    from jaxdamp.studies.sweep import sweep

    short = sweep(mod.thesis_config(s, s["short"]), {"frequency": list(s["freqs"])},
                  progress=False, echo=None, replicates=s["R"])
    np.testing.assert_allclose(mod._protocol_values(short, s["freqs"], "amplitude"),
                               out["thesis"]["base_short"]["Z"], rtol=1e-12)
    paper = ef.measure(presets.get(mod.PAPER), [s["amplitude"]], periods=s["paper_periods"],
                       transient=s["paper_transient"], progress=False, echo=None,
                       replicates=s["paper_R"])
    np.testing.assert_allclose(paper.replicate_summary["E_d_mean"][0],
                               out["paper"]["protocol"]["E_d"], rtol=1e-12)
    from jaxdamp.io.study import load

    b = mod.budget(load(str(tmp_path / "data.h5")))
    assert {p: set(q) for p, q in b.items()} == {p: set(q) for p, q in mod.QUANTITIES.items()}
    for point in b.values():
        for q in point.values():
            measured = [t for t in q["terms"].values() if isinstance(t, dict)]
            assert measured and all(np.isfinite([t["delta"], t["ci95"], t["u"]]).all()
                                    for t in measured)
            assert q["total"] == pytest.approx(np.sqrt(sum(t["u"] ** 2 for t in measured)))
    assert mod.relative_uncertainty(b, "thesis_optimum", "M_ef") == pytest.approx(
        2 * b["thesis_optimum"]["f_res"]["total"])
    assert mod.relative_uncertainty(b, "far") == pytest.approx(max(
        b["thesis_optimum"]["Z"]["total"], b["paper_reference"]["E_d"]["total"]))
    assert "| **total** |" in (tmp_path / "summary.md").read_text()


def test_friction_coefficient_quick(tmp_path):
    """Two friction coefficients × 2 frequencies × 2 beds: the walls are of the grains'
    material (so μ is both), and the report compares with μ = 0.3."""
    from jaxdamp.cases import presets

    cfg = presets.get("sanchez2012-optimal")
    assert cfg.box.wall is None and cfg.wall_material is cfg.grains[0].material
    out = _load("friction_coefficient").main(["--quick", "--out", str(tmp_path),
                                              "--no-progress"])
    assert out["Z"].shape == (2, 2, 2) and np.all(np.isfinite(out["Z_peak"]))
    text = (tmp_path / "summary.md").read_text()
    assert "| 0.3 |" in text and "reference" in text and "90 %" in text


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
def test_bed_dynamics_details_quick(tmp_path):
    """7.5, 8 and 14.5 Hz × 2 short beds: every measure is finite per bed, the 8 Hz line share
    is a fraction, and the impact episodes are counted per period on lid and floor."""
    out = _load("bed_dynamics_details").main(["--quick", "--out", str(tmp_path),
                                              "--no-progress"])
    assert set(out) == {7.5, 8.0, 14.5}
    for f, v in out.items():
        assert len(v["rows"]) == 2
        assert all(np.isfinite(r["Z_over_U"]) and r["a_over_g"] > 0 for r in v["rows"])
    assert all(0 < r["three_line_share"] <= 1 + 1e-12 for r in out[8.0]["rows"])
    row = out[14.5]["rows"][0]
    assert 0.5 < row["lid_episodes"] < 3 and 0.5 < row["floor_episodes"] < 3
    assert 0 <= row["lid_floor_separation"] < 360
    assert "14.5 Hz impacts" in (tmp_path / "summary.md").read_text()


def test_few_grains_friction_quick(tmp_path):
    """Two grain numbers × γ_s off and on × 2 beds: equal total mass (radius ∝ N^(-1/3)), a
    finite Z_res per bed and case, and a change with an interval in the summary."""
    rows = _load("few_grains_friction").main(["--quick", "--out", str(tmp_path),
                                              "--no-progress"])
    assert [r["N"] for r in rows] == [25, 50]
    assert rows[0]["radius"] ** 3 * 25 == pytest.approx(rows[1]["radius"] ** 3 * 50)
    assert all(np.all(np.isfinite(r["off"])) and np.all(np.isfinite(r["on"])) for r in rows)
    assert "change (95 %)" in (tmp_path / "summary.md").read_text()


def test_effective_field_chain_quick(tmp_path):
    """``effective_field.py --structure chain --quick``: the damper's map inserted into the
    2-DOF chain by harmonic balance beside the chain's coupled DEM, stored and summarised; the
    summary comes back from the data alone (``--from-data``). Physics checked at quick size:
    near mode 1 (9.25–9.5 Hz, U = 4.5 mm) the upper mass moves far more than the base in the
    coupled DEM, and every bed's consistent amplitude is one where its own map, inserted
    into the chain, gives back that amplitude (the balance closes)."""
    import h5py

    from jaxdamp.analysis.harmonic_balance import solve
    from jaxdamp.cases import presets
    from jaxdamp.physics.structure import matrices

    ef = _load("effective_field")
    ef.main(["--structure", "chain", "--quick", "--out", str(tmp_path), "--no-progress"])
    text = (tmp_path / "summary.md").read_text()
    assert "A 2-DOF structure" in text and "The chain's mode 1:" in text
    assert (tmp_path / "figure.png").exists() and (tmp_path / "map.png").exists()
    with h5py.File(tmp_path / "data.h5", "r") as h:
        dem, roots = h["chain/dem"][()], h["chain/roots"][()]
        A, f = h["map/amplitude"][()], h["map/frequency"][()]
        m, c = h["map/values/m_eff"][()], h["map/values/c_eff"][()]
    U = 4.5e-3
    assert dem.shape == (2, 2) and np.all(dem / U > 5.0) and np.all(dem / U < 30.0)
    M, K, C, r, b = matrices(presets.get("sanchez2012-chain"))
    for k in range(roots.shape[0]):
        for j, fj in enumerate(f):
            bal = solve(A, m[..., k], c[..., k], float(fj), M, K, C, r, b, U, 1, f)
            got = roots[k, j][np.isfinite(roots[k, j])]
            np.testing.assert_allclose(got, bal.roots, rtol=1e-9)
    (tmp_path / "summary.md").unlink()
    ef.main(["--from-data", "--out", str(tmp_path), "--no-progress"])
    assert (tmp_path / "summary.md").read_text() == text


def test_envelope_design_quick(tmp_path):
    """``envelope_design.py --quick``: the batched search over Lz against the worst point of a
    2 × 2 envelope, the single-point and the envelope design confirmed on fresh beds, the
    search-vs-Latin-hypercube measurement; stored, summarised, and the summary reproduced from
    the data alone. The stored worst case is the smallest per-point mean of the stored C_eq,
    and each C_eq is E / (π Ω Z²) of its point."""
    import h5py

    from jaxdamp.design.envelope import summarise

    ed = _load("envelope_design")
    ed.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    text = (tmp_path / "summary.md").read_text()
    assert "## B. Confirmation on fresh beds" in text and "by the rule" in text
    with h5py.File(tmp_path / "data.h5", "r") as h:
        C, Z, E = (h[f"confirmation/{k}"][()] for k in ("C", "Z", "E"))
        n = len(h["search/X"][()])
    assert C.shape == (4, 2, 2) and n == 5
    f = np.array([14.0, 15.16, 14.0, 15.16])[:, None, None]
    np.testing.assert_allclose(C, E / (np.pi * 2 * np.pi * f * Z ** 2), rtol=1e-12)
    s = summarise(C, "worst")
    assert np.all(s["value"] == C.mean(axis=2).min(axis=0))
    (tmp_path / "summary.md").unlink()
    ed.main(["--from-data", "--out", str(tmp_path), "--no-progress"])
    assert (tmp_path / "summary.md").read_text() == text


def test_mass_front_quick(tmp_path):
    """``mass_front.py --quick``: at two fills in the box and the cylinder, the optimal Lz
    above the bed, C_eq confirmed on fresh beds; the fill that doubles the grains doubles the
    mass ratio; summary reproduced from the data alone."""
    import h5py

    mf = _load("mass_front")
    mf.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    text = (tmp_path / "summary.md").read_text()
    with h5py.File(tmp_path / "data.h5", "r") as h:
        for c in ("box", "cylinder"):
            mu, n = h[f"{c}/mu"][()], h[f"{c}/grains"][()]
            assert np.all(h[f"{c}/lz"][()] > h[f"{c}/h_bed"][()])
            assert np.all(np.isfinite(h[f"{c}/C"][()])) and np.all(h[f"{c}/C"][()] > 0)
            assert mu[1] / mu[0] == pytest.approx(n[1] / n[0])
    (tmp_path / "summary.md").unlink()
    mf.main(["--from-data", "--out", str(tmp_path), "--no-progress"])
    assert (tmp_path / "summary.md").read_text() == text
