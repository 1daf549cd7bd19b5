"""Which engine advances a batch: the one rule behind ``numerics.engine = "auto"``.

Three engines compute the same step (:mod:`jaxdamp.physics.integrate`): the XLA step of
:mod:`jaxdamp.engine.simulate` (``"jax"``, differentiable, any device, float64 or float32),
the compiled CPU kernel of :mod:`jaxdamp.engine.native` (``"native"``, forward only, float64,
the host's cores) and the same kernel's step fused into one CUDA launch per chunk
(:mod:`jaxdamp.engine.fused`, ``"fused"``, forward only, float64, an NVIDIA GPU). Which one
is faster depends on where JAX runs and on the batch:

* JAX on the CPU: the native kernel, always (XLA's CPU step is 20–40× slower,
  ``benchmarks/RESULTS.md``);
* float32 (``numerics.precision``): the XLA step, the only float32 engine;
* JAX on an accelerator: the native kernel below the batch at which the device's step was
  *measured* to beat it (:data:`MEASURED`), the device's step from there on: the fused step
  where it was measured on the device (``fused_from``; it agreed with the CPU there, by
  ``benchmarks/device_check.py``) and numba-cuda finds a GPU, else the XLA step. A device with no
  measurement of its own uses the nearest one recorded (said so by ``jaxdamp info
  --devices``); ``benchmarks/device_check.py`` measures a device and prints its entry.

An explicit ``numerics.engine`` always wins. :func:`choose` returns the engine with the reason,
printed with every run and stored in its file (``engine``, ``engine_reason``), so that
``--resume`` continues on the engine the file was written with.

Example::

    >>> from jaxdamp.engine.choice import choose
    >>> choose("auto", "float64", batch=1, backend="cpu").engine
    'native'
    >>> choose("auto", "float64", batch=4096, backend="gpu", device_kind="NVIDIA H200").engine
    'native'
    >>> choose("auto", "float32", batch=4096, backend="gpu", device_kind="NVIDIA H200").engine
    'jax'
"""

from __future__ import annotations

from typing import NamedTuple

from jaxdamp.validation import ENGINES, engine_precision_error


class Crossover(NamedTuple):
    """One measurement of a device's steps against the native kernel on its own host's
    cores: µs per system-step by batch (``xla``, ``native``, ``fused``), the host's cores,
    the batch from which the device's XLA step is faster in float64 (``float64_from``) and
    from which its fused step is (``fused_from``; ``None``: at no measured batch, or not
    measured)."""

    device_kind: str
    host_cores: int
    xla: dict
    native: dict
    float64_from: int | None
    source: str
    fused: dict = {}
    fused_from: int | None = None


#: The recorded measurements, by ``jax.Device.device_kind``. Add one with
#: ``python benchmarks/device_check.py`` on the device (it prints the entry).
MEASURED: dict[str, Crossover] = {
    "NVIDIA H200": Crossover(
        device_kind="NVIDIA H200", host_cores=16,
        xla={32: 3.29, 256: 1.31, 1024: 1.18, 4096: 1.06, 16384: 0.82},
        native={1: 9.2, 32: 1.05, 256: 0.75, 1024: 0.71},
        float64_from=None,
        source="issue 32: sanchez2012-optimal bed driven 0.2 s, chunk_fn, 1000 steps per chunk, "
               "jax 0.11.2, float64; the native kernel on the machine's 16 host cores "
               "(best of its measured range)"),
}


class Choice(NamedTuple):
    """The engine a batch runs on and why (one line, printed and stored)."""

    engine: str
    reason: str


def nearest(device_kind: str) -> tuple[Crossover | None, bool]:
    """The measurement for ``device_kind`` and whether it is the device's own (else the
    recorded one whose name shares the most leading words, or ``None`` if none is
    recorded)."""
    if device_kind in MEASURED:
        return MEASURED[device_kind], True
    if not MEASURED:
        return None, False

    def shared(name: str) -> int:
        a, b = name.lower().split(), device_kind.lower().split()
        k = 0
        while k < min(len(a), len(b)) and a[k] == b[k]:
            k += 1
        return k

    return MEASURED[max(MEASURED, key=shared)], False


