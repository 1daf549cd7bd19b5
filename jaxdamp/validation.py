"""Checks of a configuration before any compute. Each error names the parameter and the limit.

The plain checks (names, signs, finiteness, grains that fit) run first and import nothing
heavy, so they answer at once; the checks that need the contact laws (their own inputs, the
collision time against the time step) import :mod:`jaxdamp.physics` (and with it JAX) last."""

from __future__ import annotations

import importlib.util
import math

from jaxdamp.config import Config, ConfigError, Material

SYSTEMS = ("primary", "driven", "impact")
MIXING = ("arithmetic", "harmonic", "geometric")
#: Densest packing of equal spheres: no bed of the given grains can be lower than this allows.
_DENSEST = math.pi / (3.0 * math.sqrt(2.0))


def _number(value) -> bool:
    """A real number (``True``/``False`` are not, although Python counts them as ints)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _integer(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _positive(value, name, allow_zero=False):
    ok = _number(value) and math.isfinite(value)
    ok = ok and (value >= 0 if allow_zero else value > 0)
    if not ok:
        limit = "≥ 0" if allow_zero else "> 0"
        raise ConfigError(f"{name} = {value!r}: must be a finite number {limit}")


def _material(mat: Material, name: str, grain: bool) -> None:
    _positive(mat.E, f"{name}.E")
    if not (_number(mat.nu) and 0.0 <= mat.nu < 0.5):
        raise ConfigError(f"{name}.nu = {mat.nu!r}: Poisson ratio must be in [0, 0.5)")
    if grain:
        _positive(mat.density, f"{name}.density")
    _positive(mat.mu, f"{name}.mu", allow_zero=True)
    _positive(mat.gamma_s, f"{name}.gamma_s", allow_zero=True)


#: The contact laws by name (:data:`jaxdamp.physics.contact.LAWS`, checked equal by the tests):
#: named here so that a wrong name is refused without importing the physics.
CONTACT_LAWS = ("hertz", "linear")

#: The tangential laws by name (``Config.tangential_law``; named here, so that a wrong name is
#: refused without importing the physics): ``"viscous"``, the thesis' viscous force capped by
#: Coulomb, without memory (:func:`jaxdamp.physics.contact.contact_force`), and ``"mindlin"``,
#: the spring with history (:func:`jaxdamp.physics.tangential.contact_force`; Hertz only).
TANGENTIAL_LAWS = ("viscous", "mindlin")

#: Grain–wall damping conventions (``Config.wall_damping``).
WALL_DAMPING = ("mixed", "calibrated")

#: The engines (``numerics.engine``; :func:`jaxdamp.engine.choice.choose`).
ENGINES = ("auto", "jax", "native", "fused")
#: Where the grains start before settling (``numerics.pour``;
#: :data:`jaxdamp.engine.packing.POURS`).
POURS = ("lattice", "random")
#: The contact laws' floating-point types (``numerics.precision``;
#: :data:`jaxdamp.physics.contact.PRECISIONS`, checked equal by the tests).
PRECISIONS = ("float64", "float32")


def engine_precision_error(engine: str, precision: str) -> str | None:
    """Why ``engine`` cannot run at ``precision``, or ``None``: the native kernel and the
    fused device step compute in float64 (the one statement of the rule, for configurations
    and for direct calls)."""
    if engine in ("native", "fused") and precision != "float64":
        return (f"numerics.precision = {precision!r} runs on the JAX engine only (the "
                f"{engine} kernel computes in float64): set numerics.engine = 'jax' or 'auto'")
    return None


#: Most lines a random base motion may have (``(f_n - f_1)/resolution``): every line costs a
#: cosine and a sine per time step.
MAX_LINES = 20000


def _random(rnd) -> None:
    """Checks of ``Config.random`` (:class:`jaxdamp.config.RandomBase`)."""
    table = rnd.psd
    rows = table if isinstance(table, (list, tuple)) else None
    if (rows is None or len(rows) < 2
            or not all(isinstance(r, (list, tuple)) and len(r) == 2 for r in rows)):
        raise ConfigError(f"random.psd = {table!r}: expected at least two breakpoints "
                          "[[f_1, S_1], [f_2, S_2], ...] (f in Hz, S in (m/s²)²/Hz), e.g. "
                          "[[5, 0.01], [30, 0.01]] for a flat band 5–30 Hz")
    for i, (f, S) in enumerate(rows):
        for name, v in (("f", f), ("S", S)):
            if not (_number(v) and math.isfinite(v)):
                raise ConfigError(f"random.psd[{i}] = {[f, S]!r}: {name} must be a finite "
                                  "number")
        if f < 0:
            raise ConfigError(f"random.psd[{i}] = {[f, S]!r}: frequency {f} Hz must be ≥ 0")
        if S < 0:
            raise ConfigError(f"random.psd[{i}] = {[f, S]!r}: spectral density {S} "
                              "(m/s²)²/Hz must be ≥ 0 (a density is never negative)")
    fs = [r[0] for r in rows]
    if any(b <= a for a, b in zip(fs, fs[1:])):
        raise ConfigError(f"random.psd frequencies {fs}: must increase strictly")
    if not any(r[1] > 0 for r in rows):
        raise ConfigError("random.psd: every density is zero; nothing would move the base")
    _positive(rnd.scale, "random.scale", allow_zero=True)
    _positive(rnd.resolution, "random.resolution")
    if (fs[-1] - fs[0]) / rnd.resolution > MAX_LINES:
        raise ConfigError(f"random.resolution = {rnd.resolution} Hz: the band {fs[0]}–{fs[-1]} "
                          f"Hz would need {(fs[-1] - fs[0]) / rnd.resolution:.0f} lines, more "
                          f"than {MAX_LINES}; use a coarser resolution")
    if fs[-1] < rnd.resolution:
        raise ConfigError(f"random.psd: the band ends at {fs[-1]} Hz, below the first line "
                          f"(random.resolution = {rnd.resolution} Hz)")
    if rnd.seed is not None and not (_integer(rnd.seed) and rnd.seed >= 0):
        raise ConfigError(f"random.seed = {rnd.seed!r}: must be an integer ≥ 0 (or absent: "
                          "the bed's numerics.seed)")


def _matrix(value, name: str, n: int | None = None):
    """A finite square matrix (as nested lists), or a ConfigError naming ``name``."""
    import numpy as np

    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is None or a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] < 1:
        raise ConfigError(f"{name} = {value!r}: expected a square matrix [[...], [...], ...]")
    if n is not None and a.shape[0] != n:
        raise ConfigError(f"{name}: {a.shape[0]}×{a.shape[0]}, expected {n}×{n} like "
                          "structure.M (or the number of modes)")
    if not np.all(np.isfinite(a)):
        raise ConfigError(f"{name}: every entry must be a finite number")
    return a


def _vector(value, name: str, n: int, positive: bool = False, allow_zero: bool = False):
    import numpy as np

    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is None or a.shape != (n,) or not np.all(np.isfinite(a)):
        raise ConfigError(f"{name} = {value!r}: expected {n} finite numbers")
    if positive and not (np.all(a >= 0) if allow_zero else np.all(a > 0)):
        bad = a[a < 0] if allow_zero else a[a <= 0]
        raise ConfigError(f"{name} = {value!r}: every value must be {'≥' if allow_zero else '>'}"
                          f" 0 (got {bad[0]:g})")
    return a


def _structure(s, cells: int = 1) -> None:
    """Checks of ``Config.structure`` (:class:`jaxdamp.config.Structure`) of a damper of
    ``cells`` cells: matrices symmetric, ``M`` positive definite, ``K`` and ``C`` positive
    semi-definite; modal data positive and the shapes invertible; indices in range (``attach``
    one, or one per cell)."""
    import numpy as np

    if (s.M is None) == (s.frequencies is None):
        raise ConfigError("structure: give either the matrices (structure.M, K[, C]) or the "
                          "modal data (structure.frequencies, shapes[, damping, modal_masses]), "
                          "not both and not neither")
    if s.M is not None:
        M = _matrix(s.M, "structure.M")
        n = len(M)
        if s.K is None:
            raise ConfigError("structure.K: the stiffness matrix is missing (structure.M given)")
        mats = {"M": M, "K": _matrix(s.K, "structure.K", n)}
        if s.C is not None:
            mats["C"] = _matrix(s.C, "structure.C", n)
        for key, a in mats.items():
            if not np.allclose(a, a.T, rtol=1e-10, atol=1e-12 * np.abs(a).max()):
                raise ConfigError(f"structure.{key} is not symmetric (largest |A - Aᵀ| = "
                                  f"{np.abs(a - a.T).max():.3g}); a physical {key} is")
            low = float(np.linalg.eigvalsh(a).min())
            scale = max(float(np.abs(a).max()), 1e-300)
            if key == "M" and low <= 1e-12 * scale:
                raise ConfigError(f"structure.M is not positive definite (smallest eigenvalue "
                                  f"{low:.3g} kg); every motion must carry mass")
            if key != "M" and low < -1e-10 * scale:
                raise ConfigError(f"structure.{key} is indefinite (smallest eigenvalue "
                                  f"{low:.3g}); it must be positive semi-definite")
    else:
        f = np.atleast_1d(np.asarray(s.frequencies, dtype=float))
        n = len(f)
        _vector(s.frequencies, "structure.frequencies", n, positive=True)
        if s.shapes is None:
            raise ConfigError("structure.shapes: the mode shapes are missing (structure."
                              "frequencies given)")
        phi = _matrix(s.shapes, "structure.shapes", n)
        if abs(np.linalg.det(phi)) < 1e-12 * max(np.abs(phi).max(), 1e-300) ** n:
            raise ConfigError("structure.shapes is singular: the modes must be independent "
                              "(one column per mode, one row per degree of freedom)")
        if s.damping is not None:
            _vector(s.damping, "structure.damping", n, positive=True, allow_zero=True)
        if s.modal_masses is not None:
            _vector(s.modal_masses, "structure.modal_masses", n, positive=True)
    if isinstance(s.attach, (tuple, list)):  # one degree of freedom per cell
        if len(s.attach) != cells or not all(_integer(a) and 0 <= a < n
                                                    for a in s.attach):
            raise ConfigError(
                f"structure.attach = {list(s.attach)!r}: a list gives the degree of freedom "
                f"(0..{n - 1}) of each of the {cells} cell(s) (cells = {cells}); "
                "a number puts every cell on one")
    elif not (_integer(s.attach) and 0 <= s.attach < n):
        raise ConfigError(f"structure.attach = {s.attach!r}: must be a degree of freedom "
                          f"0..{n - 1} (or a list of one per cell)")
    if not (_integer(s.force_dof) and 0 <= s.force_dof < n):
        raise ConfigError(f"structure.force_dof = {s.force_dof!r}: must be a degree of freedom "
                          f"0..{n - 1}")
    if s.influence is not None:
        _vector(s.influence, "structure.influence", n)
    if not (_number(s.force) and math.isfinite(s.force)):
        raise ConfigError(f"structure.force = {s.force!r}: must be a finite number [N]")


def _cells(config: Config) -> None:
    """Checks of ``Config.cells``: an integer ≥ 1 (on a multi-DOF structure each cell on the
    degree of freedom ``structure.attach`` gives it, checked with the structure); the
    single-particle model (S3) has one cavity."""
    k = config.cells
    if not _integer(k) or k < 1:
        raise ConfigError(f"cells = {k!r}: must be an integer ≥ 1 (the number of identical "
                          "cells of the damper)")
    if k > 1 and config.system == "impact":
        raise ConfigError(f"cells = {k}: the single-particle model (system 'impact', S3) has "
                          "one cavity; only cells = 1")


def periodic(config: Config) -> bool:
    """Whether ``config`` is driven at ``frequency`` (a harmonic base motion of the primary, or
    a driven box), so that its per-cycle quantities and amplitudes mean something."""
    if config.system == "driven":
        return config.drive is not None and config.drive.amplitude > 0
    return (config.system == "primary" and config.primary is not None
            and config.primary.U > 0 and config.random is None and config.shock is None)


def _schedule(config: Config) -> None:
    """The run's sampling against its length and its drive: a sample interval within a chunk
    and within the run; with a periodic drive, samples that resolve it (≥ 20 per period) and a
    run of at least one whole period (the analysis window of per-cycle quantities)."""
    num = config.numerics
    if num.record_dt > num.chunk:
        raise ConfigError(f"numerics.record_dt = {num.record_dt} s: the sample interval must not "
                          f"exceed numerics.chunk = {num.chunk} s (a chunk holds whole samples)")
    if num.record_dt > num.duration:
        raise ConfigError(f"numerics.record_dt = {num.record_dt} s: the sample interval must not "
                          f"exceed the run, numerics.duration = {num.duration} s")
    if periodic(config) and num.record_dt > 1.0 / (20.0 * config.frequency):
        f = config.frequency
        raise ConfigError(
            f"numerics.record_dt = {num.record_dt} s: the samples must resolve the drive at "
            f"frequency = {f:g} Hz, record_dt ≤ 1/(20 f) = {1.0 / (20.0 * f):.4g} s")


def check_periods(config: Config, frequency: float | None = None) -> None:
    """Refuse a periodically driven run shorter than one drive period (at ``frequency``, by
    default ``config.frequency``): its amplitude and per-cycle quantities would be
    extrapolated from part of a cycle. The commands that print them (``run``, ``frf``) call
    this; the library lets shorter runs through (tests of the dynamics use them), and its
    summaries then cover the whole run."""
    f = config.frequency if frequency is None else frequency
    num = config.numerics
    if periodic(config) and num.duration < 1.0 / f:
        raise ConfigError(
            f"numerics.duration = {num.duration:g} s is shorter than one drive period "
            f"(1/f = {1.0 / f:.4g} s at frequency = {f:g} Hz): amplitudes and per-cycle "
            "quantities need at least one whole period — raise numerics.duration (--duration) "
            "or the frequency")


def _container(config: Config) -> None:
    """Exactly one container table: ``[box]`` (Lx, Ly, Lz) or ``[container]`` (its height and
    its dimensions positive; the shape and the names of its dimensions are checked against the
    registry by :func:`_container_shape`, after the checks that need no import)."""
    if (config.box is None) == (config.container is None):
        given = "both" if config.box is not None else "neither"
        raise ConfigError(f"the container: give exactly one of [box] (Lx, Ly, Lz) and "
                          f"[container] (shape, Lz and its dimensions); this gives {given}")
    if config.box is not None:
        box = config.box
        for side in ("Lx", "Ly", "Lz"):
            _positive(getattr(box, side), f"box.{side}")
        if box.wall is not None:
            _material(box.wall, "box.wall", grain=False)
        return
    c = config.container
    _positive(c.Lz, "container.Lz")
    for k, v in c.size:
        _positive(v, f"container.{k}")
    if c.wall is not None:
        _material(c.wall, "container.wall", grain=False)


def _container_shape(config: Config) -> None:
    """A ``[container]`` names a registered shape and exactly its dimensions
    (:data:`jaxdamp.physics.containers.CONTAINERS`; imports the physics)."""
    c = config.container
    if c is None:
        return
    from jaxdamp.physics.containers import CONTAINERS

    shapes = [n for n in CONTAINERS if n != "box"]
    if c.shape not in shapes:
        hint = " (the box is the [box] table)" if c.shape == "box" else ""
        raise ConfigError(f"container.shape = {c.shape!r}: expected one of {shapes}{hint}")
    fields = CONTAINERS[c.shape].fields
    names = [k for k, _ in c.size]
    missing = [f for f in fields if f not in names]
    extra = [k for k in names if k not in fields]
    if missing or extra:
        what = (f"lacks {', '.join(missing)}" if missing
                else f"does not know {', '.join(extra)}")
        raise ConfigError(f"container: a {c.shape} {what}; its dimensions are "
                          f"{', '.join(fields)} [m] (and Lz)")


def _check_tangential(config: Config) -> None:
    """``tangential_law``: a registered name; the spring with history needs the Hertz law
    (its stiffness ``8 G* sqrt(R* ξ)`` and its damping follow the Hertz contact) and a bed."""
    law = config.tangential_law
    if law not in TANGENTIAL_LAWS:
        raise ConfigError(f"tangential_law = {law!r}: expected one of {TANGENTIAL_LAWS}")
    if law == "mindlin" and config.contact_law != "hertz":
        raise ConfigError(f"tangential_law = 'mindlin' needs contact_law = 'hertz' (got "
                          f"{config.contact_law!r}): Mindlin's stiffness 8 G* sqrt(R* ξ) and "
                          "its damping are those of a Hertz contact")
    if law == "mindlin" and config.system == "impact":
        raise ConfigError("tangential_law = 'mindlin' applies to the DEM systems ('primary', "
                          "'driven'); system = 'impact' (S3) has no tangential force")


def unused_note(config: Config) -> str | None:
    """One sentence naming the settings that a run of ``config`` does not use, or ``None``:
    under ``tangential_law = 'mindlin'`` the materials' ``gamma_s`` (the viscous law's
    tangential constant; the spring's damping follows the normal one,
    :func:`jaxdamp.physics.tangential.damping`). Printed before a run, so that a value that
    changes nothing is not taken for one that does."""
    if config.tangential_law != "mindlin":
        return None
    vessel = config.box if config.box is not None else config.container
    where = "box" if config.box is not None else "container"
    mats = [(f"grains.{i}.material", sp.material) for i, sp in enumerate(config.grains)]
    if vessel is not None and vessel.wall is not None:
        mats.append((f"{where}.wall", vessel.wall))
    named = [f"{name}.gamma_s = {m.gamma_s:g}" for name, m in mats if m.gamma_s]
    if not named:
        return None
    return (f"note: {', '.join(named)} [kg s^-1 m^-1/2] not used: under tangential_law = "
            "'mindlin' the tangential damping follows the normal one (γ_t = k_t γ_n / "
            "(1.5 k_n), docs/physics.md §2)")


def validate(config: Config) -> Config:
    """Raise :class:`ConfigError` for any invalid value; return the config, with every
    species' count derived from its ``mass_ratio`` or ``fill_fraction`` where it states one
    (:func:`jaxdamp.cases.filling.resolve`; otherwise unchanged)."""
    if config.system not in SYSTEMS:
        raise ConfigError(f"system = {config.system!r}: expected one of {SYSTEMS}")
    if config.mixing not in MIXING:
        raise ConfigError(f"mixing = {config.mixing!r}: expected one of {MIXING}")
    if config.contact_law not in CONTACT_LAWS:
        raise ConfigError(
            f"contact_law = {config.contact_law!r}: expected one of {CONTACT_LAWS}")
    _check_tangential(config)
    if config.wall_damping not in WALL_DAMPING:
        raise ConfigError(f"wall_damping = {config.wall_damping!r}: expected one of "
                          f"{WALL_DAMPING}")
    if config.wall_damping == "calibrated":
        if config.contact_law != "hertz":
            raise ConfigError("wall_damping = 'calibrated' applies to the Hertz law (the "
                              "linear law's restitution does not depend on the pair's size)")
        table = "box" if config.box is not None else "container"
        wall = getattr(config, table).wall if getattr(config, table) is not None else None
        wall_e = wall.restitution if wall is not None else None
        for i, sp in enumerate(config.grains):
            if wall_e is None and sp.material.restitution is None:
                raise ConfigError(f"wall_damping = 'calibrated': grains.{i}.material has no "
                                  f"restitution (thesis form gamma_n) and {table}.wall gives "
                                  "none; set a restitution or use wall_damping = 'mixed'")
    _positive(config.frequency, "frequency")
    _positive(config.gravity, "gravity", allow_zero=True)
    _container(config)
    _cells(config)
    if config.system == "impact":
        return _validate_impact(config)

    d = config.direction
    if not (isinstance(d, tuple) and len(d) == 3
            and all(_number(x) and math.isfinite(x) for x in d)
            and math.hypot(*d) > 0):
        raise ConfigError(f"direction = {d!r}: the excitation axis must be three finite numbers "
                          "(x, y, z), not all zero, e.g. [0, 0, 1] (vertical) or [1, 0, 0]")
    if config.system == "primary":
        if config.primary is None:
            raise ConfigError("primary: system 'primary' (S1) needs a [primary] table (M, K, C, U)")
        pr = config.primary
        _positive(pr.M, "primary.M")
        _positive(pr.K, "primary.K", allow_zero=True)
        if config.structure is None and pr.K == 0:
            raise ConfigError("primary.K = 0: must be > 0 — without a spring the primary has no "
                              "static equilibrium: the box drifts under the bed's weight and a "
                              "drift would be reported as an amplitude")
        _positive(pr.C, "primary.C", allow_zero=True)
        _positive(pr.U, "primary.U", allow_zero=True)
        for name in ("z0", "v0"):
            value = getattr(pr, name)
            if not (_number(value) and math.isfinite(value)):
                raise ConfigError(f"primary.{name} = {value!r}: must be a finite number")
        if config.random is not None:
            _random(config.random)
        if config.structure is not None:
            _structure(config.structure, config.cells)
        if config.shock is not None:
            sh = config.shock
            if not (_number(sh.peak) and math.isfinite(sh.peak)):
                raise ConfigError(f"shock.peak = {sh.peak!r}: must be a finite number [m/s²]")
            _positive(sh.duration, "shock.duration")
            _positive(sh.start, "shock.start", allow_zero=True)
    else:
        for name in ("random", "shock", "structure"):
            if getattr(config, name) is not None:
                raise ConfigError(f"{name}: base excitation acts on the primary's base (S1, "
                                  f"system 'primary'), not on system {config.system!r}")
        if config.drive is None:
            raise ConfigError("drive: system 'driven' (S2) needs a [drive] table (amplitude)")
        _positive(config.drive.amplitude, "drive.amplitude", allow_zero=True)

    num = config.numerics
    if num.dt is not None:
        _positive(num.dt, "numerics.dt")
    for name in ("dt_per_collision", "v_impact", "duration", "chunk", "record_dt", "skin",
                 "stiffness_scale", "settle_speed"):
        _positive(getattr(num, name), f"numerics.{name}")
    _positive(num.settle_time, "numerics.settle_time", allow_zero=True)
    _positive(num.settle_drag, "numerics.settle_drag", allow_zero=True)
    if num.pour not in POURS:
        raise ConfigError(f"numerics.pour = {num.pour!r}: expected one of {POURS}")
    if not 0.0 < num.analysis_window <= 1.0:
        raise ConfigError(f"numerics.analysis_window = {num.analysis_window}: must be in (0, 1]")
    _schedule(config)
    if num.capacity_multiplier < 1.0:
        raise ConfigError(
            f"numerics.capacity_multiplier = {num.capacity_multiplier}: must be ≥ 1"
        )
    if num.engine not in ENGINES:
        raise ConfigError(f"numerics.engine = {num.engine!r}: expected one of {ENGINES}")
    if num.precision not in PRECISIONS:
        raise ConfigError(f"numerics.precision = {num.precision!r}: expected one of "
                          f"{PRECISIONS}")
    if (why := engine_precision_error(num.engine, num.precision)) is not None:
        raise ConfigError(why)
    if num.engine == "native" and importlib.util.find_spec("numba") is None:
        raise ConfigError("numerics.engine = 'native' needs numba (pip install numba)")
    if num.engine == "fused":
        from jaxdamp.engine import fused

        usable, why = fused.available()
        if not usable:
            raise ConfigError(f"numerics.engine = 'fused': {why}")
    if not _integer(num.seed) or num.seed < 0:
        raise ConfigError(f"numerics.seed = {num.seed!r}: must be a non-negative integer")

    from jaxdamp.physics.containers import container

    _container_shape(config)
    from jaxdamp.cases.filling import resolve

    vessel = container(config)
    lid = vessel.height(config)
    for i, sp in enumerate(config.grains):  # one grain fits, before a fill is reckoned
        name = f"grains.{i}"
        _positive(sp.radius, f"{name}.radius")
        if not 0.0 <= sp.radius_spread < 1.0:
            raise ConfigError(f"{name}.radius_spread = {sp.radius_spread}: must be in [0, 1)")
        r_max = sp.radius * (1.0 + sp.radius_spread)
        grain = (f"{name}.radius = {sp.radius} (largest {r_max:.4g} m): a grain of diameter "
                 f"{2 * r_max:.4g} m")
        why = vessel.fit_error(config, 2.0 * r_max, grain)
        if why is None and 2.0 * r_max >= lid:
            why = f"{grain} does not fit {vessel.lid_key} = {lid} m"
        if why is not None:
            raise ConfigError(why)
    config = resolve(config)  # counts from mass ratios and fill fractions
    volume = 0.0
    for i, sp in enumerate(config.grains):
        name = f"grains.{i}"
        if not _integer(sp.count) or sp.count < 0:
            raise ConfigError(f"{name}.count = {sp.count!r}: must be a non-negative integer")
        _material(sp.material, f"{name}.material", grain=True)
        volume += sp.count * 4.0 / 3.0 * math.pi * sp.radius**3
    if volume > 0:
        height = volume / (_DENSEST * vessel.base_area(config))
        if height >= lid:
            raise ConfigError(
                f"{vessel.lid_key} = {lid} m: the grains cannot fit — even packed at the "
                f"densest possible fraction {_DENSEST:.3f} they fill {height:.4g} m of the "
                f"{vessel.describe(config)}"
            )

    from jaxdamp.physics.contact import LAWS
    from jaxdamp.physics.model import collision_time_limit, config_dt, grain_radii, impact_speed

    law = LAWS[config.contact_law]
    wall = vessel.wall(config)
    if wall is not None:  # the law's own inputs (damping, restitution, ...)
        law.check(wall, f"{vessel.lid_key.split('.')[0]}.wall")
    for i, sp in enumerate(config.grains):
        law.check(sp.material, f"grains.{i}.material")
    radii = grain_radii(config)
    t_c = collision_time_limit(config, radii)
    dt = config_dt(config, radii)
    if math.isfinite(t_c) and dt > t_c / num.dt_per_collision * (1 + 1e-12):
        raise ConfigError(
            f"numerics.dt = {dt:.4g} s is too large: the {config.contact_law} collision time of the smallest "
            f"grains at an impact speed of {impact_speed(config):.4g} m/s (numerics.v_impact = "
            f"{num.v_impact}; a driven box needs at least 2 A_d ω) is t_c = {t_c:.4g} s, and dt must be ≤ "
            f"t_c / {num.dt_per_collision:g} = {t_c / num.dt_per_collision:.4g} s "
            "(lower dt, or numerics.stiffness_scale, or numerics.dt_per_collision knowingly)"
        )
    if dt > 1.0 / (20.0 * config.frequency):
        raise ConfigError(
            f"numerics.dt = {dt:.4g} s: must resolve the excitation, dt ≤ 1/(20 f) = "
            f"{1.0 / (20.0 * config.frequency):.4g} s"
        )
    return config


def _validate_impact(config: Config) -> Config:
    """Checks of an S3 (single-particle impact damper) configuration, see :mod:`jaxdamp.s3.impact`."""
    d = config.direction
    if not (isinstance(d, tuple) and len(d) == 3 and d[0] == 0 and d[1] == 0 and d[2] > 0):
        raise ConfigError(f"direction = {d!r}: the single-particle model (S3) is vertical; use "
                          "[0, 0, 1] (other directions run on the DEM, system 'primary')")
    if config.grains:
        raise ConfigError(f"grains: system 'impact' (S3) models the bed as one particle; grains must "
                          f"be empty (got {config.n_grains} grains) — set impactor.mass instead")
    if config.primary is None:
        raise ConfigError("primary: system 'impact' (S3) needs a [primary] table (M, K, C, U)")
    if config.impactor is None:
        raise ConfigError("impactor: system 'impact' (S3) needs an [impactor] table "
                          "(mass, restitution, gap)")
    pr, im = config.primary, config.impactor
    _positive(pr.M, "primary.M")
    # K > 0: the closed-form segments expand about the static equilibrium -m g / K
    _positive(pr.K, "primary.K")
    _positive(pr.C, "primary.C", allow_zero=True)
    _positive(pr.U, "primary.U", allow_zero=True)
    if pr.z0 != 0.0 or pr.v0 != 0.0:
        raise ConfigError(f"primary.z0 = {pr.z0!r}, primary.v0 = {pr.v0!r}: the single-particle "
                          "model (S3) starts at rest; free decay runs on the DEM (system "
                          "'primary')")
    _positive(im.mass, "impactor.mass")
    if not (_number(im.restitution) and 0.0 <= im.restitution <= 1.0):
        raise ConfigError(f"impactor.restitution = {im.restitution!r}: must be in [0, 1]")
    _positive(im.gap, "impactor.gap")
    if im.method not in ("event", "smooth"):
        raise ConfigError(f"impactor.method = {im.method!r}: expected 'event' or 'smooth'")
    _positive(im.stick_speed, "impactor.stick_speed")
    _positive(im.contact_time, "impactor.contact_time")
    _positive(im.smooth_width, "impactor.smooth_width")
    if not (_number(im.steps_per_contact) and im.steps_per_contact >= 5):
        raise ConfigError(f"impactor.steps_per_contact = {im.steps_per_contact!r}: must be ≥ 5")
    w = 2.0 * math.pi * config.frequency
    if pr.C == 0:
        for name, mass in (("M", pr.M), ("M + m", pr.M + im.mass)):
            if abs(pr.K - mass * w * w) <= 1e-9 * pr.K:
                raise ConfigError(
                    f"frequency = {config.frequency} Hz: exactly at the undamped resonance of "
                    f"mass {name} with primary.C = 0 (unbounded response); set primary.C > 0")
    period = min(1.0 / config.frequency, 2.0 * math.pi * math.sqrt(pr.M / pr.K))
    if im.method == "smooth" and im.contact_time > 0.05 * period:
        raise ConfigError(
            f"impactor.contact_time = {im.contact_time} s: the penalty contact must be short "
            f"against the drive and primary periods, ≤ {0.05 * period:.4g} s (5 % of "
            f"{period:.4g} s)")
    num = config.numerics
    for name in ("duration", "record_dt"):
        _positive(getattr(num, name), f"numerics.{name}")
    if not 0.0 < num.analysis_window <= 1.0:
        raise ConfigError(f"numerics.analysis_window = {num.analysis_window}: must be in (0, 1]")
    if num.record_dt > 1.0 / (20.0 * config.frequency):
        raise ConfigError(
            f"numerics.record_dt = {num.record_dt} s: the samples must resolve the drive, "
            f"record_dt ≤ 1/(20 f) = {1.0 / (20.0 * config.frequency):.4g} s")
    if num.duration < 1.0 / config.frequency:
        raise ConfigError(f"numerics.duration = {num.duration} s: must cover at least one drive "
                          f"period (1/f = {1.0 / config.frequency:.4g} s)")
    _container_shape(config)
    return config
