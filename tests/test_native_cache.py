"""The native kernel gives the same bits however numba's cache found it.

numba links a callee compiled in the process as LLVM IR (LLVM may inline it and optimise it
again in the caller) and one loaded from its on-disk cache as object code (called as it is).
Which of the two a caller gets depends on what the cache held when the caller compiled — with
several processes (pytest's workers, a sweep's hosts) on one cache, on which process got there
first. Code compiled with reassociation may then round otherwise in one caller than in another:
the large-bed path once gave a system alone (its sweep over the cores) other quaternion bits
than the same system in a batch (the serial sweep) in 3 of 7 cold test runs. Slow: two cold
compiles (about 7 minutes on 2 cores)."""

import os
import subprocess
import sys

import pytest

from jaxdamp.engine import native

pytestmark = [pytest.mark.skipif(not native.AVAILABLE, reason="numba not installed"),
              pytest.mark.slow]

HERE = os.path.dirname(os.path.abspath(__file__))

#: One step's chunk of the two-species bed on the large-bed path (blocks of 6 grains, chunks of
#: 2 blocks), alone and twice in a batch; prints a digest of each state field of each system.
RUN = r"""
import hashlib, sys
import numpy as np
sys.path.insert(0, {here!r})
from test_native_large import FIELDS, _chunk
from helpers import mixture, mixture_bed
cfg = mixture("driven", "harmonic")
r, v, w = mixture_bed(50)
for batch in (1, 2):
    s, _ = _chunk(cfg, r, v, w, 2, block=6, chunk=2, batch=batch)
    for f in FIELDS:
        for b in range(batch):
            x = np.ascontiguousarray(s[f][b])
            print(f, hashlib.sha1(x.tobytes()).hexdigest())
"""

#: The kernel's functions that call the per-block ones (``_correct``, ``_done_blocks``, ...):
#: their cache files are removed so that they compile against callees loaded from the cache.
CALLERS = ("_sweep_each", "_sweep_all", "_advance")  # _advance, _advance_one, _advance_serial


def _digests(cache: str) -> list[str]:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    p = subprocess.run([sys.executable, "-c", RUN.format(here=HERE)], capture_output=True,
                       text=True, env=env, timeout=1200)
    assert p.returncode == 0, p.stderr[-3000:]
    return p.stdout.split("\n")


def test_same_bits_whether_callees_were_compiled_or_loaded(tmp_path):
    """A fresh cache (every function compiled in the process, callees inlinable), then the
    same cache without its callers' entries (callers compiled against callees loaded as object
    code): every state field of every system has the same bits in both, alone and in a
    batch."""
    cache = str(tmp_path / "numba")
    fresh = _digests(cache)
    gone = []
    for root, _, files in os.walk(cache):
        for name in files:
            if any(f".{c}" in name for c in CALLERS):
                os.remove(os.path.join(root, name))
                gone.append(name)
    assert gone, "no cache files of the callers found: numba's cache layout changed"
    relinked = _digests(cache)
    assert relinked == fresh
    lines = [x.split() for x in fresh if x]
    by_field = {}
    for f, d in lines:
        by_field.setdefault(f, []).append(d)
    for f, ds in by_field.items():  # alone = each system of the batch
        assert len(set(ds)) == 1, f


def _cli(cache: str, *overrides: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    args = [sys.executable, "-m", "jaxdamp", "run", "--preset", "sanchez2012-optimal",
            "--set", "grains.0.count=20", "--set", "numerics.engine='native'", "--duration",
            "0.1", "--no-progress"]
    for o in overrides:
        args += ["--set", o]
    return subprocess.run(args, capture_output=True, text=True, env=env, timeout=1800)


def test_the_spring_form_compiles_against_a_cached_viscous_kernel(tmp_path):
    """The spring form of the kernel (``tangential_law = "mindlin"``) is a second
    specialisation; compiled in a process that found the viscous one's parallel callees in the
    cache, it links their thread scheduler, which numba registers only once its threads are
    launched: the first spring run after a viscous one aborted with "LLVM ERROR: Symbol not
    found: allocate_sched" until the kernel launched them before every call. Two processes on
    one cache: a viscous run, then a spring run; both finish. Slow: two cold compiles."""
    cache = str(tmp_path / "numba")
    first = _cli(cache)
    assert first.returncode == 0, first.stderr[-3000:]
    second = _cli(cache, "tangential_law='mindlin'")
    assert second.returncode == 0, (second.stdout + second.stderr)[-3000:]
    assert "tangential-spring form" in second.stdout + second.stderr
