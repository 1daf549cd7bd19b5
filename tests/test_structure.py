"""Multi-DOF primary structures (``Config.structure``): modal data against matrices, the empty
box's FRFs at every degree of freedom against the analytic ones under random base motion and a
harmonic force, on both engines; the energy balance with a bed; bad input refused."""

import math

import numpy as np
import pytest

from jaxdamp.analysis.response import first_harmonic
from jaxdamp.cases import presets
from jaxdamp.config import ConfigError, apply_overrides
from jaxdamp.physics.structure import matrices, order
from jaxdamp.studies import random as rnd
from jaxdamp.studies.sweep import sweep
from jaxdamp.validation import validate

#: a 2-DOF chain on the base: a 2 kg lower mass, the damper's 2.37 kg box on top (DOF 1)
M2 = [[2.0, 0.0], [0.0, 2.37]]
K2 = [[43000.0, -21500.0], [-21500.0, 21500.0]]
C2 = [[15.2, -7.6], [-7.6, 7.6]]
CHAIN = {"structure.M": M2, "structure.K": K2, "structure.C": C2, "structure.attach": 1}


def _empty(engine, extra):
    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          ["grains=[]", f"numerics.engine={engine!r}", "numerics.chunk=0.5",
                           "numerics.settle_time=0"])
    return apply_overrides(cfg, extra)


def _frf(M, K, C, w, load):
    return np.linalg.solve(np.asarray(K) - w * w * np.asarray(M) + 1j * w * np.asarray(C), load)


def test_modal_data_give_the_matrices_and_the_box_comes_first():
    """Mode shapes (unnormalised, with their modal masses), frequencies and damping ratios of a
    Rayleigh-damped chain reproduce its M, K, C to 1e-10; the engines' order puts the box's
    degree of freedom first."""
    from scipy.linalg import eigh

    M, K = np.array(M2), np.array(K2)
    C = 1e-4 * M + 4e-4 * K
    lam, phi = eigh(K, M)  # mass-normalised columns
    w = np.sqrt(lam)
    zeta = (1e-4 / w + 4e-4 * w) / 2
    shapes = phi * np.array([2.0, -0.5])  # any scaling, with m_k = scale²
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), {
        "structure.frequencies": list(w / (2 * math.pi)), "structure.damping": list(zeta),
        "structure.shapes": shapes.tolist(), "structure.modal_masses": [4.0, 0.25],
        "structure.attach": 1})
    validate(cfg)
    Mm, Km, Cm, r, b = matrices(cfg)
    np.testing.assert_allclose(Mm, M, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(Km, K, rtol=1e-10, atol=1e-6)
    np.testing.assert_allclose(Cm, C, rtol=1e-8, atol=1e-10)
    assert list(order(cfg)) == [1, 0] and np.all(r == 1) and np.all(b == 0)


@pytest.mark.parametrize("engine", ["jax", "native"])
def test_empty_two_dof_structure_random_frf_equals_the_analytic_frf(engine):
    """No grains, the box on the top mass of a 2-DOF chain, random base motion over 4–25 Hz
    (both modes): H1 of the box (z/u) and of the lower mass (y/u) equal
    (K − ω²M + iωC)⁻¹ (K + iωC) r at every line to 0.5 % (issue 16; measured ~1e-5)."""
    cfg = _empty(engine, {**CHAIN, "random.psd": [[4.0, 0.5], [25.0, 0.5]],
                          "random.resolution": 0.5, "primary.U": 0.0})
    res = rnd.measure(cfg, [1.0], duration=4.0, replicates=1, progress=False, echo=None)
    lev = res.levels[0]
    r = np.ones(2)
    M, K, C = np.array(M2), np.array(K2), np.array(C2)
    X = np.array([_frf(M, K, C, 2 * np.pi * f, (K + 2j * np.pi * f * C) @ r)
                  for f in lev["f"]])
    np.testing.assert_allclose(lev["H"], X[:, 1], rtol=5e-3)
    assert np.all(lev["coherence"] > 1 - 1e-6)
    assert res.dof == 1
    # the other degree of freedom, from the same run
    low = rnd.analyse(res.sweep, [1.0], 1, dof=0)
    assert low.dof == 0
    np.testing.assert_allclose(low.levels[0]["H"], X[:, 0], rtol=5e-3)
    assert np.all(low.levels[0]["coherence"] > 1 - 1e-6)
    with pytest.raises(ConfigError, match="dof = 2: the structure has 2 degree"):
        rnd.analyse(res.sweep, [1.0], 1, dof=2)


@pytest.mark.parametrize("engine", ["jax", "native"])
def test_empty_structure_under_a_harmonic_force_matches_the_analytic_response(engine):
    """No grains, no base motion, F0 cos Ωt on the lower mass of a stiffly damped chain
    (C = 2e-3 K, ζ ≈ 9–25 %): after the transient both degrees of freedom follow
    (K − Ω²M + iΩC)⁻¹ F0 e_0 to 0.5 % in amplitude and 0.01 rad in phase."""
    C = (2e-3 * np.array(K2)).tolist()
    cfg = _empty(engine, {**CHAIN, "structure.C": C, "structure.force": 50.0,
                          "structure.force_dof": 0, "primary.U": 0.0,
                          "numerics.duration": 1.5})
    freqs = [5.0, 12.0, 30.0]
    res = sweep(cfg, {"frequency": freqs}, progress=False, echo=None)
    for i, f in enumerate(freqs):
        X = _frf(M2, K2, C, 2 * np.pi * f, np.array([50.0, 0.0]))
        t = np.asarray(res.records["t"][i])
        sel = t > 1.0
        for series, x in ((np.asarray(res.records["z_box"][i]), X[1]),
                          (np.asarray(res.records["y_dofs"][i])[:, 0], X[0])):
            amp, ph = first_harmonic(t[sel], series[sel], f)
            assert amp == pytest.approx(abs(x), rel=5e-3), f
            assert abs(np.angle(np.exp(1j * (ph - np.angle(x))))) < 0.01, f


def test_energy_balance_closes_with_a_bed_on_a_structure():
    """250 grains on the top of a 3-DOF chain under the harmonic base motion and a force:
    the balance residual stays below 1e-3 of the input work (native engine; the JAX engine
    equals it to round-off, tests/test_native.py)."""
    M = np.diag([3.0, 2.0, 2.37])
    k = 21500.0
    K = k * np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), {
        "structure.M": M.tolist(), "structure.K": K.tolist(),
        "structure.C": (3e-4 * K).tolist(), "structure.attach": 2, "structure.force": 20.0,
        "structure.force_dof": 1, "numerics.settle_time": 0.3, "numerics.duration": 0.3,
        "numerics.engine": "native", "frequency": 8.0})
    res = sweep(cfg, {"frequency": [8.0]}, progress=False, echo=None)
    work = np.asarray(res.records["work"][0])
    resid = np.abs(np.asarray(res.records["balance_residual"][0])).max()
    assert work[-1, 0] > 0.05 and resid < 1e-3 * work[-1, 0]
    assert np.asarray(res.records["y_dofs"]).shape[-1] == 2


