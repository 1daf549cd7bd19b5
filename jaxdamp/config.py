"""Typed, validated configuration of a particle-damper simulation.

A :class:`Config` is a tree of frozen dataclasses holding plain Python numbers (SI units). It is
what users write (presets, TOML files, ``--set key=value``), what every output file stores (as
JSON), and what :mod:`jaxdamp.physics.model` turns into JAX arrays. Nothing here touches JAX.

Two systems (docs/physics.md §1):

* ``system = "primary"`` (S1): the box rides on a 1-DOF primary ``M, K, C`` whose base moves as
  ``u(t) = U cos(2π f t)``.
* ``system = "driven"`` (S2): the box itself moves as ``z(t) = A_d cos(2π f t)``.
* ``system = "impact"`` (S3): the primary of S1 with the whole bed replaced by one point mass
  (:class:`Impactor`, modelled by :mod:`jaxdamp.s3.impact`); ``grains`` must be empty and the box
  is not used (the free height is ``impactor.gap``).

Contact damping is given per material either directly (``gamma_n``, ``gamma_s``; thesis) or as a
coefficient of restitution ``restitution`` at impact speed ``v_ref`` for a like-pair collision
(paper), which :mod:`jaxdamp.physics.restitution` turns into the dissipative constant ``A``.
A material may also be named from the table of :mod:`jaxdamp.materials` (``material = "steel"``,
``wall = "glass"``), resolved to its full :class:`Material` when the configuration is built.
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from dataclasses import dataclass, field, fields, replace
from typing import Any

from jaxdamp import materials


class ConfigError(ValueError):
    """A configuration value is invalid. The message names the parameter and the limit."""


@dataclass(frozen=True)
class Material:
    """Elastic, frictional and dissipative properties of grains or walls.

    Attributes:
      E: Young's modulus [Pa].
      nu: Poisson ratio [-], in [0, 0.5).
      density: mass density [kg/m^3] (ignored for walls).
      mu: Coulomb friction coefficient [-]. For a pair, the mixing rule combines both sides.
      gamma_n: normal viscoelastic constant [kg s^-1 m^-1/2] (thesis form ``γ_n sqrt(ξ) ξ'``).
        Give either ``gamma_n`` or ``restitution``.
      gamma_s: tangential viscous constant [kg s^-1 m^-1/2] (``γ_s sqrt(ξ) |v_s|``).
      restitution: coefficient of restitution [-] of a head-on collision of two grains of this
        material and the species' radius at speed ``v_ref`` (paper form); sets ``A``.
      v_ref: impact speed [m/s] at which ``restitution`` holds.
      calibration_radius: radius [m] of the like-pair collision at which ``restitution`` holds;
        ``None`` means the species' own radius (for walls: the first species'). Fixing it for
        the walls keeps the wall's constant the same across mixtures of different sizes.
      linear_stiffness: contact stiffness ``k`` [N/m] of the linear spring–dashpot law
        (``Config.contact_law = "linear"``, required there) for a contact between two bodies of
        this material; there ``restitution`` (default 1) holds at every speed and ``E``,
        ``nu``, ``v_ref``, ``calibration_radius`` play no role.
    """

    E: float
    nu: float
    density: float
    mu: float = 0.0
    gamma_n: float | None = None
    gamma_s: float = 0.0
    restitution: float | None = None
    v_ref: float = 1.0
    calibration_radius: float | None = None
    linear_stiffness: float | None = None


@dataclass(frozen=True, kw_only=True)
class Species:
    """One kind of grain.

    Attributes:
      count: number of grains; or, instead, one of
      mass_ratio: the species' mass over the primary's mass ``M`` [-], or
      fill_fraction: the volume of the species' bed at random packing over the cavity's
        volume [-] (:mod:`jaxdamp.cases.filling`; validation turns either into ``count`` and
        keeps it beside the statement).
      radius: mean radius [m].
      radius_spread: relative half-width of a uniform radius distribution (0.04 means radii
        uniformly in ``radius * [0.96, 1.04]``), drawn with the run's seed.
      material: the grains' :class:`Material`.
      name: label used in outputs.

    Example (TOML)::

        [[grains]]
        mass_ratio = 0.1          # 10 % of the primary's mass
        radius = 0.003
        material = "steel"        # from the material table (:mod:`jaxdamp.materials`), or
        # [grains.material]       # a whole table, or name = "steel" with fields replaced
        # name = "steel"
        # mu = 0.1

    A material given by name (``material = "glass"``; ``--set grains.0.material=glass``) is
    resolved to the table's full :class:`Material` when the configuration is built, so the
    configuration (and every output file's copy of it) holds the numbers, not the name.
    """

    count: int | None = None
    mass_ratio: float | None = None
    fill_fraction: float | None = None
    radius: float
    material: Material
    radius_spread: float = 0.0
    name: str = "grains"


#: The ways a species states its fill (:class:`Species`), the count first.
FILL_KEYS = ("count", "mass_ratio", "fill_fraction")


@dataclass(frozen=True)
class Box:
    """The container: a rectangular box with flat walls that moves rigidly along z.

    Attributes:
      Lx, Ly: base side lengths [m].
      Lz: inner height [m] (floor to lid).
      wall: wall :class:`Material`; ``None`` means the material of the first species; a
        name of the material table (``wall = "steel"``) is resolved as for grains.
    """

    Lx: float
    Ly: float
    Lz: float
    wall: Material | None = None


@dataclass(frozen=True)
class Container:
    """A container other than the box of ``[box]``, chosen by name (``[container]`` in TOML;
    :data:`jaxdamp.physics.containers.CONTAINERS`).

    Attributes:
      shape: the container's name, e.g. ``"cylinder"``.
      Lz: inner height, floor to lid [m].
      size: the container's own dimensions [m] by name, in TOML keys of the table beside
        ``shape`` (the cylinder: ``radius``); each container names its own
        (``Container.fields``), stored here as sorted ``(name, value)`` pairs.
      wall: wall :class:`Material`; ``None`` means the material of the first species; a
        name of the material table (``wall = "steel"``) is resolved as for grains.

    Example (TOML)::

        [container]
        shape = "cylinder"
        radius = 0.02
        Lz = 0.12
    """

    shape: str
    Lz: float
    size: tuple[tuple[str, float], ...] = ()
    wall: Material | None = None

    def dimension(self, name: str) -> float:
        """The dimension ``name`` [m] (``KeyError`` if the table does not give it)."""
        return dict(self.size)[name]


@dataclass(frozen=True)
class Primary:
    """The 1-DOF primary system of S1: ``M z'' = -C(z'-u') - K(z-u) + F_gz``.

    Attributes:
      M: primary mass [kg] (box included, grains excluded).
      K: spring stiffness [N/m].
      C: viscous damping [N s/m].
      U: base displacement amplitude [m].
      z0: the primary's displacement from its static equilibrium (under the bed's weight) at
        t = 0 [m]: with ``U = 0``, a free-decay test (``jaxdamp decay``); the grains start
        where the settled bed lies, moved with the box.
      v0: the primary's velocity at t = 0 [m/s] (an impulse on the structure: the grains
        start at rest).
    """

    M: float
    K: float
    C: float
    U: float
    z0: float = 0.0
    v0: float = 0.0


@dataclass(frozen=True)
class Drive:
    """Prescribed box motion of S2: ``z_box(t) = amplitude cos(2π f t)``.

    Attributes:
      amplitude: ``A_d`` [m].
    """

    amplitude: float


@dataclass(frozen=True)
class RandomBase:
    """Band-limited random base motion of S1, added to the harmonic one
    (:mod:`jaxdamp.physics.excitation`: a random-phase multisine).

    Attributes:
      psd: the one-sided base *acceleration* spectral density as breakpoints
        ``[[f_1, S_1], [f_2, S_2], …]`` (``f`` [Hz] increasing, ``S`` [(m/s²)²/Hz] ≥ 0), linear
        between them and zero outside ``[f_1, f_n]``; a flat band is ``[[f_lo, S], [f_hi, S]]``.
      scale: factor on ``S`` (a level sweep varies it: RMS ∝ √scale) [-].
      resolution: line spacing ``Δf`` [Hz]; the motion repeats every ``1/Δf`` s.
      seed: seed of the phases; ``None`` uses ``numerics.seed`` (each bed of a replicated study
        its own realisation of the excitation).
    """

    psd: tuple[tuple[float, float], ...]
    scale: float = 1.0
    resolution: float = 0.25
    seed: int | None = None


@dataclass(frozen=True)
class Structure:
    """A multi-degree-of-freedom primary structure carrying the damper (S1), in place of the
    1-DOF primary's ``M, K, C`` (:mod:`jaxdamp.physics.structure`; ``primary`` still gives the
    base amplitude ``U`` and the box's initial ``z0``, ``v0``; its ``M, K, C`` are not used).

    Give either the matrices or the modal data:

    Attributes:
      M, K, C: mass [kg], stiffness [N/m] and damping [N s/m] matrices ``(n, n)``, symmetric
        (``C`` optional: zero).
      frequencies: natural frequencies ``f_k`` [Hz] of the modes.
      damping: modal damping ratios ``ζ_k`` [-] (optional: zero).
      shapes: mode shapes ``Φ`` ``(n, n)``: row ``i`` degree of freedom ``i``, column ``k``
        mode ``k``.
      modal_masses: ``m_k`` [kg] of the shapes as given; ``None``: mass-normalised shapes.
      attach: the degree of freedom that carries the box (0-based).
      influence: how the base moves each degree of freedom, ``r`` ``(n,)`` (default all ones:
        the whole structure on the moving base).
      force: amplitude ``F0`` [N] of a harmonic force ``F0 cos(2π f t)`` on ``force_dof``.
      force_dof: the degree of freedom the force acts on (0-based).
    """

    M: tuple[tuple[float, ...], ...] | None = None
    K: tuple[tuple[float, ...], ...] | None = None
    C: tuple[tuple[float, ...], ...] | None = None
    frequencies: tuple[float, ...] | None = None
    damping: tuple[float, ...] | None = None
    shapes: tuple[tuple[float, ...], ...] | None = None
    modal_masses: tuple[float, ...] | None = None
    attach: int = 0
    influence: tuple[float, ...] | None = None
    force: float = 0.0
    force_dof: int = 0


@dataclass(frozen=True)
class Shock:
    """A half-sine base acceleration pulse of S1 (:func:`jaxdamp.physics.excitation.shock_pulse`):
    ``u'' = peak sin(π (t - start)/duration)`` during the pulse, from rest; the base keeps the
    velocity ``2 peak duration / π`` it ends with.

    Attributes:
      peak: peak base acceleration [m/s²] (its sign gives the direction along the axis).
      duration: pulse length ``T`` [s].
      start: time of the pulse's start after settling [s].
    """

    peak: float
    duration: float
    start: float = 0.0


@dataclass(frozen=True)
class Impactor:
    """The single particle of S3 (docs/physics.md §1 S3; thesis §2.1.3, §5.3.2), see :mod:`jaxdamp.s3.impact`.

    Attributes:
      mass: particle mass ``m`` [kg] (the bed's total mass ``m_p`` when it stands for a bed).
      restitution: coefficient of restitution ``e`` of particle–box impacts [-], in [0, 1].
      gap: free height between floor and lid for the point particle [m] (for a bed:
        ``Lz - h_bed``).
      method: ``"event"`` (exact event-driven, numba) or ``"smooth"`` (penalty contacts, JAX,
        differentiable, ``vmap``-batched).
      stick_speed: event-driven only: after an impact slower than this relative speed [m/s]
        the particle sticks to the wall if the contact force is compressive (ends the
        infinite series of ever shorter bounces of ``e > 0``; its loss is booked).
      contact_time: smooth only: duration of one free collision of the penalty contact [s]
        (sets the contact stiffness).
      steps_per_contact: smooth only: time steps per ``contact_time``.
      smooth_width: smooth only: length [m] over which the contact force switches on.
    """

    mass: float
    restitution: float
    gap: float
    method: str = "event"
    stick_speed: float = 1e-4
    contact_time: float = 3e-4
    steps_per_contact: float = 20.0
    smooth_width: float = 3e-5


@dataclass(frozen=True)
class Numerics:
    """How the equations are integrated and recorded.

    Attributes:
      dt: time step [s]; ``None`` chooses ``t_c / dt_per_collision`` from the Hertz collision
        time of the smallest grains at ``v_impact``.
      dt_per_collision: the minimum number of steps per collision (docs/physics.md §3: 50).
      v_impact: largest expected impact speed [m/s] used for the collision time; for a driven
        box (S2) the walls' relative speed ``2 A_d ω`` is used when larger.
      duration: simulated time after settling [s].
      chunk: simulated time per jitted chunk [s] (checkpoint, progress and overflow checks
        happen between chunks).
      record_dt: interval between recorded samples of the time series [s].
      analysis_window: fraction of the run at its end used for steady-state quantities (at
        least one drive period).
      seed: seed of every random choice (radii, lattice jitter).
      skin: neighbour-list skin as a fraction of the largest radius.
      capacity_multiplier: neighbour-list capacity headroom.
      stiffness_scale: factor on every Young's modulus. Damping constants ``gamma_n`` and
        ``gamma_s`` are scaled by ``stiffness_scale**0.6``, which leaves the outcome of every
        binary collision (restitution, tangential impulse) unchanged and only lengthens the
        collision time (see :mod:`jaxdamp.physics.restitution`). A visible, recorded choice.
      settle_time: maximum simulated time for settling the bed before driving [s].
      settle_speed: settling stops once every grain is slower than this [m/s].
      settle_drag: viscous drag rate [1/s] on grains during settling only.
      pour: where the grains start before they settle (:mod:`jaxdamp.engine.packing`):
        ``"lattice"`` (default; an FCC lattice with a small seeded jitter, from the floor
        up: quick to settle, but the settled bed keeps some of its order) or ``"random"``
        (uniformly random places in a loose column, the seed choosing them: a random pour).
      engine: ``"auto"`` (by workload, :mod:`jaxdamp.engine.choice`: the compiled CPU kernel
        of :mod:`jaxdamp.engine.native` when JAX runs on the CPU and for small batches beside
        an accelerator), ``"jax"`` (the XLA step, differentiable), ``"native"`` or
        ``"fused"`` (the CUDA kernel of :mod:`jaxdamp.engine.fused`, one launch per chunk;
        needs ``jaxdamp[cuda]`` and an NVIDIA GPU). All compute the same step; gradients
        always use JAX.
      precision: ``"float64"`` (default) or ``"float32"``: the floating-point type the JAX
        engine evaluates the contact laws in (for accelerators, where float32 is much faster).
        The state, the integration, each contact's overlap and normal, and every sum of
        energies and powers stay float64; docs/physics.md §3 gives what float32 costs in
        accuracy. ``"float32"`` runs on the JAX engine (``"auto"`` picks it; the native
        kernel is float64 only).
    """

    dt: float | None = None
    dt_per_collision: float = 50.0
    v_impact: float = 1.0
    duration: float = 1.0
    chunk: float = 0.05
    record_dt: float = 2.5e-4
    analysis_window: float = 0.1
    seed: int = 0
    skin: float = 0.3
    capacity_multiplier: float = 1.5
    stiffness_scale: float = 1.0
    settle_time: float = 1.0
    settle_speed: float = 5e-3
    settle_drag: float = 20.0
    pour: str = "lattice"
    engine: str = "auto"
    precision: str = "float64"


@dataclass(frozen=True)
class Config:
    """A complete simulation.

    Attributes:
      system: ``"primary"`` (S1), ``"driven"`` (S2) or ``"impact"`` (S3).
      frequency: excitation frequency ``f`` [Hz] (``Ω = 2π f``).
      grains: the grain species (an empty tuple means an empty box).
      box: the container when it is the rectangular box (``[box]``).
      container: the container when it is another registered shape (``[container]``); a
        configuration gives exactly one of ``box`` and ``container``.
      primary: the primary system (required for S1).
      drive: the prescribed box motion (required for S2).
      impactor: the single particle (required for S3).
      random: band-limited random base motion (S1), added to the harmonic ``primary.U``.
      shock: a half-sine base acceleration pulse (S1), added to the rest.
      structure: a multi-DOF primary structure (S1) in place of the primary's ``M, K, C``.
      numerics: integration and recording.
      gravity: ``g`` [m/s^2] along ``-z``.
      direction: the axis of the excitation, a vector ``(x, y, z)`` (normalised when the model
        is built): the base motion and the primary's degree of freedom (S1) or the prescribed
        box motion (S2) act along it, the box translating rigidly along it; gravity stays along
        ``-z``. Default ``(0, 0, 1)``, vertical (both sources); ``(1, 0, 0)`` drives the box
        horizontally. S3 is vertical only.
      mixing: how per-species constants combine for a pair: ``"arithmetic"``, ``"harmonic"``
        or ``"geometric"`` mean (the 2023 paper: arithmetic).
      wall_damping: how grain–wall contacts are damped (docs/physics.md §7, "Grain–wall damping
        convention"): ``"mixed"`` (default; the wall material's constant mixed with each
        grain's by ``mixing``) or ``"calibrated"`` (every species' grain–wall contact gets the
        damping for which a grain of that species hitting the wall at ``v_ref`` has the
        restitution of the wall material, or of the species where the wall gives none; Hertz
        law, restitution-form materials).
      contact_law: the normal contact law by name, one of :data:`jaxdamp.physics.contact.LAWS`:
        ``"hertz"`` (Hertz + viscoelastic, docs/physics.md §2) or ``"linear"`` (linear spring–dashpot
        with a speed-independent restitution; needs ``Material.linear_stiffness``).
      tangential_law: the tangential contact force by name, one of
        :data:`jaxdamp.validation.TANGENTIAL_LAWS`: ``"viscous"`` (default; the
        thesis' ``γ_s sqrt(ξ) |v_s|`` capped by Coulomb, no memory) or ``"mindlin"`` (the
        Hertz–Mindlin tangential spring with contact history, ``k_t = 8 G* sqrt(R* ξ)`` from
        the materials' ``E`` and ``nu``, damped with the normal law's relaxation time;
        ``gamma_s`` is then unused; Hertz law; the JAX engine; docs/physics.md §2).
      name: preset or user label.
      notes: free text, e.g. deviations from a source.
      cells: the number ``k`` of identical cells of the damper on the same primary degree of
        freedom (default 1): each cell its own container (``box`` or ``container``) and bed,
        the sum of their wall forces acting on the primary (docs/physics.md, "Several cells").
        The ``[[grains]]`` tables state the fill of *each* cell (a ``count`` and a
        ``fill_fraction`` are per cell); a ``mass_ratio`` is the whole damper's (all cells),
        each cell getting ``μ/k``. One degree of freedom only (no ``structure``).
    """

    system: str
    frequency: float
    grains: tuple[Species, ...]
    box: Box | None = None
    primary: Primary | None = None
    drive: Drive | None = None
    impactor: Impactor | None = None
    random: RandomBase | None = None
    shock: Shock | None = None
    structure: Structure | None = None
    numerics: Numerics = field(default_factory=Numerics)
    gravity: float = 9.8
    direction: tuple[float, float, float] = (0.0, 0.0, 1.0)
    mixing: str = "arithmetic"
    wall_damping: str = "mixed"
    contact_law: str = "hertz"
    tangential_law: str = "viscous"
    name: str = "custom"
    notes: str = ""
    container: Container | None = None
    cells: int = 1

    # -- convenience -------------------------------------------------------------------------
    @property
    def n_grains(self) -> int:
        """Grains of the whole damper: every cell's (``cells ×`` the counts of a cell)."""
        if any(s.count is None for s in self.grains):
            raise ConfigError("the grain counts are stated as mass_ratio or fill_fraction: "
                              "validate the configuration first (jaxdamp.validation.validate "
                              "turns them into counts)")
        return self.cells * sum(s.count for s in self.grains)

    @property
    def omega(self) -> float:
        return 2.0 * math.pi * self.frequency

    @property
    def wall_material(self) -> Material:
        wall = (self.box or self.container).wall
        if wall is not None:
            return wall
        if not self.grains:
            return Material(E=1.0, nu=0.0, density=1.0)
        return self.grains[0].material

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dicts and lists (JSON/TOML-ready); a container's ``size`` is written
        as keys of its table, as in TOML."""
        d = _listify(dataclasses.asdict(self))
        if d.get("container") is not None:
            d["container"].update({k: v for k, v in d["container"].pop("size")})
        return d

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True)

    def replace(self, **changes) -> "Config":
        return replace(self, **changes)


# ---------------------------------------------------------------------------------------------
# dict <-> Config


def _listify(x):
    if isinstance(x, dict):
        return {k: _listify(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_listify(v) for v in x]
    return x


def _build(cls, data: Any, path: str):
    """Build dataclass ``cls`` from a (nested) dict, rejecting unknown keys by name and
    true/false where a number or text is expected (:func:`_refuse_bool`). The required keys
    are there (:func:`from_dict` checks them first, :func:`missing_keys`)."""
    if data is None:
        return None
    if dataclasses.is_dataclass(data):
        return data
    if cls is Material:
        data = _material_table(data, path)
    if not isinstance(data, dict):
        raise ConfigError(f"{path or 'config'}: expected a table, got {data!r}")
    if cls is Container:
        data = _container_table(data, path)
    known = {f.name: f for f in fields(cls)}
    unknown = sorted(set(data) - set(known))
    if unknown:
        raise ConfigError(
            f"{path or 'config'}: unknown key(s) {unknown}; known keys: {sorted(known)}"
        )
    kwargs = {}
    for name, value in data.items():
        sub = f"{path}.{name}" if path else name
        if (cls, name) not in _NESTED and not (cls is Config and name == "grains"):
            _refuse_bool(known[name], value, sub)  # (a table's own message says "a table")
        kwargs[name] = _convert(cls, name, value, sub)
    return cls(**kwargs)


def _material_table(data: Any, path: str) -> Any:
    """A material given by name as :class:`Material` fields: ``"steel"`` is the table's entry
    (:mod:`jaxdamp.materials`), ``{"name": "steel", "mu": 0.1}`` the entry with the other keys
    replacing its fields; any other table is returned as it is. An unknown name, or a value
    that is neither a name nor a table, raises :class:`ConfigError` naming the parameter and
    listing the known names."""
    if isinstance(data, str):
        return _named_material(data, path)
    if isinstance(data, dict) and "name" in data:
        fields_ = _named_material(data["name"], f"{path}.name")
        fields_.update({k: v for k, v in data.items() if k != "name"})
        return fields_
    if isinstance(data, dict):
        return data
    raise ConfigError(f"{path}: expected a material name ({', '.join(materials.names())}) "
                      f"or a table of its properties, got {data!r}")


def named_material(name: str, path: str = "material") -> Material:
    """The :class:`Material` the table of :mod:`jaxdamp.materials` gives for ``name``; an
    unknown name raises :class:`ConfigError` naming ``path`` and listing the known names."""
    return Material(**_named_material(name, path))


def _named_material(name: Any, path: str) -> dict:
    try:
        return materials.lookup(name).fields()
    except (KeyError, AttributeError, TypeError):
        raise ConfigError(f"{path} = {name!r}: not a material of the table; known materials: "
                          f"{', '.join(materials.names())} (jaxdamp materials lists them, "
                          "docs/materials.md gives their sources), or give the properties as "
                          "a table") from None


def _container_table(data: dict, path: str) -> dict:
    """A ``[container]`` table as :class:`Container` fields: every key beside ``shape``,
    ``Lz`` and ``wall`` is one of the container's dimensions [m] (checked against the
    container's own list by :mod:`jaxdamp.validation`)."""
    out = {k: v for k, v in data.items() if k in ("shape", "Lz", "wall")}
    size = []
    for k, v in data.items():
        if k in ("shape", "Lz", "wall"):
            continue
        if k == "size" and isinstance(v, (list, tuple)):  # the stored form, pairs
            size += [tuple(pair) for pair in v]
            continue
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise ConfigError(f"{path}.{k} = {v!r}: a dimension of the container, must be a "
                              "number [m]")
        size.append((k, float(v)))
    out["size"] = tuple(sorted(size))
    return out


def _refuse_bool(f: dataclasses.Field, value: Any, path: str) -> None:
    """No setting of a configuration is true/false: TOML's ``true`` is Python's ``bool``, a
    subclass of ``int``, which would otherwise pass every check of a number as 1 (or 0). The
    message says what the field holds, from its annotation."""
    if not _holds_bool(value):
        return
    kind = str(f.type)
    if kind.startswith("int"):
        rule = "must be a non-negative integer"
    elif kind.startswith("str"):
        rule = "must be text in quotes, not true/false"
    elif kind.startswith("tuple"):
        rule = "must hold numbers, not true/false"
    else:
        rule = "must be a number, not true/false"
    raise ConfigError(f"{path} = {value!r}: {rule}")


def _holds_bool(value: Any) -> bool:
    if isinstance(value, bool):
        return True
    return isinstance(value, (list, tuple)) and any(_holds_bool(v) for v in value)


def _required(cls) -> list[str]:
    """The fields of dataclass ``cls`` without a default (a configuration must give them)."""
    return [f.name for f in fields(cls)
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]


def missing_keys(data: Any, cls=None, path: str = "") -> list[str]:
    """The dotted keys a configuration dict ``data`` lacks (or sets to none) that have no
    default, in nested tables too (``["system", "box.Lz", "grains.0.material.E"]``); what is
    not a table here is left to :func:`_build`'s messages."""
    cls = Config if cls is None else cls
    if not isinstance(data, dict) or cls is Material and "name" in data:
        return []  # (a named material: the table gives the rest)
    out = [f"{path}.{n}" if path else n for n in _required(cls) if data.get(n) is None]
    if cls is Config and data.get("box") is None and data.get("container") is None:
        out.insert(min(3, len(out)), "box")  # the container: [box] or [container]
    for name, value in data.items():
        sub = f"{path}.{name}" if path else name
        if (cls, name) in _NESTED:
            out += missing_keys(value, _NESTED[(cls, name)], sub)
        elif cls is Config and name == "grains":
            species = [value] if isinstance(value, dict) else value
            if isinstance(species, (list, tuple)):
                for i, sp in enumerate(species):
                    out += missing_keys(sp, Species, f"{sub}.{i}")
    return out


#: The required keys of a whole configuration in the project's words (docs/physics.md §1).
_TOP_KEYS = {
    "system": 'system ("primary", "driven" or "impact")',
    "frequency": "frequency [Hz]",
    "grains": "the grains ([[grains]] tables: count (or mass_ratio, or fill_fraction), radius, "
              "material = \"steel\" or a [grains.material] table)",
    "box": "the box ([box] table: Lx, Ly, Lz [m]; or a [container] table with its shape)",
}


def _missing_words(missing: list[str]) -> str:
    words = [_TOP_KEYS.get(k, k) for k in missing]
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


_NESTED = {
    (Config, "box"): Box,
    (Config, "primary"): Primary,
    (Config, "drive"): Drive,
    (Config, "impactor"): Impactor,
    (Config, "random"): RandomBase,
    (Config, "shock"): Shock,
    (Config, "structure"): Structure,
    (Config, "numerics"): Numerics,
    (Config, "container"): Container,
    (Box, "wall"): Material,
    (Container, "wall"): Material,
    (Species, "material"): Material,
}


def _convert(cls, name: str, value: Any, path: str):
    if (cls, name) in _NESTED:
        return _build(_NESTED[(cls, name)], value, path)
    if cls is Config and name == "direction" and isinstance(value, (list, tuple)):
        return tuple(value)
    if cls is Structure and isinstance(value, (list, tuple)):
        return tuple(tuple(row) if isinstance(row, (list, tuple)) else row for row in value)
    if cls is RandomBase and name == "psd" and isinstance(value, (list, tuple)):
        return tuple(tuple(row) if isinstance(row, (list, tuple)) else row for row in value)
    if cls is Config and name == "grains":
        if isinstance(value, dict):
            value = [value]
        if not isinstance(value, (list, tuple)):
            raise ConfigError(f"grains = {value!r}: expected a list of species tables "
                              "([[grains]] in TOML; [] for an empty box)")
        return tuple(_build(Species, v, f"{path}.{i}") for i, v in enumerate(value))
    return value


def from_dict(data: dict[str, Any]) -> Config:
    """Build a :class:`Config` from a nested dict (e.g. parsed TOML or stored JSON); a
    :class:`ConfigError` names every required key it lacks (:func:`missing_keys`)."""
    missing = missing_keys(data)
    if missing:
        raise ConfigError(f"the configuration lacks {_missing_words(missing)} (required, no "
                          "default)")
    return _build(Config, data, "")


def from_json(text: str) -> Config:
    return from_dict(json.loads(text))


def is_stored(text, config: Config) -> bool:
    """Whether the stored configuration ``text`` (JSON, e.g. a file's attribute) is
    ``config``: compared as configurations, so a file written before a field with a default
    was added still matches (its JSON lacks the field); ``False`` for anything unreadable."""
    if not isinstance(text, str):
        return False
    try:
        return from_json(text) == config
    except (ConfigError, ValueError, TypeError):
        return False


def load_toml(path: str, base: Config | None = None) -> Config:
    """Read a TOML file. With ``base``, the file's keys override ``base`` (partial files OK).

    A file that is missing, unreadable, not UTF-8 text or not valid TOML raises
    :class:`ConfigError` naming the file (and the line and column of a syntax error); so does
    a file without ``base`` that lacks required keys (naming them, and how to start from a
    preset instead)."""
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise ConfigError(f"configuration file {path}: no such file") from None
    except IsADirectoryError:
        raise ConfigError(f"configuration file {path}: is a folder, not a TOML file") from None
    except OSError as err:
        raise ConfigError(f"configuration file {path}: cannot be read "
                          f"({err.strerror or err})") from None
    except UnicodeDecodeError as err:
        raise ConfigError(f"configuration file {path}: not a UTF-8 text file (byte "
                          f"{err.start}); a configuration is TOML text") from None
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"configuration file {path}: TOML syntax error: {err}") from None
    if base is None:
        missing = missing_keys(data)
        if missing:
            raise ConfigError(
                f"configuration file {path}: with no preset it must hold a whole "
                f"configuration, and it lacks {_missing_words(missing)}; give --preset NAME "
                f"together with --config {path} (the file's keys then override the preset's), "
                "or start a whole file from a preset: jaxdamp presets --show NAME > my.toml "
                "(the names: jaxdamp presets)")
        return from_dict(data)
    merged = _one_container(_deep_merge(base.to_dict(), data), set(data))
    if "grains" not in data:  # the base's grains, in a cavity or under a mass the file may set
        _restate(merged, [])
    return from_dict(merged)


