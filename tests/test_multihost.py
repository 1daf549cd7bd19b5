"""A sweep across two processes (``jax.distributed``, local coordinator on the loopback address),
each with its own host devices: the native engine runs on every process's shards, process 0
writes the file, and the result equals the single-process sweep."""

import json
import os
import socket
import subprocess
import sys

import h5py
import numpy as np
import pytest

PROCESS = """
import json, sys
import jax
jax.distributed.initialize(coordinator_address={address!r}, num_processes=2, process_id={pid})
assert len(jax.devices()) == 4 and len(jax.local_devices()) == 2, jax.devices()
sys.path.insert(0, {tests!r})
from test_sweep import _small_grid
from jaxdamp.config import apply_overrides
from jaxdamp.studies.sweep import sweep
cfg, axes = _small_grid()
cfg = apply_overrides(cfg, ["numerics.engine='native'"])
if {partial}:  # killed after 2 of 4 chunks, then resumed by both processes
    assert sweep(cfg, axes, progress=False, echo=None, out={out!r}, max_chunks=2) is None
    res = sweep(cfg, axes, progress=False, echo=None, out={out!r}, resume=True)
else:
    res = sweep(cfg, axes, progress=False, echo=None, out={out!r})
print("RESULT", json.dumps({{"amplitude": res.summary["amplitude"].tolist(),
                             "work": res.records["work"][:, -1].tolist()}}))
"""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _two_processes(out: str, partial: bool) -> list[dict]:
    address = f"127.0.0.1:{_free_port()}"
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=2")
    procs = [subprocess.Popen(
        [sys.executable, "-c", PROCESS.format(address=address, pid=pid, out=out, partial=partial,
                                              tests=os.path.dirname(__file__))],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for pid in (0, 1)]
    results = []
    for p in procs:
        stdout, stderr = p.communicate(timeout=600)
        assert p.returncode == 0, stderr[-3000:]
        results.append(json.loads(stdout.split("RESULT", 1)[1]))
    return results


@pytest.mark.long  # 35–40 s each on 2 cores: CI's second step
@pytest.mark.parametrize("partial", [False, True], ids=["whole", "killed-and-resumed"])
def test_sweep_across_two_processes_equals_one_process(tmp_path, partial):
    from test_sweep import _small_grid

    from jaxdamp.config import apply_overrides
    from jaxdamp.studies.sweep import sweep

    out = str(tmp_path / "two.h5")
    results = _two_processes(out, partial)
    cfg, axes = _small_grid()
    one = sweep(apply_overrides(cfg, ["numerics.engine='native'"]), axes, progress=False,
                echo=None)
    for r in results:  # both processes return the whole sweep
        np.testing.assert_array_equal(np.asarray(r["amplitude"]), one.summary["amplitude"])
        np.testing.assert_array_equal(np.asarray(r["work"]), one.records["work"][:, -1])
    with h5py.File(out) as h:  # written by process 0 alone, complete
        assert h.attrs["status"] == "finished" and h.attrs["engine"] == "native"
        assert int(h.attrs["devices"]) == 4
        np.testing.assert_array_equal(h["records/work"][()], one.records["work"])
    assert sorted(os.listdir(tmp_path)) == ["two.h5"]  # no second file, no partial copies
