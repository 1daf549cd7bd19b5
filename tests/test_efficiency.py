"""Dissipation efficiency (jaxdamp.studies.efficiency, `jaxdamp efficiency`): the analysis against
planted records, E_pp + E_pw against the energy balance of a driven-box run, and the CLI."""

import dataclasses
import math
import subprocess
import sys

import h5py
import numpy as np
import pytest

from jaxdamp.cases import mixtures, presets
from jaxdamp.config import ConfigError
from jaxdamp.physics.model import CH, N_CHANNELS
from jaxdamp.studies import efficiency as ef
from jaxdamp.studies.runner import run, schedule

REF = presets.get("varela2023-reference")


def test_e_max_formula():
    # 4 m A² ω²: the paper's reference at 3 cm, 70 Hz
    assert ef.e_max(0.154, 0.03, 70.0) == pytest.approx(4 * 0.154 * 0.03**2 * (2 * math.pi * 70) ** 2)
    assert ef.e_max(0.154, 0.03, 70.0) == pytest.approx(107.25, abs=0.01)


def test_protocol_aligns_steps_samples_chunks_and_periods():
    cfg = ef.protocol(REF, periods=5, transient=2, samples_per_period=100,
                      amplitudes=[0.02, 0.04])
    T = 1 / 70
    num = cfg.numerics
    k = round(num.record_dt / num.dt)
    assert num.record_dt == pytest.approx(T / 100, rel=1e-14) and num.dt * k == pytest.approx(T / 100)
    # dt is at most t_c / 50 at the largest amplitude
    loud = REF.replace(drive=dataclasses.replace(REF.drive, amplitude=0.04))
    from jaxdamp.physics.model import config_dt, grain_radii

    assert num.dt <= config_dt(loud, grain_radii(loud)) * (1 + 1e-12)
    sched = schedule(cfg, num.dt)
    assert sched.record_every == k and sched.records_per_chunk == 25 and sched.n_chunks == 28
    assert num.analysis_window == pytest.approx(5 / 7)
    for bad, match in ((dict(periods=0), "periods = 0"), (dict(samples_per_period=50),
                                                           "multiple of 4"),
                       (dict(amplitudes=[0.0, 0.02]), "amplitude")):
        with pytest.raises(ConfigError, match=match):
            ef.protocol(REF, **{"periods": 5, **bad})
    with pytest.raises(ConfigError, match="driven box"):
        ef.protocol(presets.get("sanchez2012-optimal"))


def _planted_records(f, spp, n_periods, rates_pp, rates_pw, S=2):
    """Records of a fictitious run: loss rates constant within each period (J per period)."""
    n = n_periods * spp
    s = np.arange(1, n + 1)
    t = s / (f * spp)
    per = (s - 1) // spp
    frac = np.asarray(rates_pp)[per] / spp
    pp = np.cumsum(frac)
    pw = np.cumsum(np.asarray(rates_pw)[per] / spp)
    work = np.zeros((n, N_CHANNELS))
    work[:, CH["pp_normal"]] = 0.75 * pp
    work[:, CH["pp_friction"]] = 0.25 * pp
    work[:, CH["pw_normal"]] = pw
    work[:, CH["input"]] = pp + pw
    phase = (s % spp) / spp
    contacts = np.rint(10 + 5 * np.cos(2 * np.pi * phase)).astype(int)
    return dict(
        t=t, work=work, n_floor=contacts, n_lid=np.zeros(n, int), balance_residual=np.zeros(n),
        force_floor_lid=np.sin(2 * np.pi * phase), z_box=np.cos(2 * np.pi * phase),
        v_box=-np.sin(2 * np.pi * phase),
        n_floor_species=np.stack([contacts, 2 * contacts], -1), n_lid_species=np.zeros((n, S)),
        z_cm_species=np.stack([phase, -phase], -1), vz_cm_species=np.zeros((n, S)),
    )


