"""The damper's effective-field maps (:mod:`jaxdamp.studies.maps`, ``jaxdamp map``) and the
harmonic balance that inserts them into a structure (:mod:`jaxdamp.analysis.harmonic_balance`)."""

import math

import numpy as np
import pytest

from jaxdamp.analysis import harmonic_balance as hb
from jaxdamp.analysis.response import grain_force_coefficients
from jaxdamp.cases import presets
from jaxdamp.config import ConfigError, apply_overrides

#: The thesis' damper with 40 grains: a map of two amplitudes at 12 Hz, 2 beds, in seconds.
SMALL = ["grains.0.count=40", "numerics.settle_time=0.3"]


@pytest.fixture(scope="module")
def small_map(tmp_path_factory):
    """A resting bed (A = 0.5 mm at 12 Hz: Γ = A Ω²/g = 0.29 < 1) and a flying one (5 mm:
    Γ = 2.9), two beds each, written to a sweep file and read back."""
    from jaxdamp.studies import maps

    cfg = apply_overrides(presets.get("sanchez2012-optimal"), SMALL)
    path = str(tmp_path_factory.mktemp("map") / "map.h5")
    field = maps.measure(cfg, [0.0005, 0.005], [12.0], periods=8, transient=2, replicates=2,
                         out=path, progress=False, echo=None)
    return field, maps.read(path)


def test_a_bed_resting_on_the_floor_moves_as_its_mass(small_map):
    """Below Γ = 1 the grains ride on the floor: the container feels their mass, m_eff = m_p
    to 1 %, and no damping: c_eff below 1 % of m_p Ω (the container does no work on them).
    (Without dividing out the force samples' half-interval lag the same bed shows c_eff =
    m_p Ω · ΩΔ/2 = 4.9 % of m_p Ω at 64 samples per period.) The contact losses of such a bed
    are not zero: under the viscous tangential law (no static friction) a loose bed creeps,
    and its friction spends the bed's own potential energy, not the container's work."""
    field, _ = small_map
    m_p, W = field.grain_mass, 2 * math.pi * 12.0
    assert np.allclose(field.values["m_eff"][0, 0], m_p, rtol=0.01)
    assert np.all(np.abs(field.values["c_eff"][0, 0]) < 0.01 * m_p * W)
    assert np.all(np.abs(field.values["c_force"][0, 0]) < 0.01 * m_p * W)


def test_the_force_does_the_work_the_grains_dissipate(small_map):
    """A flying bed (Γ = 2.9) in its steady state dissipates (ψ > 0.1); the damping read off
    the force samples' first harmonic equals the one from the container's work (the input
    channel, exact) to 3 % (the samples alias the impacts' harmonics: about a per cent at 64
    per period); and the grains' losses equal the container's work to 5 % (the difference is
    the bed's energy change over the few periods of the window)."""
    field, _ = small_map
    v = {q: x[1, 0] for q, x in field.values.items()}
    assert np.all(v["psi"] > 0.1)
    np.testing.assert_allclose(v["c_force"], v["c_eff"], rtol=0.03)
    np.testing.assert_allclose(v["E_diss"], v["E_input"], rtol=0.05)


def test_the_map_file_reads_back_what_was_measured(small_map):
    field, back = small_map
    for q in field.values:
        np.testing.assert_array_equal(back.values[q], field.values[q])
    np.testing.assert_array_equal(back.stationary, field.stationary)
    assert back.grain_mass == field.grain_mass and back.config == field.config


@pytest.mark.long
def test_a_bed_resting_in_a_cylinder_moves_as_its_mass():
    """Every container: the cylinder's resting bed (Γ = 0.29) is its mass to 1 %, with no
    damping (as the box's, :func:`test_a_bed_resting_on_the_floor_moves_as_its_mass`)."""
    from jaxdamp.studies import maps

    cfg = apply_overrides(presets.get("sanchez2012-cylinder"),
                          ["grains.0.count=40", "grains.0.mass_ratio=None",
                           "numerics.settle_time=0.3"])
    field = maps.measure(cfg, [0.0005], [12.0], periods=4, transient=1, replicates=1,
                         progress=False, echo=None)
    assert field.config.container.shape == "cylinder"
    m_p, W = field.grain_mass, 2 * math.pi * 12.0
    assert field.values["m_eff"][0, 0, 0] == pytest.approx(m_p, rel=0.01)
    assert abs(field.values["c_eff"][0, 0, 0]) < 0.01 * m_p * W