def _one_container(data: dict, given) -> dict:
    """A configuration has one container: where ``given`` (the keys a file or the overrides
    set) names one of ``box`` / ``container`` and not the other, the other is dropped (a
    ``[container]`` file over a box preset makes a cylinder, not both)."""
    for table, other in (("container", "box"), ("box", "container")):
        if table in given and other not in given:
            data[other] = None
    return data


def _deep_merge(base: dict, top: dict) -> dict:
    """``top`` over ``base``, tables merged key by key; a material table that names an entry of
    the material table (``[box.wall]`` with ``name = "glass"``) replaces the base's material
    whole, its other keys replacing the entry's fields (not the base's)."""
    out = dict(base)
    for key, value in top.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict) and not (
                key in _MATERIAL_KEYS and "name" in value):
            out[key] = _deep_merge(out[key], value)
        else:
            out[key] = value
    return out


# ---------------------------------------------------------------------------------------------
# --set key=value overrides


def parse_value(text: str) -> Any:
    """Parse the right-hand side of ``--set``: TOML scalars/arrays, ``none``, or a bare string."""
    text = text.strip()
    if text.lower() in ("none", "null"):
        return None
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def get_path(config: Config, key: str) -> Any:
    """The value at dotted ``key`` of ``config`` (``"box.Lz"``, ``"grains.0.radius"``, a
    container's own dimension ``"container.radius"``), as :func:`apply_overrides` names it."""
    node: Any = config
    for part in key.split("."):
        if isinstance(node, (list, tuple)):
            node = node[int(part)]
        elif isinstance(node, Container) and not hasattr(node, part):
            node = node.dimension(part)
        else:
            node = getattr(node, part)
    return node


