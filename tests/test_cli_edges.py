"""The edges a user touches, through the real command line: existing outputs are never replaced
without --overwrite, every file problem is one line before any compute (and before JAX is
imported), --debug shows the traceback, failed FRF fits and unsettled beds are flagged."""

import json
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest

from jaxdamp.cli import main

SMALL_RUN = ["--preset", "sanchez2012-optimal", "--set", "grains.0.count=8",
             "--set", "numerics.duration=0.07", "--set", "numerics.settle_time=0.01",
             "--no-progress"]


def _one_line_error(capsys, code, *names):
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    for name in names:
        assert name in err, err
    return err


def _snapshot(folder):
    """Every file under ``folder`` with its bytes: what a refused command must leave as it was."""
    out = {}
    for root, _, files in os.walk(folder):
        for f in files:
            p = os.path.join(root, f)
            with open(p, "rb") as fh:
                out[p] = fh.read()
    return out


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    """A real run file of 8 grains (settling cut short: the bed is still moving) and what
    `jaxdamp run` printed."""
    import contextlib
    import io

    path = tmp_path_factory.mktemp("run") / "run.h5"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["run", *SMALL_RUN, "--out", str(path)]) == 0
    return path, buf.getvalue()


def test_existing_outputs_are_refused_and_left_untouched(tmp_path, capsys, run_file):
    """Each command that writes a file, pointed at an existing one without --overwrite: exit
    2, one line naming the file and --overwrite, every file in the folder byte-identical and
    no new file."""
    run, _ = run_file
    old = tmp_path / "old.h5"
    old.write_bytes(b"precious results")
    png = tmp_path / "old.png"
    png.write_bytes(b"precious figure")
    (tmp_path / "new_phase.png").write_bytes(b"precious phase figure")
    (tmp_path / "x.xyz").write_bytes(b"precious trajectory")
    (tmp_path / "v_0000.vtk").write_bytes(b"precious frame")
    before = _snapshot(tmp_path)
    cases = [
        (["run", "--preset", "sanchez2012-optimal", "--out", str(old)], old),
        (["run", "--preset", "sanchez2012-optimal", "--replicates", "2", "--out", str(old)], old),
        (["frf", "--preset", "sanchez2012-optimal", "--out", str(old)], old),
        (["frf", "--preset", "sanchez2012-optimal", "--out", str(tmp_path / "f.h5"),
          "--png", str(png)], png),
        (["frf", "--preset", "sanchez2012-optimal", "--png", str(png)], png),
        (["efficiency", "--preset", "varela2023-reference", "--out", str(old)], old),
        (["efficiency", "--preset", "varela2023-reference", "--out", str(tmp_path / "new.h5")],
         tmp_path / "new_phase.png"),
        (["optimize", "--preset", "sanchez2012-optimal", "--out", str(old)], old),
        (["plot", str(run), "--kind", "energy", "--out", str(png)], png),
        (["export", str(run), "--format", "xyz", "--out", str(tmp_path / "x.xyz")],
         tmp_path / "x.xyz"),
        (["export", str(run), "--format", "vtk", "--out", str(tmp_path / "v.pvd")],
         tmp_path / "v_0000.vtk"),
    ]
    for argv, clash in cases:
        err = _one_line_error(capsys, main(argv), str(clash), "--overwrite", "already exists")
        assert ("--resume" in err) == (argv[0] in ("run", "frf") and clash == old), err
        assert _snapshot(tmp_path) == before, argv


