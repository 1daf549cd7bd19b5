"""`jaxdamp frf`: the sweep command writes HDF5 (summary, fit) and the figure."""

import h5py
import numpy as np

from jaxdamp import cli


def test_frf_cli_small(tmp_path, capsys):
    out = tmp_path / "frf.h5"
    args = ["frf", "--preset", "sanchez2012-optimal", "--frequencies", "10,15,20",
            "--lz", "0.05,0.08", "--out", str(out), "--no-progress",
            "--set", "grains.0.count=20", "--set", "numerics.duration=0.1",
            "--set", "numerics.chunk=0.05", "--set", "numerics.settle_time=0.05"]
    assert cli.main(args) == 0
    text = capsys.readouterr().out
    assert "Lz = 0.05 m: peak Z/U" in text and "fit M_ef" in text
    with h5py.File(out) as h:
        assert h["summary/amplitude"].shape == (3, 2)
        assert h["summary/amplitude"].attrs["units"] == "m"
        assert np.all(h["summary/amplitude"][()] > 0)
        assert h["fit/M_ef"].shape == (2,)
        assert list(h["axes/frequency"][()]) == [10.0, 15.0, 20.0]
        assert h.attrs["status"] == "finished"
    assert (tmp_path / "frf.png").stat().st_size > 10_000


def test_frf_cli_rejects_bad_frequencies(capsys):
    assert cli.main(["frf", "--preset", "sanchez2012-optimal", "--frequencies", "0,10"]) == 2
    assert "every frequency must be > 0 Hz" in capsys.readouterr().err
    assert cli.main(["frf", "--preset", "sanchez2012-optimal", "--fmin", "20", "--fmax", "10"]) == 2
    assert "need 0 < fmin < fmax" in capsys.readouterr().err
