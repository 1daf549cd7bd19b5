"""The steady reading of a replicated sweep (:func:`jaxdamp.studies.grid.steady_replicates`)."""

import numpy as np
import pytest

from jaxdamp.studies.grid import SweepResult, steady_or_window, steady_replicates


def _result():
    """A 2 × 3 grid with R = 2: replicate (1, 2, 0) not detected stationary, replicate
    (0, 0, 1) stationary but NaN in "amplitude"; "loss" stationary everywhere."""
    shape = (2, 3, 2)
    steady_z = np.arange(12.0).reshape(shape)
    steady_z[0, 0, 1] = np.nan
    window_z = 100 + np.arange(12.0).reshape(shape)
    stat_z = np.ones(shape, bool)
    stat_z[1, 2, 0] = False
    steady = {"amplitude": {"values": steady_z, "stationary": stat_z},
              "loss": {"values": -steady_z, "stationary": np.ones(shape, bool)}}
    per_rep = {"amplitude": window_z, "loss": -window_z}
    return SweepResult(axes={"a": [0, 1], "b": [0, 1, 2]}, configs=[], path=None, records={},
                       summary={"wall_time": 12.5}, replicates=2, replicate_summary=per_rep,
                       steady=steady)


def test_steady_replicates_reads_every_key_as_steady_or_window():
    res = _result()
    st = steady_replicates(res, "amplitude", "loss")
    Z, W = st.values
    np.testing.assert_array_equal(Z, steady_or_window(res, "amplitude")[0])
    assert Z[1, 2, 0] == 110.0 and Z[0, 0, 1] == 101.0 and Z[0, 1, 0] == 2.0
    assert W[0, 0, 1] == -101.0 and W[1, 2, 0] == -10.0  # "loss" was stationary there
    assert st.fallback == (2, 1)  # the NaN, the non-stationary one; "loss": the NaN only
    assert st.stationary.dtype == bool and st.stationary.shape == (2, 3, 2)
    assert int(st.stationary.sum()) == 11 and not st.stationary[1, 2, 0]
    assert st.wall == 12.5 and isinstance(st.wall, float)


def test_steady_replicates_needs_a_key():
    with pytest.raises(ValueError, match="at least one key"):
        steady_replicates(_result())
