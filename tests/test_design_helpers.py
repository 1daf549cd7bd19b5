"""What the studies take from :mod:`jaxdamp.design`: the local jackknife optimum of a scan
(``local_quadratic_optimum``), the central-difference check of the pathwise window derivative
(``DEMProblem.central_difference``) and the cost of one derivative call per mode
(``DEMProblem.derivative_cost``), on answers known in advance."""

import numpy as np
import pytest

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.design import DEMProblem, Objective
from jaxdamp.design.surface import local_quadratic_optimum

X = np.array([0.06, 0.08, 0.10, 0.12, 0.14])


def test_local_quadratic_optimum_on_exact_parabolas():
    """Replicates offset by constants share the vertex: the three points around the best mean
    sample give it exactly, with a jackknife error of zero; a minimum likewise."""
    J = 1 - 100 * (X[:, None] - 0.1) ** 2 + np.array([[0.0, 0.01, -0.02]])
    opt, pts = local_quadratic_optimum(X, J, maximise=True)
    np.testing.assert_allclose(pts, [0.08, 0.10, 0.12])
    assert opt.x == pytest.approx(0.1, abs=1e-12) and opt.se == pytest.approx(0.0, abs=1e-9)
    assert opt.interior and opt.replicates == 3
    opt, pts = local_quadratic_optimum(X, (X - 0.085) ** 2, maximise=False)  # one realisation
    np.testing.assert_allclose(pts, [0.06, 0.08, 0.10])
    assert opt.x == pytest.approx(0.085, abs=1e-12) and opt.interior and opt.replicates == 1


def test_local_quadratic_optimum_at_an_end_is_not_interior():
    """A curve still rising at the end of the grid: the last three points, no interior
    optimum (the best sample is returned)."""
    J = np.stack([X + 10 * X**2, X + 10 * X**2 + 0.01], axis=1)
    opt, pts = local_quadratic_optimum(X, J, maximise=True)
    np.testing.assert_allclose(pts, [0.10, 0.12, 0.14])
    assert not opt.interior and opt.x == pytest.approx(0.14)


class _Cubic(DEMProblem):
    """A window objective known in closed form, ``v(Lz) = (Lz³, 2 Lz)`` per window."""

    def __init__(self):  # no bed: only the finite-difference arithmetic is tested
        self.engines = []

    def window_values(self, ens, lz=None, engine="jax"):
        self.engines.append(engine)
        return np.array([lz**3, 2 * lz])


def test_central_difference_of_a_known_window_objective():
    """``(v(Lz + h) − v(Lz − h)) / 2h`` = ``3 Lz² + h²`` for the cube, exactly 2 for the line;
    at ``ens.lz`` by default, native forward runs by default."""
    prob, ens, h = _Cubic(), type("E", (), {"lz": 0.1})(), 1e-3
    np.testing.assert_allclose(prob.central_difference(ens, h), [3 * 0.01 + h**2, 2.0],
                               rtol=1e-9)
    np.testing.assert_allclose(prob.central_difference(ens, h, lz=0.2, engine="jax"),
                               [3 * 0.04 + h**2, 2.0], rtol=1e-9)
    assert prob.engines == ["auto", "auto", "jax", "jax"]


@pytest.mark.long
def test_derivative_cost_forward_needs_less_memory_than_reverse():
    """On a 24-grain bed: both modes report a compiled call's wall time and temporary memory,
    and forward mode (``jax.jvp``) needs less of it than reverse mode (``jax.grad`` with a
    checkpoint every ``record_every`` steps)."""
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), {
        "grains.0.count": 24, "box.Lx": 0.02, "box.Ly": 0.02, "numerics.settle_time": 0.15,
        "primary.M": 0.3, "primary.K": 2720.0, "primary.C": 1.0})
    prob = DEMProblem(cfg, Objective("dissipation"), window=0.0005, n_windows=2, burn_in=0.05)
    ens = prob.start_states(prob.bed.height + 0.01)
    cost = {m: prob.derivative_cost(ens, m) for m in ("forward", "reverse")}
    for c in cost.values():
        assert c["wall"] > 0 and np.isfinite(c["temp_bytes"]) and c["temp_bytes"] > 0
    assert cost["forward"]["temp_bytes"] < cost["reverse"]["temp_bytes"]