def test_force_samples_averaged_over_their_interval_are_unlagged():
    """A force that is a mass and a damper, sampled as interval means (the records'
    ``force_box``): with ``interval`` the coefficients come back exactly; without it the
    half-interval lag shows as a spurious damping."""
    f, m, c, A = 10.0, 0.5, 3.0, 1e-3
    W, dt = 2 * np.pi * f, 1.0 / (16 * f)
    t = np.arange(1, 16 * 20 + 1) * dt
    z = A * np.cos(W * t)
    # the interval mean of F = -m z'' - c z' = m W² A cos Wt + c W A sin Wt over (t - dt, t]
    F = (m * W * A * (np.sin(W * t) - np.sin(W * (t - dt)))
         - c * A * (np.cos(W * t) - np.cos(W * (t - dt)))) / dt
    r = grain_force_coefficients(t, z, F, f, interval=dt)
    assert r["m_add"] == pytest.approx(m, rel=1e-9) and r["c_add"] == pytest.approx(c, rel=1e-9)
    lagged = grain_force_coefficients(t, z, F, f)
    assert abs(lagged["c_add"] - c) > 0.1 * c


def _linear_structure():
    M = np.array([[2.0, 0.0], [0.0, 2.37]])
    K = np.array([[3e4, -1e4], [-1e4, 1e4]]) * 2.0
    C = np.array([[4.0, -1.0], [-1.0, 1.0]])
    return M, K, C, np.ones(2), np.zeros(2)


def test_a_constant_map_is_a_linear_added_mass_and_damper():
    """A map that does not depend on the amplitude adds ``m`` and ``c`` to the carrying
    degree of freedom: the balance's one root is the linear response, on the 1-DOF primary
    (closed form) and on a 2-DOF structure (the augmented linear solve), to 1e-10."""
    A, f = np.geomspace(1e-5, 1.0, 5), np.array([8.0, 12.0, 16.0])
    m, c = np.full((5, 3), 0.227), np.full((5, 3), 4.0)
    M, K, C, U = 2.37, 2.37 * (2 * np.pi * 15.2) ** 2, 7.6, 0.0045
    for freq in (8.0, 10.0, 15.0):  # 10 and 15 Hz between the map's frequencies
        W = 2 * np.pi * freq
        b = hb.solve(A, m, c, freq, [[M]], [[K]], [[C]], [1.0], [0.0], U, 0, f)
        exact = abs(K + 1j * W * C) * U / abs(K - W * W * (M + 0.227) + 1j * W * (C + 4.0))
        assert b.where == "inside" and len(b.roots) == 1
        assert b.single == pytest.approx(exact, rel=1e-10)
    shuffled = hb.solve(A[::-1], m[::-1], c[::-1], 10.0, [[M]], [[K]], [[C]], [1.0], [0.0], U,
                        0, f[::-1])  # nodes in any order
    assert shuffled.roots == hb.solve(A, m, c, 10.0, [[M]], [[K]], [[C]], [1.0], [0.0], U, 0,
                                      f).roots
    Ms, Ks, Cs, r, bf = _linear_structure()
    for attach in (0, 1):
        W = 2 * np.pi * 12.0
        D = Ks - W * W * Ms + 1j * W * Cs
        D[attach, attach] += -W * W * 0.227 + 1j * W * 4.0
        x = np.linalg.solve(D, (Ks + 1j * W * Cs) @ r * U)
        b = hb.solve(A, m, c, 12.0, Ms, Ks, Cs, r, bf, U, attach, f)
        assert b.single == pytest.approx(abs(x[attach]), rel=1e-10)


