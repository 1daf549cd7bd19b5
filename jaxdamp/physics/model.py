"""From a :class:`~jaxdamp.config.Config` to JAX pytrees: ``Model`` (static), ``Params``, ``State``.

``Params`` and ``State`` are dataclasses registered with JAX whose every field is an array, so
a batch of systems is the same pytree with a leading batch axis and ``vmap`` maps over it
(frequency sweeps, ``Lz`` scans, ...). ``Model`` holds what fixes array shapes and code paths
(number of grains, system kind, contact law, species, neighbour-list geometry); it is hashable
and static under ``jit``.

Contact constants are computed once, here (JaxDEM's ``MaterialTable``): the law's constants of
every pair of species, ``Params.pair_table`` ``(S, S, F)``, and of every species against the
walls, ``Params.wall_table`` ``(S, F)``, with the mixing rule applied only in
:meth:`jaxdamp.physics.contact.Law.mix`. Grains are stored species after species
(:meth:`Model.species_index`); per contact both engines only look the row up and form the
radius- and mass-dependent part (:meth:`jaxdamp.physics.contact.Law.pair_jax`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.config import Config
from jaxdamp.physics.contact import LAWS, Law, calibrate_wall_row
from jaxdamp.physics.containers import container, effective_radius
from jaxdamp.physics.excitation import base_motion, random_lines
from jaxdamp.physics.structure import cell_dofs as structure_cell_dofs
from jaxdamp.physics.structure import internal

#: Names of the cumulative work channels, in order (all in J).
#:   input:       work done on the system by the base through spring and damper (S1) or by the
#:                moving walls on the grains (S2)
#:   primary_damping: viscous loss in the primary's damper C (S1)
#:   pp_normal, pp_friction, pw_normal, pw_friction: granular losses, grain–grain / grain–wall
#:   drag:        loss to the settling drag (zero while driving)
#:   pw_floor, pw_lid, pw_side: the grain–wall losses (``pw_normal + pw_friction``) split by
#:                the wall they occur at: the floor, the lid, the container's side walls. A
#:                breakdown, not a term of the energy balance (:data:`LOSSES` are its terms).
#:   pp_slip, pw_slip: the slip's part of ``pp_friction``, ``pw_friction`` (the rest is the
#:                tangential dashpot's) with the tangential spring (``tangential_law =
#:                "mindlin"``, :mod:`jaxdamp.physics.tangential`); zero for the viscous law. A
#:                breakdown, not a term of the balance.
#:   spring_stiffness: the energy the tangential springs lose as their stiffness
#:                ``8 G* sqrt(R* ξ)`` changes with the overlap, at constant force (no
#:                force does this work; at a contact's end it is the spring's whole remaining
#:                energy): the no-slip Mindlin model's own term of the balance, of either
#:                sign; zero for the viscous law.
CHANNELS = ("input", "primary_damping", "pp_normal", "pp_friction", "pw_normal", "pw_friction",
            "drag", "pw_floor", "pw_lid", "pw_side", "pp_slip", "pw_slip", "spring_stiffness")
N_CHANNELS = len(CHANNELS)
CH = {name: i for i, name in enumerate(CHANNELS)}
#: The loss channels of the energy balance ``W_input = ΔE + Σ losses`` (names).
LOSS_CHANNELS = ("primary_damping", "pp_normal", "pp_friction", "pw_normal", "pw_friction",
                 "drag", "spring_stiffness")
#: Their places in :data:`CHANNELS` (an index array: ``work[..., LOSSES]``).
LOSSES = np.array([CH[k] for k in LOSS_CHANNELS])
#: The channels whose power is, wholly or in part, the energy of one step divided by ``dt``
#: (the springs' slip and stiffness work: what a step did, not a rate at an instant), and
#: where that part is: each channel's source channel, or -1. The engines integrate such a
#: part as ``power × dt`` of the step it belongs to; the trapezoid rule of the other powers
#: would put half of it a step late.
INCREMENT_OF = np.array([{"pp_friction": CH["pp_slip"], "pw_friction": CH["pw_slip"],
                          "pp_slip": CH["pp_slip"], "pw_slip": CH["pw_slip"],
                          "spring_stiffness": CH["spring_stiffness"]}.get(k, -1)
                         for k in CHANNELS])
#: The wall groups every engine reports apart (contact counts ``n_floor``, ``n_lid``,
#: ``n_side`` and the channels ``pw_floor``, ``pw_lid``, ``pw_side``).
WALL_GROUPS = ("floor", "lid", "side")


def pytree_dataclass(cls):
    """Frozen dataclass registered as a JAX pytree whose fields are all data (arrays)."""
    cls = dataclass(frozen=True)(cls)
    names = [f.name for f in dataclasses.fields(cls)]
    return jax.tree_util.register_dataclass(cls, data_fields=names, meta_fields=[])


@dataclass(frozen=True)
class Model:
    """Static description of a system: shapes and code paths (hashable, a ``jit`` static arg).

    Attributes:
      n: number of grains.
      system: ``"primary"`` (S1) or ``"driven"`` (S2).
      law: the contact law's name (:data:`jaxdamp.physics.contact.LAWS`).
      cutoff: neighbour-list cutoff ``2 R_max + skin`` [m].
      skin: neighbour-list skin [m]; the list is rebuilt once a grain moved more than skin/2.
      species: grain count of each species, in order (grains are stored species after
        species); per-species records use it. Empty means one species of ``n`` grains.
      dofs: degrees of freedom of the primary structure (S1; 1 for the 1-DOF primary and for
        S2): more than one selects the structure's matrix equations
        (:mod:`jaxdamp.physics.structure`).
      precision: ``numerics.precision``, the floating-point type of the JAX engine's contact
        laws (:data:`jaxdamp.physics.contact.PRECISIONS`): ``"float64"`` or ``"float32"``.
      container: the container's name (:data:`jaxdamp.physics.containers.CONTAINERS`).
      cells: the damper's identical cells (``Config.cells``); within each species the grains
        are stored cell after cell (:meth:`cell_index`), ``species`` counting all cells'.
      cell_dofs: where each cell's degree of freedom sits in the engines' order
        (:func:`jaxdamp.physics.structure.cell_dofs`: 0 the box, ``p`` ``State.y[p - 1]``);
        empty: every cell on the box's (:meth:`dofs_of_cells`).
      tangential: the tangential law's name (``Config.tangential_law``,
        :data:`jaxdamp.validation.TANGENTIAL_LAWS`); ``"mindlin"`` gives the state its
        springs (:class:`State`).
    """

    n: int
    system: str
    law: str
    cutoff: float
    skin: float
    species: tuple[int, ...] = ()
    dofs: int = 1
    precision: str = "float64"
    container: str = "box"
    cells: int = 1
    cell_dofs: tuple[int, ...] = ()
    tangential: str = "viscous"

    @property
    def springs(self) -> bool:
        """Whether the contacts carry tangential springs with history (``"mindlin"``)."""
        return self.tangential == "mindlin"

    def species_slices(self) -> tuple[slice, ...]:
        """Index range of every species in the grain arrays (at least one, possibly empty)."""
        counts = self.species or (self.n,)
        starts = np.cumsum((0,) + tuple(counts))
        return tuple(slice(int(a), int(b)) for a, b in zip(starts[:-1], starts[1:]))

    def species_index(self) -> np.ndarray:
        """Species of every grain, ``(N,)`` int32 (the row of the contact tables)."""
        counts = self.species or (self.n,)
        return np.repeat(np.arange(len(counts), dtype=np.int32), counts)

    def cell_index(self) -> np.ndarray:
        """Cell of every grain, ``(N,)`` int32 (:func:`cell_of`)."""
        return cell_of(self.species or (self.n,), self.cells)

    def dofs_of_cells(self) -> np.ndarray:
        """Each cell's degree of freedom in the engines' order, ``(cells,)`` int64
        (:attr:`cell_dofs`, zeros where it is empty)."""
        return np.array(self.cell_dofs or (0,) * self.cells, np.int64)


def cell_positions(z, y, model: Model):
    """Where each cell's container is along the axis ``e`` [m] (or how fast it moves, from the
    velocities): ``(cells,)`` from the box's ``z`` and the structure's other degrees of freedom
    ``y`` (:attr:`Model.cell_dofs`); ``z`` itself where every cell is on the box's."""
    if not model.cell_dofs:
        return z
    return jnp.concatenate([jnp.reshape(z, (1,)), y])[jnp.asarray(model.dofs_of_cells())]