def test_analysis_recovers_planted_per_period_energies():
    f, spp = 70.0, 20
    rates_pp = np.array([50.0, 30, 10, 12, 8, 14, 6])  # first 2 periods: the transient
    rates_pw = np.array([5.0, 5, 3, 2, 4, 2, 4])
    rec = _planted_records(f, spp, 7, rates_pp, rates_pw)
    cfg = REF.replace(frequency=f)
    out = ef.analyse(cfg, rec, periods=5, samples_per_period=spp)
    pp, s = out["per_period"], out["summary"]
    np.testing.assert_allclose(pp["E_pp"], rates_pp, rtol=1e-12)
    np.testing.assert_allclose(pp["E_pw"], rates_pw, rtol=1e-12)
    emax = ef.e_max(mixtures.granulate_mass(cfg), cfg.drive.amplitude, f)
    ed = (rates_pp + rates_pw)[2:] / emax
    assert s["E_d_mean"] == pytest.approx(ed.mean(), rel=1e-12)
    assert s["E_d_std"] == pytest.approx(ed.std(ddof=1), rel=1e-12)
    assert s["E_d_sem"] == pytest.approx(ed.std(ddof=1) / math.sqrt(5), rel=1e-12)
    # the linear fit to E_d(t): one-period integrals from every sample in the window
    loss = np.concatenate([[0.0], np.cumsum((rates_pp + rates_pw).repeat(spp) / spp)])
    starts = np.arange(2 * spp, 6 * spp + 1)
    ed_t = (loss[starts + spp] - loss[starts]) / emax
    slope, icpt = np.polyfit(starts / (f * spp), ed_t, 1)
    assert s["E_d_fit"] == pytest.approx(icpt + slope * 4 / f, rel=1e-9)
    assert s["E_d_trend"] == pytest.approx(slope / f, rel=1e-9)
    assert s["wall_fraction"] == pytest.approx(rates_pw[2:].sum() / (rates_pp + rates_pw)[2:].sum())
    ph = out["phase"]
    bins = np.arange(spp) / spp
    np.testing.assert_allclose(ph["phase"], bins)
    np.testing.assert_allclose(ph["contacts"], np.rint(10 + 5 * np.cos(2 * np.pi * bins)))
    np.testing.assert_allclose(ph["contacts_species"][:, 1], 2 * ph["contacts"])
    np.testing.assert_allclose(ph["z_box"], np.cos(2 * np.pi * bins), atol=1e-12)
    np.testing.assert_allclose(ph["z_cm_species"][:, 0], bins, atol=1e-12)
    with pytest.raises(ConfigError, match="only 7 whole periods"):
        ef.analyse(cfg, rec, periods=8, samples_per_period=spp)


def test_dissipation_channels_close_the_energy_balance_of_a_driven_box():
    """A class-b mixture (30 + 30 grains, σ = 0.5) in the paper's box at A_d = 3 cm: over the
    analysed periods, E_pp + E_pw equals the walls' input work minus the change of mechanical
    energy to 1e-3 (SPEC §4)."""
    small_ref = REF.replace(grains=(dataclasses.replace(REF.grains[0], count=60),),
                            numerics=dataclasses.replace(REF.numerics, settle_time=0.02))
    cfg = ef.protocol(mixtures.binary(small_ref, "b", 0.5), periods=2, transient=1)
    res = run(cfg, progress=False, echo=None, snapshots=False)
    rec = res.records
    out = ef.analyse(cfg, rec, periods=2)
    pp = out["per_period"]
    e_mech = rec["e_kinetic"] + rec["e_rotational"] + rec["e_gravitational"] + rec["e_elastic"]
    spp = 100
    i0, i1 = spp - 1, 3 * spp - 1  # samples at t = T and t = 3 T
    dissipated = (pp["E_pp"][1:] + pp["E_pw"][1:]).sum()
    balance = pp["E_input"][1:].sum() - (e_mech[i1] - e_mech[i0])
    assert dissipated > 1.0  # joules: the grains do hit the walls hard
    assert abs(balance - dissipated) / dissipated < 1e-3
    assert out["summary"]["balance_error"] < 1e-3
    assert 0 < out["summary"]["E_d_mean"] < 1.5
    # every grain is accounted for in the per-species contact counts
    assert np.all(rec["n_floor_species"].sum(-1) == rec["n_floor"])