def choose(engine: str, precision: str = "float64", batch: int = 1, backend: str | None = None,
           device_kind: str | None = None, have_native: bool | None = None,
           have_fused: bool | None = None, *, tangential: str = "viscous") -> Choice:
    """The engine for a batch of ``batch`` systems: ``engine`` itself unless ``"auto"``
    (checked against ``precision``), else the rule of this module. ``backend`` and
    ``device_kind``: JAX's default backend and its first device's kind (looked up when
    ``None``); ``have_native``: whether numba is installed, ``have_fused``: whether the fused
    step can run here (numba-cuda and a GPU; both looked up when ``None``); ``tangential``:
    the tangential law (``Config.tangential_law``; every engine runs the spring with history,
    but the fused step's speed was measured under the viscous law only: ``auto`` does not
    pick it for the spring)."""
    if engine not in ENGINES:
        raise ValueError(f"engine = {engine!r}: expected one of {ENGINES}")
    if (why := engine_precision_error(engine, precision)) is not None:
        raise ValueError(why)
    if engine != "auto":
        return Choice(engine, f"numerics.engine = {engine!r}")
    if precision != "float64":
        return Choice("jax", f"auto: {precision} runs on the JAX engine only")
    springs = tangential != "viscous"
    if have_native is None:
        from jaxdamp.engine import native

        have_native = native.AVAILABLE
    if not have_native:
        return Choice("jax", "auto: numba is not installed (no native kernel)")
    if backend is None or device_kind is None:
        import jax

        backend = jax.default_backend() if backend is None else backend
        device_kind = jax.devices()[0].device_kind if device_kind is None else device_kind
    if backend == "cpu":
        return Choice("native", "auto: JAX runs on the CPU")
    rec, own = nearest(device_kind)
    if rec is None:
        return Choice("native", "auto: no measurement of an accelerator recorded; the native "
                                "kernel on the host's cores")
    basis = ("measured on this device" if own
             else f"measured on {rec.device_kind}, not on this {device_kind}")
    if rec.fused_from is not None and batch >= rec.fused_from and not springs:
        if have_fused is None:
            have_fused = backend == "gpu" and _fused_usable()
        if have_fused:
            return Choice("fused", f"auto: batch {batch} ≥ {rec.fused_from}, where the fused "
                                   f"device step beats the native kernel ({basis})")
    if rec.float64_from is None:
        return Choice("native", f"auto: the native kernel beat the device's float64 step at "
                                f"every batch up to {max(rec.xla)} ({basis})")
    if batch >= rec.float64_from:
        return Choice("jax", f"auto: batch {batch} ≥ {rec.float64_from}, where the device's "
                             f"float64 step beats the native kernel ({basis})")
    return Choice("native", f"auto: batch {batch} < {rec.float64_from}, below which the native "
                            f"kernel beats the device ({basis})")


def _fused_usable() -> bool:
    from jaxdamp.engine import fused

    return fused.available()[0] and not fused.simulated()


def resolve_engine(engine: str, precision: str = "float64", batch: int = 1, *,
                   tangential: str = "viscous") -> str:
    """The engine name of :func:`choose` (``"jax"``, ``"native"`` or ``"fused"``)."""
    return choose(engine, precision, batch, tangential=tangential).engine


def stored_choice(attrs, current: Choice) -> Choice:
    """The engine a file was written with (its ``engine`` attribute), which ``--resume``
    keeps so that the continuation is bit-identical; ``current`` for a file from before
    the engine was stored."""
    if "engine" not in attrs:
        return current
    engine = str(attrs["engine"])
    return Choice(engine, f"as stored in the file: {attrs.get('engine_reason', engine)}")


def describe_devices(batches=(1, 32, 1024, 16384)) -> list[str]:
    """``jaxdamp info --devices``: JAX's devices, the host, and the engine ``auto`` picks for
    each batch in ``batches`` in float64 and float32, with the precision advice."""
    import os

    import jax

    from jaxdamp.engine import native

    backend = jax.default_backend()
    devs = jax.devices()
    lines = [f"jax {jax.__version__}, default backend {backend}: {len(devs)} device(s)"]
    for d in devs:
        mem = ""
        try:
            stats = d.memory_stats() or {}
            if "bytes_limit" in stats:
                mem = f", {stats['bytes_limit'] / 2**30:.1f} GiB"
        except Exception:  # noqa: BLE001 - not every backend reports memory
            pass
        lines.append(f"  {d.platform}:{d.id} {d.device_kind}{mem}")
    from jaxdamp.engine import fused

    usable, why = fused.available()
    lines.append(f"host: {os.cpu_count()} cores; native kernel (numba): "
                 + ("available" if native.AVAILABLE else "not installed")
                 + "; fused device step (numba-cuda): "
                 + ("available" if usable and not fused.simulated() else
                    "CUDA simulator only (NUMBA_ENABLE_CUDASIM)" if usable else why))
    if backend != "cpu":
        rec, own = nearest(devs[0].device_kind)
        lines.append("measured crossover: " + (
            "none recorded" if rec is None else
            f"{rec.device_kind} with {rec.host_cores} host cores"
            + ("" if own else " (not this device: run benchmarks/device_check.py here)")))
    lines.append("numerics.engine = 'auto' picks, by batch (systems advanced together):")
    for precision in ("float64", "float32"):
        for b in batches:
            c = choose("auto", precision, b, backend, devs[0].device_kind)
            lines.append(f"  {precision}, batch {b:>6}: {c.engine:6}  {c.reason}")
    lines.append(
        "precision: float64 is the default and the reference (every engine, every test); "
        "float32 (numerics.precision) runs the JAX engine only; its contact laws in float32 "
        + ("agreed with float64 to 5e-10 m over 1000 steps on an H200 and ran about twice as "
           "fast there (issue 32); on a CPU it is not faster" if backend != "cpu" else
           "make the JAX engine 10-15 % faster on a CPU, where the native kernel (float64) is "
           "20-40x faster than either (benchmarks/RESULTS.md): keep float64 here"))
    return lines