def test_bad_structure_input_is_refused_before_compute():
    cfg = presets.get("sanchez2012-optimal")
    bad = [({"structure.M": M2, "structure.K": [[43000.0, -21000.0], [-21500.0, 21500.0]]},
            "structure.K is not symmetric"),
           ({"structure.M": M2, "structure.K": [[1000.0, 3000.0], [3000.0, 1000.0]]},
            "structure.K is indefinite"),
           ({"structure.M": [[1.0, 0.0], [0.0, -1.0]], "structure.K": K2},
            "structure.M is not positive definite"),
           ({"structure.M": M2}, "stiffness matrix is missing"),
           ({"structure.M": M2, "structure.K": [[1.0]]}, "expected 2×2"),
           ({"structure.frequencies": [5.0, 12.0], "structure.shapes": [[1, 1], [1, -1]],
             "structure.modal_masses": [2.0, 0.0]}, "structure.modal_masses"),
           ({"structure.frequencies": [5.0, -12.0], "structure.shapes": [[1, 1], [1, -1]]},
            "structure.frequencies"),
           ({"structure.frequencies": [5.0, 12.0], "structure.shapes": [[1, 2], [2, 4]]},
            "singular"),
           ({**CHAIN, "structure.attach": 2}, "structure.attach = 2"),
           ({**CHAIN, "structure.frequencies": [5.0, 12.0]}, "not both"),
           ({**CHAIN, "structure.influence": [1.0]}, "structure.influence")]
    for overrides, message in bad:
        with pytest.raises(ConfigError, match=message):
            validate(apply_overrides(cfg, overrides))
    with pytest.raises(ConfigError, match="system 'driven'"):
        validate(apply_overrides(presets.family("varela2023-reference"), CHAIN))


def test_structure_file_loads_and_frf_refuses_it_in_one_line(tmp_path):
    """A TOML configuration with a [structure] table (the documented format) loads and
    validates; ``jaxdamp frf`` (a 1-DOF fit) refuses it with one line, no traceback."""
    import subprocess
    import sys

    from jaxdamp.config import load_toml

    path = tmp_path / "chain.toml"
    path.write_text("[structure]\nM = [[2.0, 0.0], [0.0, 2.37]]\n"
                    "K = [[43000.0, -21500.0], [-21500.0, 21500.0]]\n"
                    "C = [[15.2, -7.6], [-7.6, 7.6]]\nattach = 1\nforce = 20.0\n")
    cfg = validate(load_toml(str(path), presets.get("sanchez2012-optimal")))
    assert cfg.structure.attach == 1 and len(matrices(cfg)[0]) == 2
    done = subprocess.run([sys.executable, "-m", "jaxdamp", "frf", "--preset",
                           "sanchez2012-optimal", "--config", str(path), "--quick"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "does not apply to a multi-DOF" in done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.examples
def test_two_mode_structure_experiment_quick(tmp_path):
    """The damper at mode 1's against mode 2's antinode on test-sized settings: H1 per
    placement, per-realisation two-mode fits near the empty chain's modes, Welch verdicts;
    data, figure and summary written."""
    from helpers import load_experiment

    r = load_experiment("two_mode_structure").main(["--quick", "--out", str(tmp_path),
                                                    "--no-progress"])
    f_e = r["f_empty"]
    for dof in (0, 1):
        fits = r["runs"][dof]["fits"]
        assert fits.shape == (2, 6)
        np.testing.assert_allclose(fits[:, 0], f_e[0], rtol=0.05)
        np.testing.assert_allclose(fits[:, 2], f_e[1], rtol=0.05)
        assert np.all(fits[:, [1, 3]] > 0)
    text = (tmp_path / "summary.md").read_text()
    assert "| ζ_1 [%] |" in text and "Welch" in text
    assert (tmp_path / "figure.png").stat().st_size > 10_000