@pytest.mark.long  # half a minute (the marker's definition)
def test_efficiency_cli_quick_writes_data_and_figures(tmp_path):
    out = tmp_path / "b.h5"
    cmd = [sys.executable, "-m", "jaxdamp", "efficiency", "--preset", "varela2023-b",
           "--sigma", "0.5", "--amplitude", "0.025,0.035", "--periods", "2", "--transient", "1",
           "--set", "numerics.settle_time=0.02", "--out", str(out), "--no-progress"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert "varela2023-b, σ = 0.5: 300 grains, 2 amplitudes" in p.stdout
    with h5py.File(out) as h5:
        g = h5["efficiency"]
        assert g["amplitude"][()].tolist() == [0.025, 0.035]
        assert g["summary/E_d_mean"].shape == (2,) and g["summary/E_d_mean"].attrs["units"] == "1"
        assert g["summary/E_pp"].attrs["units"] == "J"
        assert g["per_period/E_d"].shape == (2, 3)
        assert g["phase/contacts_species"].shape == (2, 100, 2)
        assert g["replicate_phase/force_floor_lid"].shape == (2, 1, 100)
        assert g["replicate_phase/force_floor_lid"].attrs["units"] == "N"
        assert h5["snapshots/r"].shape == (2, 4, 300, 3)
        assert "4 m A_d^2" in g.attrs["E_max"]
        assert np.all(np.isfinite(g["summary/E_d_mean"][()]))
    for suffix in ("", "_phase", "_snapshots"):
        assert (tmp_path / f"b{suffix}.png").stat().st_size > 10_000
    back = ef.read(str(out))
    assert back.config.grains[1].radius == pytest.approx(1.25e-3)
    # one bed: its phase curves are the mean's
    np.testing.assert_array_equal(back.replicate_phase["vz_cm_species"][:, 0],
                                  back.phase["vz_cm_species"])
    # bad input is refused before any compute, naming the parameter
    for args, match in ((["--preset", "varela2023-reference", "--sigma", "0.5"], "monodisperse"),
                        (["--preset", "varela2023-a", "--sigma", "1.5"], "sigma = 1.5"),
                        (["--preset", "varela2023-a", "--amplitude", "0.04:0.02:3"], "A0 <= A1"),
                        (["--preset", "nonsense"], "unknown")):
        p = subprocess.run([sys.executable, "-m", "jaxdamp", "efficiency", *args],
                           capture_output=True, text=True, timeout=120)
        assert p.returncode != 0 and match in p.stderr, p.stderr


def test_per_period_heights_and_segregation_index_recover_planted_values():
    """Per-period species heights above the floor are the period means of z_cm − z_box, and
    the segregation index is 2 (h_L − h_S)/(h_L + h_S): planted per-period heights on a moving
    floor come back to rounding; one species gives NaN."""
    f, spp, n_per = 70.0, 20, 6
    rec = _planted_records(f, spp, n_per, np.full(n_per, 10.0), np.full(n_per, 2.0))
    h_large = np.array([0.01, 0.02, 0.03, 0.03, 0.04, 0.05])
    h_small = np.array([0.01, 0.01, 0.02, 0.01, 0.04, 0.02])
    k = (np.arange(1, n_per * spp + 1) - 1) // spp  # period of every sample
    rec["z_cm_species"] = np.stack([h_large[k], h_small[k]], -1) + rec["z_box"][:, None]
    out = ef.analyse(REF.replace(frequency=f), rec, periods=4, samples_per_period=spp)
    pp = out["per_period"]
    np.testing.assert_allclose(pp["h_cm_species"], np.stack([h_large, h_small], -1), atol=1e-15)
    want = 2 * (h_large - h_small) / (h_large + h_small)
    np.testing.assert_allclose(pp["segregation"], want, atol=1e-12)
    assert out["summary"]["segregation"] == pytest.approx(want[2:].mean(), abs=1e-12)
    assert np.isnan(ef.segregation_index(np.array([[0.02], [0.03]]))).all()
    assert ef.segregation_index(np.array([0.02, 0.02])) == 0.0
