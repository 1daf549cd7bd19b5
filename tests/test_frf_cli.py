"""`jaxdamp frf`: the sweep command writes HDF5 (summary, fit) and the figure."""

import h5py
import numpy as np

from jaxdamp import cli


def test_frf_cli_small(tmp_path, capsys):
    """3 frequencies × 2 heights × 2 independent beds in one batch: amplitudes per replicate,
    steady-state estimates, fits per replicate with both residual weightings. On this tiny,
    unsettled bed the two beds agree but 3 frequencies do not determine C_ef (the mean FRF's
    fit error is about its value): every fit is FAILED by the rule, with the reason."""
    out = tmp_path / "frf.h5"
    args = ["frf", "--preset", "sanchez2012-optimal", "--frequencies", "10,15,20",
            "--lz", "0.05,0.08", "--out", str(out), "--no-progress", "--replicates", "2",
            "--set", "grains.0.count=20", "--set", "numerics.duration=0.1",
            "--set", "numerics.chunk=0.05", "--set", "numerics.settle_time=0.05"]
    assert cli.main(args) == 0
    text = capsys.readouterr().out
    assert "Lz = 0.05 m: peak Z/U" in text and "relative fit FAILED (C_ef = " in text
    assert "(fit error of the mean FRF)" in text and "absolute fit FAILED" in text
    with h5py.File(out) as h:
        assert h.attrs["replicates"] == 2
        assert h["replicate_summary/amplitude"].shape == (3, 2, 2)
        assert h["steady/amplitude/values"].shape == (3, 2, 2)
        assert h["fit"].attrs["residuals"] == "relative"
        assert np.isfinite(h["fit/se_M_ef"][()]).all() and "fit/absolute/M_ef" in h
        assert h["fit/ok"][()].tolist() == [False, False] and h["fit"].attrs["failed"] == 2
        assert np.isfinite(h["fit/fit_se_C_ef"][()]).all()
        assert h["summary/amplitude"].shape == (3, 2)
        assert h["summary/amplitude"].attrs["units"] == "m"
        assert np.all(h["summary/amplitude"][()] > 0)
        assert h["fit/M_ef"].shape == (2,)
        assert list(h["axes/frequency"][()]) == [10.0, 15.0, 20.0]
        assert h.attrs["status"] == "finished"
    assert (tmp_path / "frf.png").stat().st_size > 10_000


def test_frf_cli_rejects_bad_frequencies(capsys):
    assert cli.main(["frf", "--preset", "sanchez2012-optimal", "--frequencies", "0,10"]) == 2
    assert "every frequency must be a finite number > 0 Hz" in capsys.readouterr().err
    assert cli.main(["frf", "--preset", "sanchez2012-optimal", "--fmin", "20", "--fmax", "10"]) == 2
    assert "need 0 < fmin < fmax" in capsys.readouterr().err
