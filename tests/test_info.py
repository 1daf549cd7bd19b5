"""``jaxdamp info`` on every file kind the program writes, and one-line errors for files it
cannot read."""

import h5py
import numpy as np
import pytest

from jaxdamp.cases import presets
from jaxdamp.cli import main
from jaxdamp.config import apply_overrides


def _small(**extra):
    return apply_overrides(presets.get("sanchez2012-optimal"), dict({
        "grains.0.count": 8, "box.Lx": 0.02, "box.Ly": 0.02, "numerics.settle_time": 0.05,
        "primary.M": 0.3, "primary.K": 2720.0, "primary.C": 1.0, "numerics.duration": 0.05},
        **extra))


@pytest.mark.long  # half a minute (the marker's definition)
def test_info_describes_sweep_run_and_optimiser_files(tmp_path, capsys):
    from jaxdamp.design import Objective, S3Problem, optimize
    from jaxdamp.studies.sweep import sweep

    sw = tmp_path / "sweep.h5"
    sweep(_small(), {"frequency": [14.0, 15.0]}, out=str(sw), progress=False, echo=None,
          replicates=2)
    s3 = S3Problem(apply_overrides(presets.get("sanchez2012-impact"),
                                   {"numerics.analysis_window": 0.5}),
                   Objective("damping"), duration=1.0)
    opt = tmp_path / "opt.h5"
    optimize(s3, 0.05, max_iter=1, out=str(opt), progress=False)
    run = tmp_path / "run.h5"
    assert main(["run", "--preset", "sanchez2012-optimal", "--set", "grains.0.count=8",
                 "--set", "numerics.duration=0.07", "--set", "numerics.settle_time=0.05",
                 "--out", str(run), "--no-progress"]) == 0
    capsys.readouterr()
    for path, expect in ((sw, "(sweep file)"), (opt, "(optimiser log)"), (run, "(run file)")):
        assert main(["info", str(path)]) == 0
        out = capsys.readouterr().out
        assert expect in out, out
    assert "grid of frequency (2: 14 … 15) × 2 replicates" in (
        main(["info", str(sw)]), capsys.readouterr().out)[1]


def test_info_refuses_unreadable_files_in_one_line(tmp_path, capsys):
    text = tmp_path / "notes.txt"
    text.write_text("hello")
    foreign = tmp_path / "other.h5"
    with h5py.File(foreign, "w") as h:
        h["x"] = np.arange(3)
    truncated = tmp_path / "cut.h5"
    with h5py.File(truncated, "w") as h:
        h.attrs["format"] = "jaxdamp-sweep/1"
    for path, msg in ((tmp_path / "missing.h5", "no such file"), (text, "not an HDF5 file"),
                      (foreign, "not a jaxdamp file"), (truncated, "without its")):
        assert main(["info", str(path)]) == 2
        err = capsys.readouterr().err.strip()
        assert msg in err and "Traceback" not in err and len(err.splitlines()) == 1, err


def test_zero_or_negative_counts_are_errors_not_defaults(capsys):
    """`frf --n 0`, `efficiency --periods 0`, a negative budget, a NaN duration, a word for a
    count: each a one-line usage error (exit 2) before any compute, never a silent default."""
    from jaxdamp.cli import main

    for argv, msg in ((["frf", "--preset", "sanchez2012-optimal", "--n", "0"],
                       "--n: 0: must be > 0"),
                      (["efficiency", "--preset", "varela2023-reference", "--periods", "0"],
                       "--periods: 0: must be > 0"),
                      (["optimize", "--preset", "sanchez2012-optimal", "--budget", "-3"],
                       "--budget: -3: must be > 0"),
                      (["run", "--preset", "sanchez2012-optimal", "--duration", "nan"],
                       "--duration: nan: must be > 0"),
                      (["frf", "--preset", "sanchez2012-optimal", "--n", "two"], "not an integer"),
                      (["efficiency", "--preset", "varela2023-reference", "--transient", "-1"],
                       "must be ≥ 0")):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert msg in err and len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert main(["--help"]) == 0


def _chunk(path):
    try:
        with h5py.File(path, "r", locking=False) as h:
            return int(h["checkpoint"].attrs.get("chunk", 0)) if "checkpoint" in h else 0
    except (OSError, KeyError):
        return 0


def _interrupt_after(argv, path, chunks, timeout=300):
    """Start ``jaxdamp argv`` in a child, SIGINT it once ``path`` holds a checkpoint after
    ``chunks`` chunks; returns ``(exit status, stderr)``."""
    import signal
    import subprocess
    import sys
    import time

    # SIGINT as at a terminal, even when the tests themselves run as a background job (which
    # starts with SIGINT ignored, and Python then installs no KeyboardInterrupt handler)
    proc = subprocess.Popen([sys.executable, "-m", "jaxdamp", *argv], stderr=subprocess.PIPE,
                            stdout=subprocess.DEVNULL, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + timeout
    while time.time() < deadline and proc.poll() is None and _chunk(path) < chunks:
        time.sleep(0.2)
    assert proc.poll() is None, "the run ended before it could be interrupted"
    proc.send_signal(signal.SIGINT)
    err = proc.communicate(timeout=120)[1].strip()
    return proc.returncode, err


@pytest.mark.long
def test_ctrl_c_leaves_a_resumable_interrupted_file(tmp_path):
    """SIGINT to a running `jaxdamp run --out` (~300 chunks; interrupted after 3): exit 130, a
    one-line message with the exact command that resumes it, no traceback, the file marked
    'interrupted' with its checkpoint; the printed command continues from that checkpoint to
    the end (one strictly increasing time series of the full length)."""
    import shlex
    import subprocess
    import sys

    out = tmp_path / "long.h5"
    argv = ["run", "--preset", "sanchez2012-optimal", "--set", "grains.0.count=8",
            "--set", "numerics.settle_time=0.05", "--set", "numerics.duration=3",
            "--set", "numerics.chunk=0.01", "--out", str(out), "--no-progress"]
    code, err = _interrupt_after(argv, out, 3)
    assert code == 130, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert "Traceback" not in err and len(lines) == 2, err  # Ctrl-C noted, then what was kept
    assert lines[0].startswith("jaxdamp: Ctrl-C: stopping at the next safe point"), err
    assert "interrupted" in lines[1] and "--resume" in lines[1]
    with h5py.File(out, "r") as h:
        assert h.attrs["status"] == "interrupted" and "checkpoint" in h
        first = int(h["checkpoint"].attrs["chunk"])
        assert 3 <= first < 300
        assert h["series/t"].shape[0] == int(h["checkpoint"].attrs["n_records"])
    again = shlex.split(err.split("Continue with: ")[1])
    assert again[0] == "jaxdamp" and again[-1] == "--resume"
    done = subprocess.run([sys.executable, "-m", "jaxdamp", *again[1:]], capture_output=True,
                          text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    with h5py.File(out, "r") as h:
        assert h.attrs["status"] == "finished"
        t = h["series/t"][()]
        assert np.all(np.diff(t) > 0) and t[-1] == pytest.approx(3.0, abs=0.01)
