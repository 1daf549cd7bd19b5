"""Nothing lost, nothing meaningless: one writer per output (two real processes), a disk that
fills (an injected shortfall, and a real tmpfs), Ctrl-C from the first line of `main` (SIGINT
in a child at several moments of start-up), damaged files refused on resume, batches sized
before compute, and the physical sanity limits of a run's schedule."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from jaxdamp import interrupt
from jaxdamp.cli import main
from jaxdamp.config import ConfigError
from jaxdamp.io import claims

# a run of a few seconds: 8 grains, one period of the thesis' 15.16 Hz in 7 chunks
TINY = ["--preset", "sanchez2012-optimal", "--set", "grains.0.count=8",
        "--set", "numerics.duration=0.07", "--set", "numerics.chunk=0.01",
        "--set", "numerics.settle_time=0.01", "--no-progress"]


def _child(argv, **kw):
    """``jaxdamp argv`` in a child with SIGINT as at a terminal (not ignored, even when the
    tests run as a background job)."""
    return subprocess.Popen([sys.executable, "-m", "jaxdamp", *argv], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
                            **kw)


# -- one writer per output -------------------------------------------------------------------

HOLD = ("import sys, time; from jaxdamp.io import claims; claims.claim(sys.argv[1]); "
        "print('held', flush=True); time.sleep(60)")


def test_a_claimed_output_is_refused_before_compute_and_a_dead_holder_blocks_nobody(
        tmp_path, capsys):
    out = tmp_path / "same.h5"
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(out)], stdout=subprocess.PIPE,
                              text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        t0 = time.perf_counter()
        assert main(["run", *TINY, "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert time.perf_counter() - t0 < 5.0  # before JAX, settling or any file
        assert len(err.splitlines()) == 1 and "Traceback" not in err, err
        assert f"{out} is being written by another jaxdamp process (pid {holder.pid}" in err
        assert not out.exists()
        # --overwrite and --resume do not get past it either
        assert main(["run", *TINY, "--out", str(out), "--overwrite"]) == 2
        assert "being written by another" in capsys.readouterr().err
    finally:
        holder.kill()
        holder.wait()
    assert claims.lock_path(out) and os.path.exists(claims.lock_path(out))  # left by the kill
    claims.claim(out)  # the kernel dropped the dead holder's lock: claimed again at once
    assert claims.held(out)
    claims.release(out)
    assert not os.path.exists(claims.lock_path(out)) and not claims.held(out)


def test_claims_are_counted_within_a_process(tmp_path):
    out = tmp_path / "x.h5"
    claims.claim(out)
    claims.claim(out)  # the writer's claim on top of the command's: never blocks itself
    claims.release(out)
    assert claims.held(out)
    claims.release(out)
    assert not claims.held(out)


@pytest.mark.long
def test_two_jobs_on_one_output_one_refused_the_other_intact(tmp_path):
    """Two real `jaxdamp run` processes started together on one --out (the battery's F15): one
    is refused in one line before computing, the other finishes and its file opens whole."""
    out = tmp_path / "same.h5"
    procs = [_child(["run", *TINY, "--out", str(out)]) for _ in range(2)]
    results = [(p.wait(timeout=600), p.communicate()[1]) for p in procs]
    codes = sorted(code for code, _ in results)
    assert codes == [0, 2], results
    err = next(e for code, e in results if code == 2)
    assert "is being written by another jaxdamp process" in err and "Traceback" not in err
    with h5py.File(out, "r") as h:
        assert h.attrs["status"] == "finished"
        assert np.all(np.diff(h["series/t"][()]) > 0)
    assert not os.path.exists(claims.lock_path(out))


# -- a disk that fills -----------------------------------------------------------------------

def _small_config():
    import helpers

    from jaxdamp.config import Primary

    return helpers.config(n=6, system="primary", gravity=9.81, frequency=15.0,
                          primary=Primary(M=2.0, K=2e4, C=5.0, U=1e-3),
                          duration=0.04, chunk=0.005, record_dt=2.5e-4, settle_time=0.01)


@pytest.mark.long
def test_a_full_disk_stops_between_chunks_and_the_file_resumes_bit_identically(
        tmp_path, monkeypatch):
    """The disk's free space is made to run out after 3 chunks (injected): the run stops with
    one DiskFull error before writing the 4th chunk, the file is marked 'stopped' and holds 3
    whole chunks and their checkpoint; with room again, --resume ends exactly where an
    uninterrupted run ends."""
    from jaxdamp.io.common import DiskFull
    from jaxdamp.studies.runner import run

    cfg = _small_config()
    ref = run(cfg, out=str(tmp_path / "ref.h5"), progress=False, echo=None)
    real = shutil.disk_usage
    calls = {"n": 0}

    def filling(path):
        calls["n"] += 1
        total, used, free = real(path)
        # 1: the batch's size check; 2-4: chunks 1-3 have room; then 100 kB are left
        return type(real(path))(total, used, free if calls["n"] <= 4 else 100_000)

    out = tmp_path / "full.h5"
    monkeypatch.setattr(shutil, "disk_usage", filling)
    with pytest.raises(DiskFull, match=r"the disk holding .*full\.h5 is full: 100 kB free"):
        run(cfg, out=str(out), progress=False, echo=None)
    monkeypatch.setattr(shutil, "disk_usage", real)
    assert not claims.held(out)
    with h5py.File(out, "r") as h:
        assert h.attrs["status"] == "stopped" and "is full" in h.attrs["message"]
        assert int(h["checkpoint"].attrs["chunk"]) == 3
        assert h["series/t"].shape[0] == int(h["checkpoint"].attrs["n_records"]) == 60
    res = run(cfg, out=str(out), resume=True, progress=False, echo=None)
    for k in ref.records:
        np.testing.assert_array_equal(res.records[k], ref.records[k], err_msg=k)
    with h5py.File(out, "r") as h:
        assert h.attrs["status"] == "finished"


@pytest.mark.long
def test_a_run_file_is_resumable_from_its_settled_start(tmp_path):
    """The checkpoint is written with the file (chunk 0): a run stopped before its first chunk
    finished is continued, not lost."""
    from jaxdamp.studies.runner import run

    cfg = _small_config()
    out = tmp_path / "r.h5"
    assert run(cfg, out=str(out), progress=False, echo=None, max_chunks=0) is not None
    with h5py.File(out, "r") as h:
        assert int(h["checkpoint"].attrs["chunk"]) == 0 and h.attrs["status"] == "partial"
    ref = run(cfg, progress=False, echo=None)
    res = run(cfg, out=str(out), resume=True, progress=False, echo=None)
    np.testing.assert_array_equal(res.records["z_box"], ref.records["z_box"])


def test_resume_refuses_a_damaged_file_in_one_line(tmp_path):
    """Holes left by a full disk (zeros) or overwritten bytes are found before a resume."""
    from jaxdamp.studies.runner import run

    cfg = _small_config()
    out = tmp_path / "d.h5"
    run(cfg, out=str(out), progress=False, echo=None, max_chunks=3)
    with h5py.File(out, "a") as h:
        h["series/t"][-10:] = 0.0  # what a failed write reads back as
    with pytest.raises(ConfigError, match=r"is damaged \(its sampled times stop increasing "
                                          r"at sample 50\)"):
        run(cfg, out=str(out), resume=True, progress=False, echo=None)
    with h5py.File(out, "a") as h:
        h["series/t"][-10:] = np.arange(50, 60) * 2.5e-4 + 2.5e-4
        h["checkpoint/state/r"][0, 0] = np.nan
    with pytest.raises(ConfigError, match=r"checkpoint's state/r is not finite"):
        run(cfg, out=str(out), resume=True, progress=False, echo=None)


def test_resume_refuses_a_checkpoint_of_an_older_version_in_one_line(tmp_path):
    """A file written before the wall groups (no ``n_side``, 7 work channels) cannot go on
    bit-identically: the resume says so instead of failing deep in the driver."""
    from jaxdamp.studies.runner import run

    cfg = _small_config()
    out = tmp_path / "old.h5"
    run(cfg, out=str(out), progress=False, echo=None, max_chunks=1)
    with h5py.File(out, "a") as h:
        del h["checkpoint/state/n_side"]
    with pytest.raises(ConfigError, match=r"written by an older jaxdamp \(its state lacks "
                                          r"n_side\); it cannot be continued"):
        run(cfg, out=str(out), resume=True, progress=False, echo=None)
    out = tmp_path / "older.h5"
    run(cfg, out=str(out), progress=False, echo=None, max_chunks=1)
    with h5py.File(out, "a") as h:
        work = h["checkpoint/state/work"][()]
        del h["checkpoint/state/work"]
        h["checkpoint/state/work"] = work[..., :7]
    from jaxdamp.physics.model import N_CHANNELS

    with pytest.raises(ConfigError, match=rf"it has 7 work channels, this version {N_CHANNELS}"):
        run(cfg, out=str(out), resume=True, progress=False, echo=None)
    out = tmp_path / "before_cells.h5"  # its series lack a record: they would end short of t
    run(cfg, out=str(out), progress=False, echo=None, max_chunks=1)
    with h5py.File(out, "a") as h:
        del h["series/z_cm_cell"]
    with pytest.raises(ConfigError, match=r"older jaxdamp \(its series lack z_cm_cell\)"):
        run(cfg, out=str(out), resume=True, progress=False, echo=None)


def _tmpfs(path, size):
    os.makedirs(path, exist_ok=True)
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
                          capture_output=True, text=True)
    return done.returncode == 0


@pytest.mark.long
def test_a_real_full_tmpfs_gives_one_line_and_a_file_that_resumes(tmp_path):
    """The battery's F06/F07 on a real file system of 500 kB: exit 2 with one line (no
    segfault, no HDF5 tracebacks), the file keeps its whole chunks; on a larger disk --resume
    finishes with the energy balance of an uninterrupted run."""
    disk = tmp_path / "disk"
    if not _tmpfs(disk, "500k"):
        pytest.skip("mounting a tmpfs needs root (CI runs as root)")
    try:
        out = disk / "full.h5"
        argv = ["run", "--preset", "sanchez2012-optimal", "--quick", "--no-progress",
                "--set", "numerics.duration=1.5", "--out", str(out)]
        p = _child(argv)  # F07: refused before compute, the file's size estimated
        _, err = p.communicate(timeout=600)
        assert p.returncode == 2 and not out.exists(), err
        assert err.strip().count("\n") == 0 and "its disk has" in err, err
        p = _child(["--no-size-check", *argv])  # F06: the disk fills during the run
        _, err = p.communicate(timeout=600)
        assert p.returncode == 2, err
        assert err.strip().count("\n") == 0 and "Traceback" not in err, err
        assert "is full" in err and "--resume" in err
        with h5py.File(out, "r") as h:
            assert h.attrs["status"] == "stopped" and "checkpoint" in h
        subprocess.run(["mount", "-o", "remount,size=16m", str(disk)], check=True)
        p = _child(argv + ["--resume"])
        text, err = p.communicate(timeout=600)
        assert p.returncode == 0, err
        ref = tmp_path / "ref.h5"
        p = _child(argv[:-1] + [str(ref)])
        ref_text, err = p.communicate(timeout=600)
        assert p.returncode == 0, err
        line = [x for x in text.splitlines() if x.startswith("energy balance error")][0]
        ref_line = [x for x in ref_text.splitlines() if x.startswith("energy balance error")][0]
        assert line.split(";")[0] == ref_line.split(";")[0]
    finally:
        subprocess.run(["umount", str(disk)], capture_output=True)


# -- Ctrl-C ----------------------------------------------------------------------------------

#: A process that ignores SIGINT (a background job of a non-interactive shell: ``pytest ... &``)
#: cannot be sent a Ctrl-C, and jaxdamp then installs nothing, by design (:mod:`jaxdamp.interrupt`):
#: the in-process Ctrl-C tests are skipped there rather than failed.
needs_sigint = pytest.mark.skipif(
    signal.getsignal(signal.SIGINT) is signal.SIG_IGN,
    reason="SIGINT is ignored in this process (a background job): Ctrl-C cannot be tested")


@needs_sigint
def test_ctrl_c_is_a_request_acted_on_at_the_next_safe_point():
    interrupt.install()
    try:
        os.kill(os.getpid(), signal.SIGINT)  # lands anywhere: only noted
        time.sleep(0.05)
        assert interrupt.asked()
        with pytest.raises(KeyboardInterrupt):
            interrupt.check()
    finally:
        interrupt.uninstall()
    assert not interrupt.asked()


@needs_sigint
def test_outside_the_command_line_a_chunk_holds_ctrl_c_until_it_is_done():
    done = []
    with pytest.raises(KeyboardInterrupt):
        with interrupt.held():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
            done.append(True)  # the block finishes first
    assert done == [True]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.long
def test_ctrl_c_in_the_first_seconds_exits_130_naming_only_files_that_exist(tmp_path):
    """SIGINT during the imports, JAX's start, settling and the first chunks (the battery's
    F11): always exit 130 with no traceback and no crash; the message names the output only
    when it exists, and then with a checkpoint that continues it."""
    # Only the interpreter's own start, before `jaxdamp/__main__.py` installs the handler, is
    # Python's: the first delay is past it (measured here, under this machine's present load).
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import jaxdamp.interrupt"], check=True)
    start = time.perf_counter() - t0
    seen = []
    for delay in (max(0.15, 3 * start), 0.6, 1.5, 3.0, 6.0):
        out = tmp_path / f"i{delay}.h5"
        p = _child(["run", "--preset", "sanchez2012-optimal", "--quick", "--no-progress",
                    "--out", str(out)])
        time.sleep(delay)
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=300)
        assert p.returncode == 130, (delay, err)
        assert "Traceback" not in err and "Exception ignored" not in err, (delay, err)
        last = err.strip().splitlines()[-1]
        if out.exists():
            assert "--resume" in last and f"{out} keeps every finished chunk" in last, last
            with h5py.File(out, "r") as h:
                assert h.attrs["status"] == "interrupted" and "checkpoint" in h
        else:
            assert f"interrupted before {out} was written (nothing to resume)" in last, last
        seen.append(out.exists())
        assert not os.path.exists(claims.lock_path(out))
    assert not seen[0]  # the earliest is before the file exists


# -- sizes checked up front ------------------------------------------------------------------

@pytest.mark.parametrize("argv, what", [
    (["run", "--preset", "sanchez2012-optimal", "--quick", "--replicates", "100000"],
     "100000 systems × 250 grains"),
    (["frf", "--preset", "sanchez2012-impact", "--n", "100000"], "100000 systems"),
])
def test_a_batch_larger_than_memory_is_refused_before_compute(argv, what, capsys):
    t0 = time.perf_counter()
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert time.perf_counter() - t0 < 30
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert "this batch needs about" in err and what in err and "--no-size-check" in err, err


def test_the_estimate_follows_its_model_and_the_measured_peak():
    """Memory per system of the thesis bed over the quick run (4000 samples): the model gives
    3.1 MB; measured peak RSS of `run --quick --replicates 32` against `--replicates 1`:
    (645 - 556) MB / 31 = 2.9 MB."""
    from jaxdamp.engine import budget

    one = budget.estimate(systems=1, grains=250, steps=1, samples=4000, sample_bytes=232)
    many = budget.estimate(systems=32, grains=250, steps=1, samples=4000, sample_bytes=232)
    per = (many.memory - one.memory) / 31
    assert 2.5e6 < per < 3.5e6
    assert 0.5e9 < one.memory < 0.6e9  # measured 0.556 GB
    assert budget.size(2.02e12) == "2.02 TB" and budget.duration(7200) == "2 h"


def test_a_file_larger_than_its_disk_is_refused(tmp_path, monkeypatch):
    from jaxdamp.engine import budget

    b = budget.estimate(systems=10, grains=250, steps=1, samples=4000, sample_bytes=232,
                        out=True)
    real = shutil.disk_usage
    monkeypatch.setattr(shutil, "disk_usage",
                        lambda p: type(real(p))(10**9, 10**9 - 10**6, 10**6))
    with pytest.raises(ConfigError, match=r"the output needs about 1[0-9.]* MB and its disk has "
                                          r"1 MB free"):
        budget.check(b, out=tmp_path / "x.h5")
    budget.ENFORCE = False
    try:
        budget.check(b, out=tmp_path / "x.h5")
    finally:
        budget.ENFORCE = True


# -- physical sanity of a run's schedule ----------------------------------------------------

@pytest.mark.parametrize("extra, expect", [
    (["--set", "primary.K=0"], "primary.K = 0: must be > 0"),
    (["--set", "numerics.record_dt=10"],
     "numerics.record_dt = 10 s: the sample interval must not exceed numerics.chunk"),
    (["--frequency", "1e-6"], "is shorter than one drive period (1/f = 1e+06 s"),
    (["--set", "numerics.record_dt=0.01"], "record_dt ≤ 1/(20 f)"),
])
def test_inputs_that_would_print_meaningless_numbers_are_refused(extra, expect, capsys):
    assert main(["run", "--preset", "sanchez2012-optimal", "--quick", *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and expect in err, err


def test_a_duration_of_part_of_a_chunk_runs_as_asked_and_a_rounded_one_says_so():
    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.studies.runner import schedule, schedule_note

    base = presets.get("sanchez2012-optimal")
    dt = 2.342e-6
    short = apply_overrides(base, ["numerics.duration=0.07", "numerics.chunk=0.1"])
    s = schedule(short, dt)
    assert s.n_chunks == 1 and s.duration == pytest.approx(0.07, rel=0.01)
    assert schedule_note(short, s) is None
    odd = apply_overrides(base, ["numerics.duration=0.15", "numerics.chunk=0.1"])
    s = schedule(odd, dt)
    assert s.n_chunks == 2
    assert "numerics.duration = 0.15 s is run as 2 whole chunk(s)" in schedule_note(odd, s)


# -- damaged and foreign files ------------------------------------------------------------

def test_resume_names_a_foreign_truncated_or_missing_file_before_jax(tmp_path, capsys):
    from jaxdamp.studies.runner import run

    notes = tmp_path / "notes.txt"
    notes.write_text("hello\n")
    good = tmp_path / "good.h5"
    run(_small_config(), out=str(good), progress=False, echo=None, max_chunks=1)
    cut = tmp_path / "cut.h5"
    cut.write_bytes(good.read_bytes()[:4000])
    cases = [(notes, "notes.txt: not an HDF5 file"), (cut, "cut.h5: not an HDF5 file"),
             (tmp_path / "none.h5", "no file at"),
             (good, "`jaxdamp run --replicates --resume` continues a sweep file")]
    for path, expect in cases:
        argv = ["run", "--preset", "sanchez2012-optimal", "--quick", "--resume", "--out", str(path)]
        if path == good:
            argv += ["--replicates", "2"]
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and err.startswith("jaxdamp: error: --resume: "), err
        assert expect in err, err


def test_info_plot_and_export_see_a_file_whose_bytes_were_overwritten(tmp_path, capsys):
    """The battery's F16: random bytes in the middle of a run file. HDF5 keeps no checksums
    here, so the samples are checked for sense: `info` warns, `plot` and `export` refuse."""
    from jaxdamp.studies.runner import run

    path = tmp_path / "r.h5"
    run(_small_config(), out=str(path), progress=False, echo=None)
    with h5py.File(path, "a") as h:
        h["series/z_box"][5:9] = np.frombuffer(b"\xff\xfe" * 16, dtype=np.float64)  # NaNs
    assert main(["info", str(path)]) == 0
    assert "WARNING: this file is damaged: non-finite or impossible values in z_box" in \
        capsys.readouterr().out
    for argv in (["plot", str(path), "--kind", "energy", "--out", str(tmp_path / "e.png")],
                 ["export", str(path), "--format", "xyz", "--out", str(tmp_path / "e.xyz")]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "is damaged" in err and "nothing drawn or exported" in err, err


def test_a_cold_native_kernel_is_announced_before_it_compiles(monkeypatch):
    """The first use after an install compiles the kernel (about three minutes on 2 cores, with the
    first bar still at 0 %): said before, not after."""
    from jaxdamp.engine import native

    if not native.AVAILABLE:
        pytest.skip("numba is not installed")
    assert native.compile_note("jax") is None
    monkeypatch.setattr(native.os.path, "exists", lambda path: False)
    assert "compiling the native kernel once" in native.compile_note("native")
    monkeypatch.setattr(native.os.path, "exists", lambda path: True)
    assert native.compile_note("native") is None
    # the spring form is its own specialisation: announced until a cached entry has it
    monkeypatch.setattr(native._advance._cache._cache_file, "_load_index", lambda: {})
    assert "tangential-spring form" in native.compile_note("native", springs=True)


def test_the_fused_kernel_is_announced_before_its_first_launch():
    """numba-cuda compiles the fused kernel at its first launch in a process: the driver's one
    note says so until a kernel of this process exists, and says nothing for the JAX engine."""
    from jaxdamp.engine import driver, fused

    assert driver.compile_note("jax") is None
    fused._kernel.cache_clear()
    assert "compiling the fused CUDA kernel" in driver.compile_note("fused")
    fused._kernel(0, 0, 0)  # what the first launch creates
    assert driver.compile_note("fused") is None


def test_large_beds_are_estimated_linearly_in_their_grains():
    """The JAX engine's neighbour rebuild is a cell list from neighbors.CELLS_FROM grains on:
    a million grains need a few GB there, not the 8 TB of an all-pairs block; a single large
    bed in the native kernel runs at the large-bed factor (its blocks over the cores)."""
    from jaxdamp.engine import budget, native, neighbors

    big = budget.estimate(systems=1, grains=10**6, steps=1, samples=100, sample_bytes=232,
                          engine="jax")
    assert big.memory < 10e9
    small = budget.estimate(systems=1, grains=neighbors.CELLS_FROM - 1, steps=1, samples=100,
                            sample_bytes=232, engine="jax")
    assert small.memory - budget.BASE_MEMORY > (neighbors.CELLS_FROM - 1) ** 2 * budget.PAIR_BYTES
    n = native.LARGE
    rate = [budget.estimate(systems=1, grains=g, steps=1000, samples=1, sample_bytes=8).seconds
            / g for g in (n - 1, n)]
    if (os.cpu_count() or 1) > 1:
        assert rate[1] == pytest.approx(rate[0] * budget.LARGE_BED_FACTOR)


@pytest.mark.parametrize("engine", ["jax", "native"])
def test_the_spring_with_history_is_estimated_at_its_measured_cost(engine):
    """A run with ``tangential_law = "mindlin"`` is announced at the spring's measured cost
    over the viscous law's on its engine (budget.TANGENTIAL_FACTOR), not at the viscous
    rate."""
    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.engine import budget
    from jaxdamp.studies.runner import batch_budget, schedule

    base = apply_overrides(presets.get("sanchez2012-optimal"), [f"numerics.engine='{engine}'"])
    spring = apply_overrides(base, ["tangential_law='mindlin'"])
    sched = schedule(base, 1e-6)
    viscous, mindlin = (batch_budget(c, sched, 4).seconds for c in (base, spring))
    factor = budget.TANGENTIAL_FACTOR[engine]["mindlin"]
    assert factor > 2
    assert mindlin == pytest.approx(viscous * factor)
