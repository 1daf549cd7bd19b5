"""The choice of a delay embedding (:func:`jaxdamp.analysis.dynamics.embedding_parameters`,
used by the bed-dynamics studies), against series whose answer is known."""

from __future__ import annotations

import doctest

import numpy as np
from scipy.integrate import solve_ivp

from jaxdamp.analysis import dynamics as dyn

F, DT = 2.0, 0.005  # 100 samples per drive period
T = np.arange(0.0, 100.0, DT)


def test_embedding_parameters_of_a_sine_delay_is_a_quarter_period():
    """A sine's mutual information first dips (prominently) at a quarter period, 25 samples;
    a sine is its own function of one delayed value: no false neighbours in one dimension."""
    dim, delay, mi, fnn = dyn.embedding_parameters(np.sin(2 * np.pi * F * T + 0.1), F, DT)
    assert abs(delay - 25) <= 2 and mi.shape == (201,)  # lags up to two periods
    assert len(fnn) == 8 and dim == 1


def test_embedding_parameters_limits_the_dimensions_of_a_short_series():
    """300 samples, 3 periods, τ = 24: m = 3 would leave 300 − 3·24 − 2·100 − 3 = 25 < 40
    samples past the two Theiler windows, so dimensions 1..3 are tried and no more (1..4
    with a 20-sample horizon: m = 4 would leave 300 − 4·24 − 2·120 − 3 < 0)."""
    x = np.sin(2 * np.pi * F * T[:300] + 0.1)
    _, delay, _, fnn = dyn.embedding_parameters(x, F, DT)
    assert delay == 24 and len(fnn) == 3
    _, _, _, fnn = dyn.embedding_parameters(x, F, DT, min_horizon=20)  # room for m = 4
    assert len(fnn) == 4


def test_embedding_parameters_of_lorenz_x_is_three_dimensional():
    """Lorenz's x (σ = 10, ρ = 28, β = 8/3), sampled every 0.01 time units and strobed once
    per time unit: the false neighbours vanish in 3 dimensions (Kennel et al. 1992)."""
    def rhs(t, s, sigma=10.0, rho=28.0, beta=8.0 / 3.0):
        x, y, z = s
        return [sigma * (y - x), x * (rho - z) - y, x * y - beta * z]

    t = np.arange(0.0, 150.0, 0.01)
    x = solve_ivp(rhs, (0.0, t[-1]), [1.0, 1.0, 1.0], method="DOP853", rtol=1e-10,
                  atol=1e-10, t_eval=t).y[0][5000:]
    dim, delay, _, fnn = dyn.embedding_parameters(x, 1.0, 0.01)
    assert dim == 3 and fnn[0] > 0.9 and fnn[2] < 0.01
    assert 5 <= delay <= 20


def test_embedding_parameters_docstring_example():
    finder = doctest.DocTestFinder()
    runner = doctest.DocTestRunner()
    for test in finder.find(dyn.embedding_parameters, "embedding_parameters",
                            globs={"embedding_parameters": dyn.embedding_parameters}):
        runner.run(test)
    assert runner.failures == 0 and runner.tries > 0