def apply_overrides(config: Config, overrides: list[str] | dict[str, Any]) -> Config:
    """Apply dotted-key overrides such as ``box.Lz=0.1225`` or ``grains.0.count=100``.

    ``overrides`` is a list of ``"key=value"`` strings (CLI ``--set``) or a dict of key -> value.
    Setting a missing optional section (``drive.amplitude=0.02`` on an S1 config) creates it;
    setting a ``container`` table on a box configuration (``container.shape=cylinder``,
    ``container.radius=0.02``, ``container.Lz=0.12``) replaces the box, and back. A material
    is set by name too (``grains.0.material=glass``, ``box.wall=steel``; a later
    ``grains.0.material.mu=0.1`` then replaces one of the named material's fields).
    Raises :class:`ConfigError` naming the key for malformed items or unknown keys.
    """
    if isinstance(overrides, dict):
        items = list(overrides.items())
    else:
        items = []
        for item in overrides:
            if "=" not in item:
                raise ConfigError(
                    f"--set {item!r}: expected key=value, e.g. --set box.Lz=0.1225"
                )
            key, value = item.split("=", 1)
            key = key.strip()
            if not key:
                raise ConfigError(f"--set {item!r}: the key before '=' is empty")
            items.append((key, parse_value(value)))
    data = config.to_dict()
    created: set = set()  # tables made by these overrides: any key may be added (checked later)
    for key, value in items:
        _set_path(data, key, value, created)
    tops = {key.split(".", 1)[0] for key, _ in items}
    if "container" in tops and config.container is None or "box" in tops and config.box is None:
        _one_container(data, tops)  # a new container table replaces the other one
    _restate(data, [key for key, _ in items])
    return from_dict(data)