def test_a_softening_map_gives_three_branches_and_edges_are_reported():
    """A damper whose damping collapses above 5 mm (a map with a steep step in c_eff) on a
    lightly damped primary: at resonance the balance has three roots — each consistent,
    ``|X(A)| = A`` — the jump of a multi-valued response; a response beyond the map's
    amplitudes is reported as such, not extrapolated; a frequency outside the map too."""
    A = np.geomspace(1e-4, 0.1, 61)
    c = np.where(A < 5e-3, 500.0, 19.0)[:, None]  # below 5 mm 2 mm, above 50 mm at resonance
    m = np.zeros_like(c)
    M, K, C, U = 2.37, 2.37 * (2 * np.pi * 15.0) ** 2, 1.0, 0.0045
    b = hb.solve(A, m, c, 15.0, [[M]], [[K]], [[C]], [1.0], [0.0], U, 0, [15.0])
    assert b.where == "inside" and len(b.roots) == 3 and math.isnan(b.single)
    W = 2 * np.pi * 15.0
    for a in b.roots:
        ca = np.interp(np.log(a), np.log(A), c[:, 0])
        x = abs(K + 1j * W * C) * U / abs(K - W * W * M + 1j * W * (C + ca))
        assert x == pytest.approx(a, rel=1e-8)
    small = hb.solve(A[:10], m[:10], c[:10], 15.0, [[M]], [[K]], [[C]], [1.0], [0.0], U, 0,
                     [15.0])
    assert small.roots == () and small.where == "above"
    assert hb.solve(A, m, c, 20.0, [[M]], [[K]], [[C]], [1.0], [0.0], U, 0,
                    [15.0]).where == "outside"


def test_predict_balances_each_bed_and_reports_mean_and_se(small_map):
    """``predict`` on a map of 2 beds: one balance per bed and frequency, the response's
    mean ± SE over the beds equal to those of the per-bed roots."""
    field, _ = small_map
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), SMALL + ["primary.U=0.0002"])
    p = hb.predict(field, cfg)
    assert len(p["balances"]) == 2 and p["amplitude"].shape == (1, 2)
    Z = p["amplitude"][0]
    if np.all(np.isfinite(Z)):
        assert p["mean"][0] == pytest.approx(Z.mean())
        assert p["se"][0] == pytest.approx(Z.std(ddof=1) / math.sqrt(2))
    else:
        assert math.isnan(p["mean"][0])


@pytest.mark.parametrize("extra, needle", [
    (["--amplitudes", "0,0.01"], "amplitudes [0.0, 0.01]: every value must be a finite number"),
    (["--frequencies", "12,-1"], "frequencies [12.0, -1.0]: every value must be a finite"),
    (["--amplitudes", "0.01,0.01"], "values repeat"),
    (["--periods", "1"], "periods = 1: must be an integer ≥ 2"),
    (["--replicates", "0"], "must be > 0"),
])
def test_map_command_refuses_bad_grids_before_any_compute(extra, needle, capsys, tmp_path):
    from jaxdamp.cli import main

    code = main(["map", "--preset", "sanchez2012-optimal", "--out", str(tmp_path / "m.h5")]
                + extra)
    err = capsys.readouterr().err
    assert code == 2 and needle in err and "Traceback" not in err
    assert not (tmp_path / "m.h5").exists()


def test_map_command_needs_a_structure_to_predict(capsys):
    from jaxdamp.cli import main

    assert main(["map", "--preset", "varela2023-reference", "--predict"]) == 2
    assert "no structure to insert the map into" in capsys.readouterr().err


def test_a_map_is_the_whole_damper_of_one_degree_of_freedom():
    """The cells of a damper move as one in a map (all of them, on one degree of freedom);
    cells on several degrees of freedom are refused, naming them."""
    from jaxdamp.studies.maps import alone

    cells = alone(presets.get("sanchez2012-cells"), 0.01)
    assert cells.system == "driven" and cells.cells == 4 and cells.primary is None
    spread = apply_overrides(presets.get("sanchez2012-chain"), ["cells=2",
                                                                "structure.attach=[0, 1]"])
    with pytest.raises(ConfigError, match=r"degrees of freedom \[0, 1\]"):
        alone(spread)


@pytest.mark.long
def test_map_command_writes_the_map_its_figures_and_a_prediction(tmp_path, capsys):
    """``jaxdamp map --quick --predict --out``: the sweep file with ``/map``, both figures,
    the printed table; re-run with the same options it reuses the file (no --overwrite)."""
    import h5py

    from jaxdamp.cli import main

    out = tmp_path / "map.h5"
    args = ["map", "--preset", "sanchez2012-optimal", "--quick", "--predict", "--set",
            "grains.0.count=40", "--out", str(out), "--no-progress"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "E_diss [J]" in text and "harmonic balance" in text
    assert (tmp_path / "map.png").exists() and (tmp_path / "map_prediction.png").exists()
    with h5py.File(out, "r") as h:
        assert h["map/values/c_eff"].shape == (2, 2, 2)
        assert h["map/mean/E_diss"].attrs["units"] == "J"
    assert main(args + ["--png", str(tmp_path / "again.png")]) == 0