def test_overwrite_replaces_and_resume_keeps(tmp_path, capsys, run_file):
    run, _ = run_file
    png = tmp_path / "e.png"
    png.write_bytes(b"old")
    assert main(["plot", str(run), "--kind", "energy", "--out", str(png), "--overwrite"]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"
    xyz = tmp_path / "r.xyz"
    xyz.write_text("old")
    assert main(["export", str(run), "--format", "xyz", "--out", str(xyz), "--overwrite"]) == 0
    assert xyz.read_text().startswith("8\n")
    capsys.readouterr()
    _one_line_error(capsys, main(["run", *SMALL_RUN, "--out", str(run), "--resume",
                                  "--overwrite"]), "--resume", "--overwrite")
    _one_line_error(capsys, main(["run", *SMALL_RUN, "--resume"]), "--resume needs --out")


def _unwritable_folder(tmp_path):
    """A folder this process cannot create files in (a read-only folder; as root, whom the
    permission bits do not stop, a kernel file system that takes no new files)."""
    ro = tmp_path / "read_only"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        (ro / "probe").write_text("")
    except OSError:
        return ro
    (ro / "probe").unlink()
    for candidate in ("/proc", "/sys"):
        try:
            open(os.path.join(candidate, "jaxdamp_probe"), "w").close()
        except OSError:
            return candidate
    pytest.skip("no unwritable folder on this machine")


def test_output_folders_are_checked_up_front(tmp_path, capsys, run_file):
    """A missing folder, a file where a folder should be, a folder that takes no files: one
    line naming the path, for every file a command writes (PNGs included), nothing written."""
    run, _ = run_file
    a_file = tmp_path / "a_file"
    a_file.write_text("")
    ro = _unwritable_folder(tmp_path)
    missing = tmp_path / "missing_dir"
    for argv, path, what in (
            (["run", "--preset", "sanchez2012-optimal", "--out", f"{missing}/x.h5"],
             f"{missing}/x.h5", "does not exist"),
            (["frf", "--preset", "sanchez2012-optimal", "--png", f"{missing}/x.png"],
             f"{missing}/x.png", "does not exist"),
            (["frf", "--preset", "sanchez2012-optimal", "--out", str(tmp_path / "ok.h5"),
              "--png", f"{a_file}/x.png"], f"{a_file}/x.png", "is not a folder"),
            (["efficiency", "--preset", "varela2023-reference", "--out", f"{ro}/e.h5"],
             f"{ro}/e.h5", "cannot write into the folder"),
            (["efficiency", "--preset", "varela2023-reference", "--out", str(tmp_path / "e.h5"),
              "--png", f"{missing}/e.png"], f"{missing}/e.png", "does not exist"),
            (["optimize", "--preset", "sanchez2012-impact", "--out", f"{ro}/o.h5"],
             f"{ro}/o.h5", "cannot write into the folder"),
            (["plot", str(run), "--kind", "band", "--out", f"{missing}/b.png"],
             f"{missing}/b.png", "does not exist"),
            (["export", str(run), "--format", "vtk", "--out", f"{a_file}/vtk/v.pvd"],
             f"{a_file}/vtk/v.pvd", "is not a folder"),
            (["export", str(run), "--format", "xyz", "--out", f"{ro}/new/x.xyz"],
             f"{ro}/new/x.xyz", "cannot write into the folder"),
            (["run", "--preset", "sanchez2012-optimal", "--out", str(tmp_path)],
             str(tmp_path), "is a folder")):
        _one_line_error(capsys, main(argv), path, what)
    assert not missing.exists()
    assert sorted(os.listdir(tmp_path)) == ["a_file", "read_only"]


def test_config_file_problems_are_one_line_errors(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\nfrequency = = 12\n')
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe\x00junk")
    for path, what in ((tmp_path / "nope.toml", "no such file"),
                       (bad, "TOML syntax error: Invalid value (at line 2, column 13)"),
                       (binary, "not a UTF-8 text file"),
                       (tmp_path, "is a folder")):
        for command in ("run", "frf", "optimize", "efficiency"):
            _one_line_error(capsys, main([command, "--config", str(path)]),
                            f"configuration file {path}", what)


def test_file_errors_answer_before_jax_is_imported(tmp_path):
    """Bad files and bad values are refused before any compute: in a fresh interpreter, the
    command returns 2 without having imported JAX or numba (which take seconds)."""
    old = tmp_path / "old.h5"
    old.write_bytes(b"x")
    bad = tmp_path / "bad.toml"
    bad.write_text("[box\n")
    cases = [["run", "--preset", "sanchez2012-optimal", "--out", str(old)],
             ["run", "--preset", "sanchez2012-optimal", "--set", "foo=1"],
             ["run", "--preset", "sanchez2012-optimal", "--set", "numerics.duration=nan"],
             ["run", "--config", str(bad)],
             ["frf", "--preset", "sanchez2012-optimal", "--png", f"{tmp_path}/no/x.png"],
             ["optimize", "--preset", "sanchez2012-optimal", "--out", str(old)],
             ["plot", str(old), "--kind", "band", "--out", str(old)],
             ["efficiency", "--preset", "varela2023-reference", "--png", f"{tmp_path}/no/x"],
             ["map", "--preset", "sanchez2012-optimal", "--png", f"{tmp_path}/no/x"],
             ["map", "--preset", "sanchez2012-optimal", "--amplitudes", "-1"]]
    code = ("import json, sys\nfrom jaxdamp.cli import main\n"
            f"codes = [main(a) for a in {cases!r}]\n"
            "print(json.dumps([codes, 'jax' in sys.modules, 'numba' in sys.modules]))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       check=False)
    codes, jax_loaded, numba_loaded = json.loads(p.stdout.strip().splitlines()[-1])
    assert codes == [2] * len(cases), p.stderr
    assert not jax_loaded and not numba_loaded
    assert len(p.stderr.strip().splitlines()) == len(cases) and "Traceback" not in p.stderr
    # --help too
    helped = ("import sys\nfrom jaxdamp.cli import main\n"
              "main(['run', '--help'])\nprint('jax' in sys.modules)")
    p = subprocess.run([sys.executable, "-c", helped], capture_output=True, text=True,
                       timeout=120, check=False)
    assert p.stdout.strip().endswith("False"), p.stdout[-200:]


def test_debug_shows_the_traceback(tmp_path):
    argv = ["run", "--config", str(tmp_path / "nope.toml")]
    plain = subprocess.run([sys.executable, "-m", "jaxdamp", *argv], capture_output=True,
                           text=True, timeout=120, check=False)
    assert plain.returncode == 2 and "Traceback" not in plain.stderr
    debug = subprocess.run([sys.executable, "-m", "jaxdamp", "--debug", *argv],
                           capture_output=True, text=True, timeout=120, check=False)
    assert debug.returncode == 1 and "Traceback" in debug.stderr
    assert "ConfigError: configuration file" in debug.stderr


def test_an_unsettled_bed_is_flagged(run_file):
    """Settling cut short (numerics.settle_time = 0.01 s, the grains still falling): `jaxdamp
    run` prints a warning, the run file's /settle says settled = false, `info` says so."""
    path, printed = run_file
    assert "warning: the bed did NOT settle" in printed, printed
    with h5py.File(path) as h:
        assert not h["settle"].attrs["settled"]
        assert h["settle"].attrs["max_speed"] > 0.01
    from jaxdamp.io import describe

    assert "NOT settled" in describe(str(path))


def test_failed_frf_fits_are_flagged_not_drawn(tmp_path):
    """An undamped FRF with 5 % noise: the fit runs onto C_ef = 0 with an infinite
    uncertainty (the issue's `C_ef = 5.9e-10 ± nan`). It is reported as failed, stored with
    /fit/ok = false and its reason, and the figure draws no fit curve for it; a clean damped
    FRF fits and is drawn."""
    from jaxdamp.analysis.response import fit_frf_replicates, frf_amplitude
    from jaxdamp.cases import presets
    from jaxdamp.figures import frf_figure
    from jaxdamp.io.sweepfile import fit_failure, write_fit

    f = np.array([10.0, 12.0, 14.0, 17.0, 19.0])
    U, K = 0.001, 9000.0
    rng = np.random.default_rng(0)
    noisy = frf_amplitude(f, 1.2, K, 0.0, U) * (1 + 0.05 * rng.standard_normal(len(f)))
    clean = frf_amplitude(f, 1.2, K, 20.0, U)
    fits = {w: [fit_frf_replicates(f, Z[:, None], U, K, M0=1.0, C0=1.0, residuals=w)
                for Z in (noisy, clean)] for w in ("relative", "absolute")}
    bad, good = fits["relative"]
    assert bad["C_ef"] < 1e-6 and "bound 0" in fit_failure(bad)
    assert fit_failure(good) == "" and abs(good["C_ef"] - 20.0) < 1e-6
    assert "not finite" in fit_failure(dict(good, fit_se_C=float("nan")))
    assert "not finite" in fit_failure(dict(good, replicates=2, se_C=float("inf")))
    with h5py.File(tmp_path / "s.h5", "w") as h:
        write_fit(h, fits, "relative")
    with h5py.File(tmp_path / "s.h5") as h:
        assert h["fit/ok"][()].tolist() == [False, True]
        assert h["fit"].attrs["failed"] == 1
        assert b"bound 0" in h["fit/failure"][0]
    p = presets.get("sanchez2012-optimal").primary
    fig = frf_figure(f, np.stack([noisy, clean], axis=1), [0.07, 0.09], p, 0.1,
                     [None, (good["M_ef"], good["C_ef"])], failures=[fit_failure(bad), ""])
    labels = [line.get_label() for line in fig.axes[0].get_lines()]
    assert sum(lab.startswith("fit: M_ef") for lab in labels) == 1
    assert any(lab.startswith("fit failed") for lab in labels)
    drawn = [line for line in fig.axes[0].get_lines() if line.get_label().startswith("fit")]
    assert [len(line.get_xdata()) > 0 for line in drawn] == [False, True]


def test_validation_names_the_contact_laws_of_the_physics():
    """validation.CONTACT_LAWS (checked without importing JAX) lists the registered laws."""
    from jaxdamp.physics.contact import LAWS
    from jaxdamp.validation import CONTACT_LAWS

    assert CONTACT_LAWS == tuple(LAWS)


def test_validation_names_the_precisions_of_the_physics():
    """validation.PRECISIONS (checked without importing JAX) lists the contact laws' types."""
    from jaxdamp.physics.contact import PRECISIONS as TYPES
    from jaxdamp.validation import PRECISIONS

    assert PRECISIONS == tuple(TYPES)