def _restate(data: dict, keys: list[str]) -> None:
    """After a change (``keys``: the dotted keys it set) to the dict of a configuration whose
    species may state their fill by ``mass_ratio`` or ``fill_fraction``: a species whose fill
    the change sets keeps that statement alone (the others cleared); every other stating
    species has its count cleared, to be derived again (:mod:`jaxdamp.cases.filling`: the
    change may have moved the primary's mass or the cavity)."""
    grains = data.get("grains")
    if not isinstance(grains, list) or "grains" in keys:
        return
    for i, sp in enumerate(grains):
        if not isinstance(sp, dict):
            continue
        chosen = [k for k in FILL_KEYS if f"grains.{i}.{k}" in keys]
        if chosen:
            sp.update({k: None for k in FILL_KEYS if k not in chosen})
        elif any(sp.get(k) is not None for k in FILL_KEYS[1:]):
            sp["count"] = None


def _set_path(data: dict, key: str, value: Any, created: set) -> None:
    parts = key.split(".")
    node: Any = data
    for i, part in enumerate(parts[:-1]):
        where = ".".join(parts[: i + 1])
        if isinstance(node, list):
            node = node[_index(part, node, where)]
            continue
        if part not in node:
            raise ConfigError(f"--set {key}: unknown key {where!r}")
        if node[part] is None:
            node[part] = {}
            created.add(id(node[part]))
        elif part in _MATERIAL_KEYS and isinstance(node[part], str):  # a named material:
            node[part] = {"name": node[part]}  # its fields may be set after the name
            created.add(id(node[part]))
        node = node[part]
    last = parts[-1]
    if isinstance(node, list):
        node[_index(last, node, key)] = value
    elif isinstance(node, dict):
        if last not in node and node and id(node) not in created:  # an existing table
            raise ConfigError(f"--set {key}: unknown key {last!r}; known: {sorted(node)}")
        node[last] = value
    else:
        raise ConfigError(f"--set {key}: {'.'.join(parts[:-1])!r} is not a table")


#: The keys whose value is a :class:`Material` (a table, or a name of the material table).
_MATERIAL_KEYS = ("material", "wall")


def _index(part: str, node: list, where: str) -> int:
    try:
        idx = int(part)
    except ValueError:
        raise ConfigError(f"--set: {where!r} indexes a list; use a number 0..{len(node)-1}") from None
    if not 0 <= idx < len(node):
        raise ConfigError(f"--set: {where!r} is out of range (list has {len(node)} entries)")
    return idx
