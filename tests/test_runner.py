"""Runs end to end: HDF5 contents, checkpoint/resume, non-finite stop, the CLI."""

import json

import h5py
import numpy as np
import pytest
from helpers import SMALL_RUN, small_config

from jaxdamp import cli
from jaxdamp.cases import presets
from jaxdamp.config import from_json
from jaxdamp.physics.energy import RECORD_UNITS
from jaxdamp.physics.model import N_CHANNELS
from jaxdamp.studies.runner import SimulationDiverged, run

SMALL = SMALL_RUN


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    path = tmp_path_factory.mktemp("run") / "run.h5"
    cfg = small_config()
    res = run(cfg, out=str(path), progress=False, echo=None)
    return cfg, res, path


def test_run_file_holds_config_series_snapshots_summary(finished):
    cfg, res, path = finished
    with h5py.File(path, "r") as h:
        assert from_json(h.attrs["config"]) == cfg
        assert h.attrs["status"] == "finished"
        n = h["series/t"].shape[0]
        assert n == 80  # 0.08 s sampled every 1 ms
        for name, unit in RECORD_UNITS.items():
            assert h[f"series/{name}"].shape[0] == n
            assert h[f"series/{name}"].attrs["units"] == unit
        assert h["series/work"].shape == (n, N_CHANNELS)
        assert json.loads(h["series/work"].attrs["channels"])[0] == "input"
        assert h["snapshots/r"].shape == (4, 30, 3)
        assert h["snapshots/q"].shape == (4, 30, 4)
        q = h["snapshots/q"][-1]
        np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
        s = h["summary"].attrs
        for key in ("amplitude", "granular_loss_per_cycle", "mean_vz_bed", "balance_error"):
            assert np.isfinite(s[key])
        assert 0 < h["settle"].attrs["bed_height"] < 0.05
        z_lo = h["series/z_lowest"][()]
        assert np.all(h["series/z_highest"][()] >= z_lo)


def test_resume_is_bit_identical(finished, tmp_path):
    cfg, res, _ = finished
    path = tmp_path / "part.h5"
    run(cfg, out=str(path), progress=False, echo=None, max_chunks=2)
    with h5py.File(path, "r") as h:
        assert h.attrs["status"] == "partial"
        assert h["series/t"].shape[0] == 40
    resumed = run(cfg, out=str(path), resume=True, progress=False, echo=None)
    for field in ("r", "v", "w", "q", "z", "zd", "work", "t"):
        np.testing.assert_array_equal(np.asarray(getattr(resumed.state, field)),
                                      np.asarray(getattr(res.state, field)))
    with h5py.File(path, "r") as h:
        np.testing.assert_array_equal(h["series/z_cm"][()], res.records["z_cm"])
        assert h.attrs["status"] == "finished"


def test_resume_refuses_a_different_config(finished, tmp_path):
    cfg, _, path = finished
    from jaxdamp.config import ConfigError

    with pytest.raises(ConfigError, match="different configuration"):
        run(small_config("frequency=12"), out=str(path), resume=True, progress=False, echo=None)


def test_non_finite_state_stops_with_message_and_keeps_data(tmp_path):
    """A time step far beyond the collision limit (forced past validation) blows up: the run
    stops naming time, step and quantity, and the file keeps the finite samples."""
    cfg = small_config("numerics.dt=2e-4", "numerics.dt_per_collision=1e-3",
                       "numerics.settle_time=0", "numerics.duration=0.2")
    path = tmp_path / "bad.h5"
    with pytest.raises(SimulationDiverged, match=r"non-finite by t = .* s \(step \d+\)"):
        run(cfg, out=str(path), progress=False, echo=None)
    with h5py.File(path, "r") as h:
        assert h.attrs["status"] == "diverged"
        assert "non-finite" in h.attrs["message"]
        assert h["series/t"].shape[0] > 0
        assert np.isfinite(h["series/z_cm"][()]).all()


def test_cli_run_and_info(tmp_path, capsys):
    out = tmp_path / "cli.h5"
    args = ["run", "--preset", "sanchez2012-optimal", "--out", str(out), "--no-progress"]
    for s in SMALL + ["numerics.duration=0.07"]:
        args += ["--set", s]
    assert cli.main(args) == 0
    text = capsys.readouterr().out
    assert "amplitude Z" in text and "energy balance error" in text
    assert cli.main(["info", str(out)]) == 0
    assert "settled bed height" in capsys.readouterr().out
    assert cli.main(["presets"]) == 0
    assert "varela2023-reference" in capsys.readouterr().out
    assert cli.main(["presets", "--show", "sanchez2012-optimal"]) == 0
    toml_text = capsys.readouterr().out
    import tomllib

    from jaxdamp.config import from_dict

    assert from_dict(tomllib.loads(toml_text)) == presets.get("sanchez2012-optimal")


def test_cli_run_with_replicates_reports_mean_se_and_detected_start(tmp_path, capsys):
    """`jaxdamp run --replicates 2` runs two independently settled beds in one batch and prints
    mean ± SE over them with the detected start of each replicate's steady state (here: a run
    too short to become stationary says so)."""
    out = tmp_path / "rep.h5"
    args = ["run", "--preset", "sanchez2012-optimal", "--out", str(out), "--no-progress",
            "--replicates", "2"]
    for s in SMALL + ["numerics.duration=0.3", "frequency=20"]:
        args += ["--set", s]
    assert cli.main(args) == 0
    text = capsys.readouterr().out
    assert "2 replicates" in text
    assert (("steady state detected" in text and "of 2 replicate" in text)
            or "steady state: not detected in any of 2 replicates" in text), text
    with h5py.File(out) as h:
        assert h.attrs["replicates"] == 2 and h["records/z_box"].shape[0] == 2
        assert h["steady/amplitude/start"].shape == (2,)
        assert h["steady"].attrs["replicates"] == 2
    assert cli.main(args[:1] + ["--preset", "sanchez2012-optimal", "--replicates", "0"]) == 2
    assert "--replicates: 0: must be > 0" in capsys.readouterr().err
