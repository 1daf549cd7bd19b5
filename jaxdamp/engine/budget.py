"""What a batch will cost before it runs: memory, output file and wall time — one estimator.

Every command that simulates grains (``run``, ``run --replicates``, ``frf``, ``decay``,
``random``, ``efficiency``, the optimisers' sweeps) reaches :func:`jaxdamp.studies.runner.run`
or :func:`jaxdamp.studies.sweep.sweep`, and both call :func:`check` before settling: a batch
whose memory exceeds what this process may use, or whose file exceeds the free space of its
disk, is refused in one line naming the size, the limit and the remedy, instead of running for
minutes and then crashing (or filling the disk). Above :data:`ANNOUNCE_SECONDS` the estimate is
printed first, so a long job says so from its first second.

The model (bytes, per system of ``N`` grains, ``S`` samples, ``steps`` steps)::

    memory = BASE_MEMORY + systems × (RECORD_COPIES × S × sample_bytes + N × GRAIN_BYTES
                                      + [JAX engine] N² × PAIR_BYTES, or N × CELL_BYTES
                                        from neighbors.CELLS_FROM grains on)
    file   = FILE_OVERHEAD × (S × sample_bytes + snapshots × N × 56 + 2 × N × CHECKPOINT_BYTES)
    time   = systems × N × steps × SECONDS_PER_GRAIN_STEP[engine]
             (native, fewer systems than cores of native.LARGE grains or more: × LARGE_BED_FACTOR)

Constants measured on the 2-core reference machine (see each one); the time is a rough guide
(within a factor of a few), the memory and file estimates err on the large side. The S3
single-particle sweeps (:mod:`jaxdamp.s3`) have no grains: their records alone count.

Example::

    from jaxdamp.engine import budget
    b = budget.estimate(systems=32, grains=250, steps=470_000, samples=4000,
                        sample_bytes=208, engine="native")
    print(b.line())          # "32 systems × 250 grains × 4.7e+05 steps: about ..."
    budget.check(b, out="frf.h5")
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from jaxdamp.config import ConfigError

#: Resident memory of a command before its batch [B]: Python, JAX, numba, h5py, the compiled
#: chunk. Measured: `jaxdamp run --quick` (one system, 250 grains, 4000 samples) peaks at
#: 0.56 GB.
BASE_MEMORY = 0.55e9
#: Copies of a system's samples held at once: the chunks kept in memory, the whole series read
#: back (or concatenated) for the summary, and its per-period series.
RECORD_COPIES = 3
#: State, checkpoint copy and neighbour list per grain [B] (a checkpoint holds 237 B per grain
#: of the thesis bed; the live batch, its host copies, settling and the cell lists about 8×
#: that: 1e6 grains of radius 0.1 mm peaked at 2.5 GB).
GRAIN_BYTES = 2000
#: A checkpoint per grain in the file [B] (measured 237 on the thesis bed).
CHECKPOINT_BYTES = 240
#: The JAX engine's all-pairs block per pair and system [B] (about 25 fused kernels over it;
#: 0.25–0.5 MB per system of 250 grains measured on the H200).
PAIR_BYTES = 8
#: The JAX engine's in-loop cell-list rebuild per grain [B], from
#: :data:`jaxdamp.engine.neighbors.CELLS_FROM` grains on (XLA's compiled memory analysis of
#: one rebuild: 55.8 MB scratch at 16 000 grains, 174 MB at 50 000, about 3.5 kB per grain).
CELL_BYTES = 4000
#: Wall seconds per grain-step on one of the reference machine's 2 cores: native kernel 5.9 µs
#: per step for 250 grains (24 ns per grain-step); JAX engine on the CPU 130–170 µs per
#: system-step at batch 32 (0.6 µs per grain-step); benchmarks/RESULTS.md.
SECONDS_PER_GRAIN_STEP = {"native": 24e-9, "jax": 600e-9}
#: A large bed in the native kernel (:data:`jaxdamp.engine.native.LARGE` grains or more, fewer
#: systems than cores: its blocks over the cores) costs this many times the small bed's
#: grain-step on the reference machine's 2 cores, a whole command-line run's steps counted
#: (pouring, settling and start-up included): the 50 000-grain thesis-like damper of
#: benchmarks/RESULTS.md ("Large beds: unsigned indices") ran 3.85e4 steps in 56 s, 29 ns per
#: grain-step (the kernel alone 21–25 ns) against :data:`SECONDS_PER_GRAIN_STEP`'s 24.
LARGE_BED_FACTOR = 1.2
#: The tangential spring with history (``tangential_law = "mindlin"``) costs this many times
#: the viscous law's grain-step, per engine (the moving thesis bed, float64, 2 cores;
#: benchmarks/RESULTS.md): the JAX engine 8.5× (1332.8 against 157.7 µs per system-step at
#: batch 32, ``python benchmarks/bench_jax_engine.py --precision float64 --tangential both
#: --batch 32 --steps 400 --rounds 3``), the native kernel 2.5× (14.8 against 6.0 µs at batch
#: 8, 2.4× for one system, ``python benchmarks/bench_spring.py --rounds 3 --steps 5000``; one
#: system of 16 000 and 50 000 grains on the large-bed path 2.9× and 2.5×, ``--n N``).
TANGENTIAL_FACTOR = {"jax": {"viscous": 1.0, "mindlin": 8.5},
                     "native": {"viscous": 1.0, "mindlin": 2.5}}
#: HDF5 chunking and metadata over the raw bytes of a run file (measured 1.2).
FILE_OVERHEAD = 1.3
#: Refuse a batch above this fraction of the memory this process may use.
MEMORY_FRACTION = 0.9
#: Print the estimate before computing when the job should take longer than this [s].
ANNOUNCE_SECONDS = 60.0

#: Whether :func:`check` refuses (the command line's ``--no-size-check`` turns it off).
ENFORCE = True


@dataclass(frozen=True)
class Budget:
    """The estimated cost of a batch: ``memory`` [B] at its peak, ``file`` [B] of its output
    (0 without one), ``seconds`` of wall time on this machine, and what it was computed from."""

    systems: int
    grains: int
    steps: int
    samples: int
    memory: float
    file: float
    seconds: float

    def line(self) -> str:
        """One line: the batch, and about how long, how much memory, how large a file."""
        what = (f"{self.systems} system{'s' if self.systems != 1 else ''}"
                + (f" × {self.grains} grains" if self.grains else "")
                + f" × {self.steps:.3g} steps")
        return (f"{what}: about {duration(self.seconds)} on this machine, "
                f"{size(self.memory)} of memory"
                + (f", a {size(self.file)} file" if self.file else ""))


def estimate(*, systems: int, grains: int, steps: int, samples: int, sample_bytes: int,
             engine: str = "native", snapshots: int = 0, out: bool = False,
             seconds_per_step: float | None = None,
             record_copies: int = RECORD_COPIES, tangential: str = "viscous") -> Budget:
    """The :class:`Budget` of ``systems`` systems of ``grains`` grains advanced ``steps`` steps
    (settling included) and sampled ``samples`` times of ``sample_bytes`` each (see the module
    docstring for the model). ``seconds_per_step``: the wall time of one step of one system
    where the grain-step rate does not apply (the S3 model); ``record_copies``: copies of the
    samples held at once where :data:`RECORD_COPIES` does not apply; ``tangential``: the
    tangential law (:data:`TANGENTIAL_FACTOR` of ``engine``)."""
    per_system = (record_copies * samples * sample_bytes + grains * GRAIN_BYTES
                  + (_jax_lists(grains) if engine == "jax" else 0))
    memory = BASE_MEMORY + systems * per_system
    file = (FILE_OVERHEAD * systems * (samples * sample_bytes + snapshots * grains * 56
                                      + 2 * grains * CHECKPOINT_BYTES) if out else 0.0)
    rate = SECONDS_PER_GRAIN_STEP.get(engine, SECONDS_PER_GRAIN_STEP["native"]) * max(grains, 1)
    if engine == "native" and _large(grains) and systems < (os.cpu_count() or 1):
        rate *= LARGE_BED_FACTOR
    rate *= TANGENTIAL_FACTOR.get(engine, TANGENTIAL_FACTOR["jax"])[tangential]
    seconds = systems * steps * (rate if seconds_per_step is None else seconds_per_step)
    return Budget(int(systems), int(grains), int(steps), int(samples), float(memory),
                  float(file), float(seconds))


def _jax_lists(grains: int) -> float:
    """The JAX engine's neighbour rebuild per system [B]: all pairs, or a cell list for a bed
    of :data:`jaxdamp.engine.neighbors.CELLS_FROM` grains or more."""
    from jaxdamp.engine.neighbors import CELLS_FROM

    return grains * CELL_BYTES if grains >= CELLS_FROM else grains * grains * PAIR_BYTES


def _large(grains: int) -> bool:
    """Whether the native kernel runs a bed of ``grains`` on its large-bed path."""
    from jaxdamp.engine.native import LARGE

    return grains >= LARGE


def available_memory() -> float:
    """Bytes this process may still use: the smaller of the machine's available memory
    (``MemAvailable``) and the process limits (``ulimit -v``, ``-d``) less what it already
    holds; ``inf`` where neither is known."""
    limits = [math.inf]
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    limits.append(float(line.split()[1]) * 1024.0)
    except OSError:
        pass
    try:
        import resource

        for which in (resource.RLIMIT_AS, resource.RLIMIT_DATA):
            soft = resource.getrlimit(which)[0]
            if soft != resource.RLIM_INFINITY:
                used = _virtual_size() if which == resource.RLIMIT_AS else 0.0
                limits.append(max(float(soft) - used, 0.0) + (BASE_MEMORY if used else 0.0))
    except (ImportError, OSError, ValueError):
        pass
    return min(limits)


def _virtual_size() -> float:
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmSize:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    return 0.0


def check(budget: Budget, out=None, say=None) -> None:
    """Refuse ``budget`` (:class:`~jaxdamp.config.ConfigError`, one line) when its memory
    exceeds :data:`MEMORY_FRACTION` of :func:`available_memory` or its file the free space of
    the disk holding ``out``; with ``say``, announce it when it should take longer than
    :data:`ANNOUNCE_SECONDS`. Nothing is refused while :data:`ENFORCE` is off."""
    if say is not None and budget.seconds > ANNOUNCE_SECONDS:
        say(f"estimated: {budget.line()}")
    if not ENFORCE:
        return
    room = available_memory()
    if budget.memory > MEMORY_FRACTION * room:
        raise ConfigError(
            f"this batch needs about {size(budget.memory)} of memory ({budget.line()}), more "
            f"than the {size(room)} this process may use: run fewer systems or replicates at "
            "once (a sweep written to a file runs in waves that fit by itself), a shorter numerics.duration or a longer numerics.record_dt (fewer samples), "
            "or fewer grains (`jaxdamp --no-size-check ...` runs it anyway)")
    if out is not None and budget.file:
        import shutil

        folder = os.path.dirname(os.path.abspath(os.fspath(out)))
        free = shutil.disk_usage(folder).free
        if budget.file > free:
            raise ConfigError(
                f"{out}: the output needs about {size(budget.file)} and its disk has "
                f"{size(free)} free: free some space or write elsewhere "
                "(`jaxdamp --no-size-check ...` runs it anyway)")


def largest(make, systems: int) -> int:
    """The most systems, at most ``systems``, whose batch fits the memory :func:`check` allows:
    ``make(n)`` is the :class:`Budget` of ``n`` systems (memory affine in ``n``); at least 1.
    Without :data:`ENFORCE`, every system."""
    if not ENFORCE:
        return int(systems)
    room = MEMORY_FRACTION * min(available_memory(), device_memory())
    one, two = make(1).memory, make(2).memory
    per = max(two - one, 1.0)
    return int(max(1, min(systems, (room - (one - per)) // per)))


def device_memory() -> float:
    """Bytes free on the first accelerator JAX sees (``inf`` on a CPU, or where the device
    does not say). A batch on a device holds its state and working arrays there; the samples
    come back to the host every chunk."""
    import jax

    dev = jax.devices()[0]
    if dev.platform == "cpu":
        return math.inf
    try:
        stats = dev.memory_stats() or {}
    except Exception:  # noqa: BLE001 - a backend without statistics
        return math.inf
    limit = stats.get("bytes_limit")
    return math.inf if limit is None else float(limit - stats.get("bytes_in_use", 0))


def size(n: float) -> str:
    """Bytes as ``'1.2 GB'`` (decimal units)."""
    for unit in ("B", "kB", "MB", "GB", "TB"):
        if abs(n) < 1000 or unit == "PB":
            return f"{n:.3g} {unit}"
        n /= 1000.0
    return f"{n:.3g} PB"


def duration(seconds: float) -> str:
    """Seconds as ``'40 s'``, ``'12 min'``, ``'3.1 h'`` or ``'2.5 days'``."""
    if seconds < 90:
        return f"{seconds:.2g} s"
    if seconds < 5400:
        return f"{seconds / 60:.2g} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.2g} h"
    return f"{seconds / 86400:.3g} days"