def grain_positions_of_boxes(z, y, model: Model):
    """:func:`cell_positions` of every grain's cell, ``(N,)`` (``z`` where every cell is on
    the box's degree of freedom)."""
    if not model.cell_dofs:
        return z
    return cell_positions(z, y, model)[jnp.asarray(model.cell_index())]


def cell_of(counts, cells: int) -> np.ndarray:
    """Cell of every grain, ``(N,)`` int32, of species of ``counts`` grains each (all cells'
    together, a multiple of ``cells``) stored species after species and, within a species, cell
    after cell: ``0 … 0 1 … 1 … k−1`` in every species."""
    return np.concatenate(
        [np.repeat(np.arange(cells, dtype=np.int32), int(c) // cells) for c in counts]
        or [np.zeros(0, np.int32)])


@pytree_dataclass
class Params:
    """Every number the step needs, as arrays (vmappable). Units SI.

    Grain arrays have shape ``(N,)``; the contact tables ``pair_table`` ``(S, S, F)`` (species
    ``s`` against species ``t``) and ``wall_table`` ``(S, F)`` (species against the walls) hold
    the law's mixed constants in the columns :attr:`jaxdamp.physics.contact.Law.columns` (Hertz:
    ``γ_s`` [kg s^-1 m^-1/2], ``μ`` [-], ``E*`` [Pa], ``γ_n`` [kg s^-1 m^-1/2], ``A`` [s]);
    ``section`` ``(G,)`` the container's section (:mod:`jaxdamp.physics.containers`; the box:
    ``(Lx, Ly)`` [m]) and ``Lz`` its inner height, floor to lid [m];
    all else is scalar (per system). ``omega`` = 2πf [rad/s]; ``U`` base amplitude (S1) [m]; ``amplitude`` box amplitude (S2) [m];
    ``z_offset`` box position about which it moves (S2) [m]; ``drag`` settling drag rate [1/s];
    ``t_window`` start of the analysis window [s]; ``ex, ey, ez`` the unit vector of the
    excitation axis (``Config.direction``), along which the box and the primary move;
    ``lines`` ``(L, 3)`` the random base motion's lines ``(ω_k, c_k, s_k)`` and ``shock_a``
    [m/s²], ``shock_t0``, ``shock_T`` [s] the shock pulse (:mod:`jaxdamp.physics.excitation`;
    one zero line and ``shock_T = 0`` when absent); ``s_M``, ``s_Minv``, ``s_K``, ``s_C``
    ``(n, n)``, ``s_r``, ``s_b`` ``(n,)`` the primary structure in the engines' order, the box's
    degree of freedom first (:func:`jaxdamp.physics.structure.internal`; ``n = 1`` for the
    1-DOF primary, whose equation uses ``M, K, C``). ``origin`` ``(N, 2)`` [m]: the box-frame
    ``(x, y)`` of the corner of every grain's cell (:func:`cell_origins`; zeros for one cell):
    the walls see a grain at its box-frame position less its cell's origin.
    """

    radius: jnp.ndarray
    mass: jnp.ndarray
    inertia: jnp.ndarray
    pair_table: jnp.ndarray
    wall_table: jnp.ndarray
    section: jnp.ndarray
    Lz: jnp.ndarray
    gravity: jnp.ndarray
    M: jnp.ndarray
    K: jnp.ndarray
    C: jnp.ndarray
    U: jnp.ndarray
    amplitude: jnp.ndarray
    omega: jnp.ndarray
    z_offset: jnp.ndarray
    dt: jnp.ndarray
    drag: jnp.ndarray
    t_window: jnp.ndarray
    ex: jnp.ndarray
    ey: jnp.ndarray
    ez: jnp.ndarray
    lines: jnp.ndarray
    shock_a: jnp.ndarray
    shock_t0: jnp.ndarray
    shock_T: jnp.ndarray
    s_M: jnp.ndarray
    s_Minv: jnp.ndarray
    s_K: jnp.ndarray
    s_C: jnp.ndarray
    s_r: jnp.ndarray
    s_b: jnp.ndarray
    origin: jnp.ndarray


@pytree_dataclass
class State:
    """The dynamical state of one system at time ``t`` (after a completed step).

    Grains, shapes ``(N, 3)`` (``q``: ``(N, 4)`` unit quaternions ``(w, x, y, z)``):
    ``r`` position [m], ``v`` velocity [m/s], ``w`` angular velocity [rad/s], ``a`` and
    ``alpha`` the accelerations at ``t`` [m/s², rad/s²].
    Box (scalars): ``z``, ``zd``, ``zdd`` position [m], velocity, acceleration of the floor
    along the excitation axis ``e`` (the box's corner is at ``e z``); ``y``, ``yd``, ``ydd``
    ``(dofs - 1,)`` the primary structure's other degrees of freedom (empty for one).
    ``power`` [W] and ``work`` [J], shape ``(N_CHANNELS,)``: the channel powers at ``t`` and
    their time integrals (trapezoid rule) since the run started (see :data:`CHANNELS`).
    ``power_cell`` [W] and ``work_cell`` [J], shape ``(cells,)``: the granular loss
    (``pp_normal + pp_friction + pw_normal + pw_friction``) of each cell of the damper and its
    integral, the same rule (no pair spans two cells, so the cells' losses sum to the
    damper's).
    ``e_elastic`` [J] elastic contact energy at ``t``; ``e_start`` [J] total mechanical energy
    when accounting started; ``f_floor_lid``, ``f_box`` [N] vertical force of the grains on
    floor + lid and on the whole box along ``e`` at ``t``; ``n_floor``, ``n_lid`` grains
    touching them, ``n_side`` contacts with the side walls (a grain in a corner of the box
    touches two);
    ``z_max``, ``z_min`` [m] box extrema since ``t_window``; ``step`` steps taken.

    The contacts' history (tangential springs, ``Model.tangential = "mindlin"``,
    :mod:`jaxdamp.physics.tangential`): ``spring_pair`` ``(N, K, 3)`` [N] the spring's force of
    grain ``i``'s contact with its partner ``spring_partner[i, k]`` ``(N, K)`` (int32; the
    neighbour list the history was written against, padded with ``N``; a rebuilt list takes
    the history over by pair identity, :mod:`jaxdamp.engine.history`); ``spring_wall``
    ``(N, 2 + W, 3)`` [N] of its contact with each wall (floor, lid, the sides); ``e_spring``
    [J] their elastic energy (a part of ``e_elastic``). Under the viscous law the three arrays
    are empty (``(N, 0, 3)``, ``(N, 0)``, ``(N, 0, 3)``) and ``e_spring`` is 0: nothing to
    carry.
    """

    r: jnp.ndarray
    v: jnp.ndarray
    w: jnp.ndarray
    q: jnp.ndarray
    a: jnp.ndarray
    alpha: jnp.ndarray
    z: jnp.ndarray
    zd: jnp.ndarray
    zdd: jnp.ndarray
    y: jnp.ndarray
    yd: jnp.ndarray
    ydd: jnp.ndarray
    t: jnp.ndarray
    step: jnp.ndarray
    power: jnp.ndarray
    work: jnp.ndarray
    power_cell: jnp.ndarray
    work_cell: jnp.ndarray
    e_elastic: jnp.ndarray
    e_start: jnp.ndarray
    f_floor_lid: jnp.ndarray
    f_box: jnp.ndarray
    n_floor: jnp.ndarray
    n_lid: jnp.ndarray
    n_side: jnp.ndarray
    z_max: jnp.ndarray
    z_min: jnp.ndarray
    spring_pair: jnp.ndarray
    spring_partner: jnp.ndarray
    spring_wall: jnp.ndarray
    e_spring: jnp.ndarray


# ---------------------------------------------------------------------------------------------
# Config -> arrays


def grain_radii(config: Config) -> np.ndarray:
    """Radii of all grains [m], shape ``(N,)``, species after species and, within a species,
    cell after cell (``Config.cells``); spreads drawn with the seed, in that order (one cell:
    the draws of a one-cell damper)."""
    rng = np.random.default_rng(config.numerics.seed)
    out = []
    for sp in config.grains:
        n = config.cells * sp.count
        r = np.full(n, sp.radius, dtype=np.float64)
        if sp.radius_spread > 0:
            r = sp.radius * (1.0 + sp.radius_spread * rng.uniform(-1.0, 1.0, n))
        out.append(r)
    return np.concatenate(out) if out else np.zeros(0)


def grain_species(config: Config) -> np.ndarray:
    """Species index of every grain, shape ``(N,)`` (every cell's grains)."""
    return np.concatenate(
        [np.full(config.cells * sp.count, i, dtype=np.int32)
         for i, sp in enumerate(config.grains)]
        or [np.zeros(0, np.int32)]
    )


def grain_cell(config: Config) -> np.ndarray:
    """Cell index of every grain, shape ``(N,)`` int32 (:func:`cell_of`: within each species,
    cell after cell)."""
    return cell_of([config.cells * sp.count for sp in config.grains], config.cells)


def neighbour_cutoff(config: Config, radii: np.ndarray) -> float:
    """``Model.cutoff`` [m]: ``2 R_max + skin``, ``skin = numerics.skin R_max``."""
    r_max = float(radii.max()) if len(radii) else 0.0
    return 2.0 * r_max + config.numerics.skin * r_max


def cell_origins(config: Config, radii: np.ndarray) -> np.ndarray:
    """The box-frame corners ``(k, 2)`` [m] of the ``k = Config.cells`` cells: side by side
    along the box frame's ``x`` axis at the pitch ``w + gap``, ``w`` the width of the
    container's section along ``x`` (its ``extent``) and ``gap = w + 2 cutoff``
    (:func:`neighbour_cutoff`). Facing walls of neighbouring cells are then ``w + 2 cutoff``
    apart, farther than any engine lists a pair (centres closer than ``cutoff + 0.05 skin`` in
    the JAX engine, than ``cutoff + 2 R_max`` in the native and device kernels at their widest
    skin), so no neighbour list ever holds a pair across cells. The first cell is at the
    origin (a one-cell damper unchanged)."""
    x0, x1, _, _ = container(config).extent(config)
    width = x1 - x0
    pitch = 2.0 * width + 2.0 * neighbour_cutoff(config, radii)
    out = np.zeros((config.cells, 2))
    out[:, 0] = pitch * np.arange(config.cells)
    return out


def damper_extent(config: Config, radii: np.ndarray) -> tuple[float, float, float, float]:
    """The bounding rectangle ``(x0, x1, y0, y1)`` [m] of every cell's section, box frame
    (the container's ``extent`` for one cell; figures and export)."""
    x0, x1, y0, y1 = container(config).extent(config)
    origins = cell_origins(config, radii)
    return (x0 + float(origins[:, 0].min()), x1 + float(origins[:, 0].max()),
            y0 + float(origins[:, 1].min()), y1 + float(origins[:, 1].max()))


def cell_outlines(config: Config, radii: np.ndarray, z0: float = 0.0) -> list[np.ndarray]:
    """Every cell's edges as 3-D polylines [m] (the container's ``outline`` at each cell's
    corner, :func:`cell_origins`; floor at ``z0``)."""
    lines = container(config).outline(config, z0)
    return [line + np.array([ox, oy, 0.0]) for ox, oy in cell_origins(config, radii)
            for line in lines]


def contact_law(config: Config) -> Law:
    """The configuration's contact law (:data:`jaxdamp.physics.contact.LAWS`)."""
    return LAWS[config.contact_law]


def contact_tables(config: Config) -> tuple[np.ndarray, np.ndarray]:
    """The contact constants of the configuration, computed once (the only place the mixing
    rule is applied): ``pair_table`` ``(S, S, F)`` and ``wall_table`` ``(S, F)`` in the
    columns of the law (:attr:`jaxdamp.physics.contact.Law.columns`). Each species' calibration uses
    its own mean radius; the walls' uses the first species' (unless the materials fix a
    ``calibration_radius``). With ``wall_damping = "calibrated"`` every species' wall row is
    re-damped to its own grain–wall restitution at ``v_ref``
    (:func:`jaxdamp.physics.contact.calibrate_wall_row`)."""
    law = contact_law(config)
    lam = config.numerics.stiffness_scale
    bodies = [law.material(sp.material, sp.radius, lam) for sp in config.grains]
    S, F = len(bodies), len(law.columns)
    pair, wall = np.zeros((S, S, F)), np.zeros((S, F))
    if S:
        walls = law.material(config.wall_material, config.grains[0].radius, lam)
        for s in range(S):
            wall[s] = law.mix(bodies[s], walls, config.mixing)
            for t in range(S):
                pair[s, t] = law.mix(bodies[s], bodies[t], config.mixing)
        if config.wall_damping == "calibrated":  # each species against the wall, at v_ref
            w = container(config).wall(config)
            for s, sp in enumerate(config.grains):
                src = w if w is not None and w.restitution is not None else sp.material
                m = sp.material.density * 4.0 / 3.0 * np.pi * sp.radius**3
                wall[s] = calibrate_wall_row(law, wall[s], src.restitution, src.v_ref, m,
                                             sp.radius)
    return pair, wall


def build(config: Config, radii: np.ndarray | None = None) -> tuple[Model, Params]:
    """Turn a (validated) configuration into the static ``Model`` and the array ``Params``."""
    if radii is None:
        radii = grain_radii(config)
    species = grain_species(config)
    n = len(radii)
    mass = np.zeros(n)
    for i, sp in enumerate(config.grains):
        sel = species == i
        mass[sel] = sp.material.density * 4.0 / 3.0 * np.pi * radii[sel] ** 3
    pair_table, wall_table = contact_tables(config)

    r_max = float(radii.max()) if n else 0.0
    skin = config.numerics.skin * r_max
    cutoff = neighbour_cutoff(config, radii)
    structure = internal(config) if config.system == "primary" else None
    vessel = container(config)
    model = Model(
        n=n, system=config.system, law=config.contact_law, cutoff=cutoff, skin=skin,
        species=tuple(int(config.cells * sp.count) for sp in config.grains),
        dofs=len(structure["s_r"]) if structure else 1,
        precision=config.numerics.precision, container=vessel.name, cells=config.cells,
        cell_dofs=_cell_dofs(config) if structure else (),
        tangential=config.tangential_law,
    )
    prim = config.primary
    shock = config.shock if config.system == "primary" else None
    f64 = lambda x: jnp.asarray(x, dtype=jnp.float64)  # noqa: E731
    params = Params(
        radius=f64(radii),
        mass=f64(mass),
        inertia=f64(0.4 * mass * radii**2),
        pair_table=f64(pair_table),
        wall_table=f64(wall_table),
        section=f64(vessel.section(config)),
        Lz=f64(vessel.height(config)),
        gravity=f64(config.gravity),
        M=f64(prim.M if prim else 1.0),
        K=f64(prim.K if prim else 0.0),
        C=f64(prim.C if prim else 0.0),
        U=f64(prim.U if prim else 0.0),
        amplitude=f64(config.drive.amplitude if config.drive else 0.0),
        omega=f64(config.omega),
        z_offset=f64(0.0),
        dt=f64(config_dt(config, radii)),
        drag=f64(0.0),
        t_window=f64((1.0 - config.numerics.analysis_window) * config.numerics.duration),
        **{k: f64(x) for k, x in zip(("ex", "ey", "ez"), excitation_axis(config))},
        lines=f64(random_lines(config)),
        shock_a=f64(shock.peak if shock else 0.0),
        shock_t0=f64(shock.start if shock else 0.0),
        shock_T=f64(shock.duration if shock else 0.0),
        **{k: f64(v) for k, v in (structure or _no_structure()).items()},
        origin=f64(cell_origins(config, radii)[model.cell_index()]),
    )
    return model, params


def _cell_dofs(config: Config) -> tuple[int, ...]:
    """:attr:`Model.cell_dofs`: empty where every cell is on the box's degree of freedom."""
    dofs = tuple(int(d) for d in structure_cell_dofs(config))
    return dofs if any(dofs) else ()


def _no_structure() -> dict:
    """The structure fields of a system without a primary (S2): one inert degree of freedom."""
    one = np.ones((1, 1))
    return dict(s_M=one, s_Minv=one, s_K=0 * one, s_C=0 * one, s_r=np.ones(1), s_b=np.zeros(1))


def excitation_axis(config: Config) -> np.ndarray:
    """The unit vector of ``config.direction``: the axis of the base or box motion."""
    d = np.asarray(config.direction, dtype=np.float64)
    return d / np.linalg.norm(d)


def impact_speed(config: Config) -> float:
    """The largest expected impact speed [m/s] that sets the collision time: ``numerics.v_impact``,
    and for a driven box (S2) at least ``2 A_d ω``, the speed at which a grain riding with one
    wall meets the other (at 70 Hz and A_d = 3 cm that is 26 m/s; collisions are then
    ``(26/1)^{1/5} = 1.9×`` shorter than at 1 m/s)."""
    v = config.numerics.v_impact
    if config.system == "driven" and config.drive is not None:
        v = max(v, 2.0 * config.drive.amplitude * config.omega)
    return v


def collision_time_limit(config: Config, radii: np.ndarray) -> float:
    """Collision time [s] of the contact law (:attr:`jaxdamp.physics.contact.Law.collision_time`) of the
    stiffest, lightest contact at :func:`impact_speed`.

    Checks the smallest grain of every species against a like grain and against a wall — the
    container's most curved wall, where a concave wall's effective radius makes the contact
    stiffer (docs/physics.md §3); the shortest wins. (A small grain against a larger one collides longer than
    against a like grain, so unlike pairs never set the limit.)
    """
    if len(radii) == 0:
        return math.inf
    law = contact_law(config)
    pair, wall = contact_tables(config)
    species = grain_species(config)
    v = impact_speed(config)
    kappa = container(config).curvature(config)  # a concave wall: the stiffest wall contact
    t_c = math.inf
    for i, sp in enumerate(config.grains):
        sel = species == i
        if not sel.any():
            continue
        r = float(radii[sel].min())
        m = sp.material.density * 4.0 / 3.0 * math.pi * r**3
        t_c = min(t_c, law.collision_time(pair[i, i], 0.5 * m, 0.5 * r, v))
        t_c = min(t_c, law.collision_time(wall[i], m, effective_radius(r, kappa), v))
    return t_c


def config_dt(config: Config, radii: np.ndarray) -> float:
    """The time step [s]: ``numerics.dt`` or, if ``None``, ``t_c / dt_per_collision``."""
    if config.numerics.dt is not None:
        return config.numerics.dt
    t_c = collision_time_limit(config, radii)
    if not math.isfinite(t_c):  # empty box: resolve the drive and the primary's period
        return 1.0 / (2000.0 * max(config.frequency, primary_frequency(config) or 0.0))
    return t_c / config.numerics.dt_per_collision


def primary_frequency(config: Config) -> float | None:
    """Undamped natural frequency ``sqrt(K/M)/2π`` of the primary [Hz] (S1), else ``None``."""
    if config.primary is None or config.primary.K <= 0:
        return None
    return math.sqrt(config.primary.K / config.primary.M) / (2 * math.pi)


def grain_mass(config: Config) -> float:
    """Total mass of the granulate [kg], all cells' (mean radii; exact masses are in
    ``Params.mass``)."""
    return config.cells * sum(
        sp.count * sp.material.density * 4.0 / 3.0 * math.pi * sp.radius**3 for sp in config.grains
    )


def base_series(config, t) -> tuple[np.ndarray, np.ndarray]:
    """The base motion ``(u [m], u' [m/s])`` of ``config`` (S1) at the times ``t`` [s] (NumPy
    arrays): :func:`jaxdamp.physics.excitation.base_motion` evaluated on the host, e.g. the
    input of an FRF estimate from recorded samples."""
    _, p = build(config)
    u, ud = jax.vmap(lambda s: base_motion(s, p))(jnp.asarray(t, dtype=jnp.float64))
    return np.asarray(u), np.asarray(ud)
