"""Checks of a configuration before any compute. Each error names the parameter and the limit."""

from __future__ import annotations

import math

from .config import Config, ConfigError, Material
from .model import collision_time_limit, config_dt, grain_radii

SYSTEMS = ("primary", "driven")
MIXING = ("arithmetic", "harmonic", "geometric")
#: Densest packing of equal spheres: no bed of the given grains can be lower than this allows.
_DENSEST = math.pi / (3.0 * math.sqrt(2.0))


def _positive(value, name, allow_zero=False):
    ok = isinstance(value, (int, float)) and math.isfinite(value)
    ok = ok and (value >= 0 if allow_zero else value > 0)
    if not ok:
        limit = "≥ 0" if allow_zero else "> 0"
        raise ConfigError(f"{name} = {value!r}: must be a finite number {limit}")


def _material(mat: Material, name: str, grain: bool) -> None:
    _positive(mat.E, f"{name}.E")
    if not (isinstance(mat.nu, (int, float)) and 0.0 <= mat.nu < 0.5):
        raise ConfigError(f"{name}.nu = {mat.nu!r}: Poisson ratio must be in [0, 0.5)")
    if grain:
        _positive(mat.density, f"{name}.density")
    _positive(mat.mu, f"{name}.mu", allow_zero=True)
    _positive(mat.gamma_s, f"{name}.gamma_s", allow_zero=True)
    if mat.gamma_n is not None and mat.restitution is not None:
        raise ConfigError(
            f"{name}: give either gamma_n (thesis) or restitution (paper), not both "
            f"(gamma_n = {mat.gamma_n}, restitution = {mat.restitution})"
        )
    if mat.gamma_n is not None:
        _positive(mat.gamma_n, f"{name}.gamma_n", allow_zero=True)
    if mat.restitution is not None:
        if not (isinstance(mat.restitution, (int, float)) and 0.0 < mat.restitution <= 1.0):
            raise ConfigError(
                f"{name}.restitution = {mat.restitution!r}: must be in (0, 1]"
            )
        _positive(mat.v_ref, f"{name}.v_ref")


def validate(config: Config) -> Config:
    """Raise :class:`ConfigError` for any invalid value; return the config unchanged."""
    if config.system not in SYSTEMS:
        raise ConfigError(f"system = {config.system!r}: expected one of {SYSTEMS}")
    if config.mixing not in MIXING:
        raise ConfigError(f"mixing = {config.mixing!r}: expected one of {MIXING}")
    _positive(config.frequency, "frequency")
    _positive(config.gravity, "gravity", allow_zero=True)
    box = config.box
    for side in ("Lx", "Ly", "Lz"):
        _positive(getattr(box, side), f"box.{side}")
    if box.wall is not None:
        _material(box.wall, "box.wall", grain=False)

    if config.system == "primary":
        if config.primary is None:
            raise ConfigError("primary: system 'primary' (S1) needs a [primary] table (M, K, C, U)")
        pr = config.primary
        _positive(pr.M, "primary.M")
        _positive(pr.K, "primary.K", allow_zero=True)
        _positive(pr.C, "primary.C", allow_zero=True)
        _positive(pr.U, "primary.U", allow_zero=True)
    else:
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
    if not 0.0 < num.analysis_window <= 1.0:
        raise ConfigError(f"numerics.analysis_window = {num.analysis_window}: must be in (0, 1]")
    if num.capacity_multiplier < 1.0:
        raise ConfigError(
            f"numerics.capacity_multiplier = {num.capacity_multiplier}: must be ≥ 1"
        )
    if num.engine not in ("auto", "jax", "native"):
        raise ConfigError(f"numerics.engine = {num.engine!r}: expected 'auto', 'jax' or 'native'")
    if num.engine == "native":
        from . import native

        if not native.AVAILABLE:
            raise ConfigError("numerics.engine = 'native' needs numba (pip install numba)")
    if not isinstance(num.seed, int) or num.seed < 0:
        raise ConfigError(f"numerics.seed = {num.seed!r}: must be a non-negative integer")

    volume = 0.0
    for i, sp in enumerate(config.grains):
        name = f"grains.{i}"
        if not isinstance(sp.count, int) or sp.count < 0:
            raise ConfigError(f"{name}.count = {sp.count!r}: must be a non-negative integer")
        _positive(sp.radius, f"{name}.radius")
        if not 0.0 <= sp.radius_spread < 1.0:
            raise ConfigError(f"{name}.radius_spread = {sp.radius_spread}: must be in [0, 1)")
        _material(sp.material, f"{name}.material", grain=True)
        r_max = sp.radius * (1.0 + sp.radius_spread)
        for side in ("Lx", "Ly", "Lz"):
            length = getattr(box, side)
            if 2.0 * r_max >= length:
                raise ConfigError(
                    f"{name}.radius = {sp.radius} (largest {r_max:.4g} m): a grain of diameter "
                    f"{2 * r_max:.4g} m does not fit box.{side} = {length} m"
                )
        volume += sp.count * 4.0 / 3.0 * math.pi * sp.radius**3
    if volume > 0:
        height = volume / (_DENSEST * box.Lx * box.Ly)
        if height >= box.Lz:
            raise ConfigError(
                f"box.Lz = {box.Lz} m: the grains cannot fit — even packed at the densest "
                f"possible fraction {_DENSEST:.3f} they fill {height:.4g} m of the "
                f"{box.Lx} × {box.Ly} m base"
            )

    radii = grain_radii(config)
    t_c = collision_time_limit(config, radii)
    dt = config_dt(config, radii)
    if math.isfinite(t_c) and dt > t_c / num.dt_per_collision * (1 + 1e-12):
        raise ConfigError(
            f"numerics.dt = {dt:.4g} s is too large: the Hertz collision time of the smallest "
            f"grains at v_impact = {num.v_impact} m/s is t_c = {t_c:.4g} s, and dt must be ≤ "
            f"t_c / {num.dt_per_collision:g} = {t_c / num.dt_per_collision:.4g} s "
            "(lower dt, or numerics.stiffness_scale, or numerics.dt_per_collision knowingly)"
        )
    if dt > 1.0 / (20.0 * config.frequency):
        raise ConfigError(
            f"numerics.dt = {dt:.4g} s: must resolve the excitation, dt ≤ 1/(20 f) = "
            f"{1.0 / (20.0 * config.frequency):.4g} s"
        )
    return config
