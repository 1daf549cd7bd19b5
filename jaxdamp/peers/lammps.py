"""LAMMPS as an independent DEM: jaxdamp's contact constants mapped onto its GRANULAR package,
the mapping's checks (small LAMMPS runs), input decks of the driven box, and running ``lmp``.

Used by the cross-check studies of the box (``experiments/lammps_crosscheck.py``), of the
cylinder (``experiments/lammps_cylinder.py``) and of friction under both tangential laws
(``experiments/lammps_friction.py``), the speed comparison
(``benchmarks/bench_lammps.py``) and ``tests/test_lammps_crosscheck.py``.

**The mapping** (``pair_style granular``; ``fix wall/gran granular``, three plane pairs):

* normal ``hertz/material E η_n0 ν``: LAMMPS' force ``(4/3) E_eff sqrt(R* ξ) ξ`` with
  ``1/E_eff = (1-ν_i²)/E_i + (1-ν_j²)/E_j`` is jaxdamp's ``k_n ξ^{3/2}``;
* ``damping viscoelastic``: LAMMPS' damping force ``η_n0 a m* ξ'`` with ``a = sqrt(R* ξ)``
  equals jaxdamp's ``γ_n sqrt(ξ) ξ'`` for ``η_n0 = γ_n / (m* sqrt(R*))``; with
  ``γ_n = (3/2) A k_n`` this is ``η_n0 = 2 A E*/m*`` — per contact type: grain–grain
  ``m* = m/2``, wall ``m* = m`` (so the wall prefactor is half the pair one);
* ``tangential linear_nohistory x_γt μ``: jaxdamp's ``F_t = γ_s sqrt(ξ) v_s`` capped at
  ``μ F_n`` (``x_γt = γ_s / g``; ``0 0`` when frictionless), ``limit_damping`` (the total
  normal force is clipped at zero, never attractive);
* the spring (``Config.tangential_law = "mindlin"``, :mod:`jaxdamp.physics.tangential`):
  ``tangential mindlin_rescale/force k_t x_γt μ`` — the history kept as the force, grown by
  ``−k_t a v_t dt``, turned into the contact plane at constant length and cut by ``a/a_old``
  when the contact shrinks, as jaxdamp's — with ``k_t = 8 G*`` given (LAMMPS multiplies it by
  ``a = sqrt(R* ξ)``; not ``NULL``, so no modulus LAMMPS derives for a wall enters) and
  ``x_γt = 4 G*/E*``, jaxdamp's ``γ_t = k_t γ_n/(1.5 k_n)`` over LAMMPS' normal damping
  (:func:`tangential`). Where they differ (not tuned): on slip LAMMPS sets the spring to the
  Coulomb force plus the dashpot's, jaxdamp scales both by one factor; LAMMPS takes ``k_t`` at
  the present overlap, jaxdamp at the step's mean; LAMMPS' pair torque has the lever arm
  ``R − ξ/2`` (its walls' ``R``), jaxdamp's ``R``. :func:`oblique_checks` measures the sum
  (oblique impacts in both codes at one time step);
* walls: the Debian build of LAMMPS (29 Sep 2021) builds the wall's effective modulus as
  ``E/(2(1-ν))`` instead of ``E/(2(1-ν²))``, i.e. walls ``1+ν`` = 1.3× too stiff (measured by
  :func:`static` and read in ``fix_wall_gran.cpp``). The walls are therefore given
  ``E_w = 2(1-ν) E*_pw`` (= ``E/(1+ν)`` for like materials), which makes their stiffness
  jaxdamp's ``(4/3) E*_pw sqrt(R)``.
* the cylinder's side (``fix wall/gran granular ... zcylinder R_c``): LAMMPS gives the concave
  wall the radius ``−2 R_c`` and the contact ``R* = R R_w / (R + R_w)`` = ``R / (1 − R/(2 R_c))``,
  jaxdamp's ``R* = R / (1 − R κ)`` with ``κ = 1/(2 R_c)``
  (:mod:`jaxdamp.physics.containers.cylinder`). In ``src/GRANULAR/fix_wall_gran.cpp`` of LAMMPS
  29 Sep 2021 Update 2 (Debian's ``lammps_20220106.git7586adbb6a+ds1`` source):
  ``FixWallGran::post_force``, lines 652–662 (``delxy = sqrt(x² + y²)``: the axis is x = y = 0;
  ``rwall = (delxy < cylradius) ? -2*cylradius : 2*cylradius``), and ``FixWallGran::granular``,
  lines 1148–1149 (``Reff = radius*rwall/(radius+rwall)``), 1171 and 1194 (``a = sqrt(δ Reff)``:
  the Hertz force ``E a δ``) and 1209 (viscoelastic damping ``η_n0 a m*``). Both stiffness and
  damping follow ``sqrt(R*)``, so the side wall gets ``η_n0 = γ_n(R*)/(m sqrt(R*))``
  (:attr:`Mapping.eta_side`; ``= 2 A E*/m`` like the planes for the paper's ``A``) and the same
  compensated modulus. Checked by :func:`static` (a grain pressed on the side by a lateral body
  force) and :func:`wall_collision` against jaxdamp's Hertz law at that ``R*``.

**The driven box** (:func:`box_deck`) is simulated in the box frame: the walls are static and
every grain feels ``g_eff = g - A_d ω² cos(ωt)`` along ``-z`` (``fix gravity`` with an
equal-style variable of ``time``): gravity plus the inertial force of the box's acceleration
(driven along another axis ``d``, ``Config.direction``: gravity and a second ``fix gravity``
of ``A_d ω² cos(ωt)`` along ``d``). The grains start with the settled bed's positions,
velocities and spins; snapshots carry spins, so the energy balance counts rotation.
Contact forces depend on relative positions and velocities only, so the contact dissipation is
the same as in the lab frame. The container is a :class:`Cavity`: the box's three plane pairs,
or the cylinder (floor and lid planes and ``zcylinder R_c``), whose axis LAMMPS fixes at
x = y = 0, so its LAMMPS frame is jaxdamp's box frame shifted by ``(−R_c, −R_c, 0)``.

**The paired comparison** (:func:`paired_bed` … :func:`analyse_amplitude`, shared by the
studies): each bed is poured by jaxdamp and is the initial state of both codes at the same dt;
per bed the codes' mean dissipation per period over a common steady window, across beds the
mean ± SE and the paired difference's Student-t 95 % interval.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import shutil
import subprocess
import time

import numpy as np

# ---------------------------------------------------------------------------------------------
# LAMMPS plumbing


def executable() -> str | None:
    """The LAMMPS executable (``lmp``, else ``lmp_serial``) or None."""
    return shutil.which("lmp") or shutil.which("lmp_serial")


def version(exe: str | None = None) -> str:
    """The version line of ``lmp -h`` (e.g. ``... - 29 Sep 2021 - Update 2``)."""
    exe = exe or executable()
    out = subprocess.run([exe, "-h"], capture_output=True, text=True, timeout=60).stdout
    for line in out.splitlines():
        if "Large-scale Atomic/Molecular" in line:
            return line.strip()
    return out.splitlines()[1].strip() if len(out.splitlines()) > 1 else out.strip()


class LammpsError(RuntimeError):
    pass


def run(script: str, name: str, workdir: str, exe: str | None = None) -> tuple[str, float]:
    """Write ``script`` to ``workdir/in.<name>``, run serial ``lmp`` on one thread, return
    (log text, wall seconds). Raises :class:`LammpsError` with the log's tail on failure."""
    exe = exe or executable()
    if exe is None:
        raise LammpsError("LAMMPS (`lmp`) is not on PATH; apt-get install lammps")
    workdir = os.path.abspath(workdir)  # lmp runs in it: a relative path would not resolve
    os.makedirs(workdir, exist_ok=True)
    inp = os.path.join(workdir, f"in.{name}")
    log = os.path.join(workdir, f"log.{name}")
    with open(inp, "w") as fh:
        fh.write(script)
    env = dict(os.environ, OMP_NUM_THREADS="1")
    t0 = time.perf_counter()
    proc = subprocess.run([exe, "-in", inp, "-log", log, "-screen", "none", "-nocite"],
                          cwd=workdir, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    text = open(log).read() if os.path.exists(log) else ""
    if proc.returncode != 0 or "ERROR" in text:
        tail = "\n".join((text or proc.stdout + proc.stderr).splitlines()[-25:])
        raise LammpsError(f"LAMMPS run {name!r} failed (rc {proc.returncode}):\n{tail}")
    return text, wall


def printed(log: str, tag: str) -> list[list[float]]:
    """Numbers of every ``print``-ed line that starts with ``tag`` (echo lines excluded)."""
    rows = []
    for line in log.splitlines():
        if line.startswith(tag + " "):
            try:
                rows.append([float(x) for x in line.split()[1:]])
            except ValueError:  # the echoed command itself
                continue
    return rows


def thermo_table(log: str, first: str = "Step") -> np.ndarray:
    """All thermo rows (numeric lines after a header starting with ``first``) of a log."""
    rows, on = [], False
    for line in log.splitlines():
        s = line.split()
        if s and s[0] == first:
            on = True
            continue
        if on:
            if line.startswith("Loop time") or not s:
                on = False
                continue
            try:
                rows.append([float(x) for x in s])
            except ValueError:
                on = False
    return np.asarray(rows)


# ---------------------------------------------------------------------------------------------
# The mapping


@dataclasses.dataclass(frozen=True)
class Mapping:
    """jaxdamp's contact constants for the reference system and their LAMMPS arguments.

    All SI. ``*_pp``: grain–grain (``R* = R/2``, ``m* = m/2``), ``*_pw``: grain–wall
    (``R* = R``, ``m* = m``, ``A`` = arithmetic mean of grain and wall A), ``*_side``: the
    container's side walls, of contact curvature ``curvature`` (``κ``: 0 for the box's planes,
    ``1/(2 R_c)`` for the cylinder) and ``R_side = R / (1 − R κ)``.
    """

    R: float
    density: float
    mass: float
    E: float
    nu: float
    A: float
    A_wall: float
    compliance: float
    wall_compliance: float
    dt: float
    E_star_pp: float
    E_star_pw: float
    k_pp: float
    k_pw: float
    gamma_pp: float
    gamma_pw: float
    eta_pp: float       # LAMMPS viscoelastic prefactor, pair_coeff [1/(s m)]
    eta_pw: float       # same, fix wall/gran
    E_wall_lammps: float  # modulus given to fix wall/gran (bug compensated)
    wall_bug_factor: float  # LAMMPS wall stiffness / intended, for the uncompensated input
    mu: float = 0.0         # Coulomb coefficient (pairs and walls: one material)
    xt_pp: float = 0.0      # tangential damping over normal damping, γ_s / g (pairs)
    xt_pw: float = 0.0      # the same for the walls
    curvature: float = 0.0  # the side walls' contact curvature κ [1/m] (jaxdamp's container)
    R_side: float = 0.0     # R* of a side-wall contact, R / (1 − R κ) [m]
    k_side: float = 0.0     # (4/3) E*_pw sqrt(R_side) [N m^-3/2]
    gamma_side: float = 0.0  # jaxdamp's damping coefficient at R_side [kg s^-1 m^-1/2]
    eta_side: float = 0.0   # LAMMPS viscoelastic prefactor of the side wall, γ/(m sqrt(R_side))
    xt_side: float = 0.0    # γ_s / g of the side wall
    tangential: str = "viscous"  # Config.tangential_law: "viscous" or "mindlin"
    kt_pp: float = 0.0      # Mindlin's k_t / a = 8 G* [Pa] (pairs; LAMMPS' k_t of mindlin)
    kt_pw: float = 0.0      # the same for the walls (G*_pw; planes and the side)
    xs_pp: float = 0.0      # the spring's dashpot over normal damping, γ_t / (g sqrt(ξ)) (pairs)
    xs_pw: float = 0.0      # the same for the plane walls
    xs_side: float = 0.0    # the same for the side wall

    def k_wall_lammps(self, E_fed: float, R_star: float | None = None) -> float:
        """Wall Hertz stiffness LAMMPS builds from ``E_fed`` (its ``E/(2(1-ν))`` formula) at
        the contact radius ``R_star`` (default ``R``: a plane)."""
        return 4.0 / 3.0 * E_fed / (2.0 * (1.0 - self.nu)) * math.sqrt(
            self.R if R_star is None else R_star)

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def build_mapping(cfg) -> Mapping:
    """The numbers jaxdamp uses (``jaxdamp.physics.model.build``) and their LAMMPS equivalents.

    One monodisperse species. The normal damping may be given as the paper's ``A`` or the
    thesis' ``γ_n`` (jaxdamp's damping coefficient ``g = γ_n + (3/2) A k`` either way); with
    friction, jaxdamp's ``F_t = γ_s sqrt(ξ) v_s`` capped at ``μ F_n`` is LAMMPS'
    ``tangential linear_nohistory x_γt μ`` with ``x_γt = γ_s / g`` (LAMMPS' tangential damping
    is ``x_γt`` times its normal damping ``η_n0 a m* = g sqrt(ξ)``). The side walls' constants
    are jaxdamp's at their contact radius ``R* = R / (1 − R κ)``, ``κ`` the container's
    contact curvature (:func:`jaxdamp.physics.containers.effective_radius`)."""
    from jaxdamp.physics.containers import container, effective_radius
    from jaxdamp.physics.model import build, contact_law
    from jaxdamp.physics.tangential import damping

    model, p = build(cfg)
    sp = cfg.grains[0]
    assert len(cfg.grains) == 1 and sp.radius_spread == 0.0, "one monodisperse species only"
    mat = sp.material
    R = float(np.asarray(p.radius)[0])
    m = float(np.asarray(p.mass)[0])
    law = contact_law(cfg)
    pair, wall = np.asarray(p.pair_table)[0, 0], np.asarray(p.wall_table)[0]  # mixed constants
    col = law.column
    A = float(pair[col("A")])
    assert cfg.mixing == "arithmetic"
    A_w = 2.0 * float(wall[col("A")]) - A  # the wall material's own A (arithmetic mixing)
    E_pp, E_pw = float(pair[col("E_star")]), float(wall[col("E_star")])
    c = 1.0 / (2.0 * E_pp)
    c_w = 1.0 / E_pw - c
    assert np.allclose(np.asarray(p.radius), R)
    mu = float(pair[col("mu")])
    assert float(wall[col("mu")]) == mu, "walls with another friction coefficient"
    R_pp, m_pp = R / 2.0, m / 2.0
    k_pp = 4.0 / 3.0 * E_pp * math.sqrt(R_pp)
    k_pw = 4.0 / 3.0 * E_pw * math.sqrt(R)
    g_pp = float(pair[col("gamma_n")]) + 1.5 * A * k_pp
    g_wall = lambda k: float(wall[col("gamma_n")]) + 1.5 * 0.5 * (A + A_w) * k  # noqa: E731
    g_pw = g_wall(k_pw)
    kappa = float(container(cfg).curvature(cfg))
    R_side = float(effective_radius(R, kappa))
    k_side = 4.0 / 3.0 * E_pw * math.sqrt(R_side)
    g_side = g_wall(k_side)
    xt = lambda row, g: float(row[col("gamma_s")]) / g if g > 0 else 0.0  # noqa: E731
    E, nu = mat.E * cfg.numerics.stiffness_scale, mat.nu
    # LAMMPS' pair builds E_eff = 1/(2(1-ν²)/E): must equal jaxdamp's from its compliance.
    assert abs(1.0 / (2 * (1 - nu**2) / E) - E_pp) < 1e-9 * E_pp, "compliance != (1-ν²)/E"
    E_wall = 2.0 * (1.0 - nu) * E_pw
    # the spring (tangential.stiffness, tangential.damping) on LAMMPS' contact radius
    # a = sqrt(R* ξ): k_t = 8 G* a and γ_t = (k_t / a) sqrt(R*) g sqrt(ξ) / (1.5 k_n)
    kt_pp, kt_pw = 8.0 * float(pair[col("G_star")]), 8.0 * float(wall[col("G_star")])
    xs = lambda kt, R_star, k: float(damping(kt * math.sqrt(R_star), k, 1.0))  # noqa: E731
    return Mapping(
        R=R, density=mat.density, mass=m, E=E, nu=nu, A=A, A_wall=A_w, compliance=c,
        wall_compliance=c_w, dt=float(p.dt), E_star_pp=E_pp, E_star_pw=E_pw, k_pp=k_pp,
        k_pw=k_pw, gamma_pp=g_pp, gamma_pw=g_pw, eta_pp=g_pp / (m_pp * math.sqrt(R_pp)),
        eta_pw=g_pw / (m * math.sqrt(R)), E_wall_lammps=E_wall,
        wall_bug_factor=(E / (2 * (1 - nu))) / E_pw, mu=mu, xt_pp=xt(pair, g_pp),
        xt_pw=xt(wall, g_pw), curvature=kappa, R_side=R_side, k_side=k_side, gamma_side=g_side,
        eta_side=g_side / (m * math.sqrt(R_side)), xt_side=xt(wall, g_side),
        tangential=cfg.tangential_law, kt_pp=kt_pp, kt_pw=kt_pw, xs_pp=xs(kt_pp, R_pp, k_pp),
        xs_pw=xs(kt_pw, R, k_pw), xs_side=xs(kt_pw, R_side, k_side),
    )


def tangential(mp: Mapping, contact: str = "pp") -> str:
    """The ``tangential ...`` keywords of a ``contact`` (``"pp"``: grain–grain, ``"pw"``: a
    plane wall, ``"side"``: the cylinder's side) for ``mp.tangential``: the viscous law as
    ``linear_nohistory x_γt μ``, the spring as ``mindlin_rescale/force k_t x_γt μ`` (history
    kept as the force, cut with the contact radius on unloading: :mod:`jaxdamp.physics.
    tangential`; ``k_t`` given, not ``NULL``, so that no modulus LAMMPS derives for a wall
    enters)."""
    if mp.tangential == "mindlin":
        kt = mp.kt_pp if contact == "pp" else mp.kt_pw
        xs = {"pp": mp.xs_pp, "pw": mp.xs_pw, "side": mp.xs_side}[contact]
        return f"tangential mindlin_rescale/force {kt!r} {xs!r} {mp.mu!r}"
    xt = {"pp": mp.xt_pp, "pw": mp.xt_pw, "side": mp.xt_side}[contact]
    return f"tangential linear_nohistory {xt!r} {mp.mu!r}"


def pair_coeff(mp: Mapping, eta: float | None = None) -> str:
    eta = mp.eta_pp if eta is None else eta
    return (f"pair_coeff * * hertz/material {mp.E!r} {eta!r} {mp.nu!r} {tangential(mp)} "
            "damping viscoelastic limit_damping")


def wall_args(mp: Mapping, eta: float | None = None, E_wall: float | None = None,
              contact: str = "pw") -> str:
    """``fix wall/gran`` arguments: the compensated modulus, the viscoelastic prefactor ``eta``
    (default: a plane's, ``mp.eta_pw``) and the tangential keywords of ``contact``
    (:func:`tangential`)."""
    eta = mp.eta_pw if eta is None else eta
    E_wall = mp.E_wall_lammps if E_wall is None else E_wall
    return (f"granular hertz/material {E_wall!r} {eta!r} {mp.nu!r} {tangential(mp, contact)} "
            "damping viscoelastic limit_damping")


def side_args(mp: Mapping, damped: bool = True, E_wall: float | None = None) -> str:
    """:func:`wall_args` of the side walls (``eta_side``, their tangential keywords;
    undamped: ``damped=False``)."""
    return wall_args(mp, mp.eta_side if damped else 0.0, E_wall, "side")


HEADER = """units si
atom_style sphere
atom_modify map array
boundary f f f
newton off
comm_modify vel yes
"""


# ---------------------------------------------------------------------------------------------
# Mapping checks (each a small LAMMPS run)


def pair_collision(mp: Mapping, v: float, workdir: str, exe=None) -> dict:
    """Two grains head-on at relative speed ``v``: restitution and overlap duration."""
    R, dt = mp.R, mp.dt
    gap = 5 * v * dt  # surfaces 5 steps apart
    x0 = R + gap / 2
    tc = 3.2 * (mp.mass / 2 / mp.k_pp) ** 0.4 * v**-0.2  # ~ elastic duration
    steps = int((gap / v + 3 * tc) / dt) + 20
    L = 4 * R + 10 * v * steps * dt
    script = HEADER + f"""
region sim block {-L!r} {L!r} {-L!r} {L!r} {-L!r} {L!r} units box
create_box 1 sim
create_atoms 1 single {-x0!r} 0.0 0.0 units box
create_atoms 1 single {x0!r} 0.0 0.0 units box
set type 1 diameter {2 * R!r} density {mp.density!r}
velocity all set 0.0 0.0 0.0 units box
set atom 1 vx {v / 2!r}
set atom 2 vx {-v / 2!r}
pair_style granular
{pair_coeff(mp)}
neighbor {0.3 * R!r} bin
neigh_modify delay 0 every 1 check yes
fix integ all nve/sphere
timestep {dt!r}
variable d equal sqrt((x[2]-x[1])^2+(y[2]-y[1])^2+(z[2]-z[1])^2)
variable v1 equal vx[1]
variable v2 equal vx[2]
variable m1 equal mass[1]
thermo_style custom step v_d v_v1 v_v2
thermo_modify format float %.17g
thermo 1
run {steps}
print "RESULT $(v_v1:%.17g) $(v_v2:%.17g) $(v_m1:%.17g)"
"""
    log, _ = run(script, f"pair_v{v:g}", workdir, exe)
    v1, v2, m1 = printed(log, "RESULT")[-1]
    tab = thermo_table(log)
    contact = int(np.sum(tab[:, 1] < 2 * R))
    assert tab[-1, 1] > 2 * R, "grains still in contact at the end"
    return dict(v=v, restitution=(v2 - v1) / v, duration=contact * dt,
                min_distance=float(tab[:, 1].min()), mass=m1)


def wall_collision(mp: Mapping, v: float, workdir: str, exe=None, Rc: float | None = None) -> dict:
    """One grain hitting a wall at ``v``: restitution and overlap duration. The floor
    (``fix wall/gran zplane``), or with ``Rc`` the concave side of a cylinder of radius ``Rc``
    (``zcylinder``, axis x = y = 0), hit radially along +x."""
    R, dt = mp.R, mp.dt
    k = mp.k_pw if Rc is None else mp.k_side
    tc = 3.2 * (mp.mass / k) ** 0.4 * v**-0.2
    steps = int(5 + 3 * tc / dt) + 20
    L = 4 * R + 2 * v * steps * dt
    if Rc is None:  # falling on the floor: the contact while z < R
        c, wall, sign = "z", 0.0, -1.0
        z0 = R + 5 * v * dt
        region = f"{-L!r} {L!r} {-L!r} {L!r} {-0.1 * R!r} {L!r}"
        at, vel = f"0.0 0.0 {z0!r}", f"0.0 0.0 {-v!r}"
        fix = f"{wall_args(mp)} zplane 0.0 NULL"
    else:  # outward onto the side at x = Rc: the contact while x > Rc − R
        c, wall, sign = "x", Rc, 1.0
        x0 = Rc - R - 5 * v * dt
        region = f"{-Rc - L!r} {Rc + L!r} {-Rc - L!r} {Rc + L!r} {-L!r} {L!r}"
        at, vel = f"{x0!r} 0.0 0.0", f"{v!r} 0.0 0.0"
        fix = f"{side_args(mp)} zcylinder {Rc!r}"
    script = HEADER + f"""
region sim block {region} units box
create_box 1 sim
create_atoms 1 single {at} units box
set type 1 diameter {2 * R!r} density {mp.density!r}
velocity all set {vel} units box
pair_style granular
{pair_coeff(mp)}
fix wall all wall/gran {fix}
fix integ all nve/sphere
timestep {dt!r}
variable v{c} equal v{c}[1]
variable {c} equal {c}[1]
thermo_style custom step v_{c} v_v{c}
thermo_modify format float %.17g
thermo 1
run {steps}
print "RESULT $(v_v{c}:%.17g)"
"""
    log, _ = run(script, f"wall_v{v:g}" if Rc is None else f"side_v{v:g}", workdir, exe)
    vc = printed(log, "RESULT")[-1][0]
    gap = sign * (wall - thermo_table(log)[:, 1])  # centre to wall
    assert gap[-1] > R, "grain still touching the wall at the end"
    return dict(v=v, restitution=-sign * vc / v, duration=int(np.sum(gap < R)) * dt)


#: The side of the resting cube of the oblique impacts [m] (both codes).
OBLIQUE_BOX = 0.08


def oblique_collision(mp: Mapping, kind: str, vn: float, vt: float, workdir: str,
                      exe=None) -> dict:
    """An oblique impact in LAMMPS: ``kind = "wall"``, one grain touching the floor (centre at
    ``z = R``) with velocity ``(vt, 0, −vn)``; ``"pair"``, two grains touching along x, grain 1
    moving ``(vn/2, 0, vt/2)`` and grain 2 the opposite. No spin at the start, no gravity, the
    time step ``mp.dt``, run until the contact has ended. Returns grain 1's final ``v`` and
    ``w`` (box frame of :func:`jaxdamp_oblique`)."""
    R, dt, L = mp.R, mp.dt, OBLIQUE_BOX
    m_eff, k = (mp.mass, mp.k_pw) if kind == "wall" else (mp.mass / 2, mp.k_pp)
    steps = int(4 * 3.2 * (m_eff / k) ** 0.4 * vn**-0.2 / dt) + 20
    r, v = _oblique_start(mp.R, kind, vn, vt, L)
    atoms = "\n".join(f"create_atoms 1 single {x!r} {y!r} {z!r} units box" for x, y, z in r)
    vels = "\n".join(f"set atom {i + 1} vx {a!r} vy {b!r} vz {c!r}"
                      for i, (a, b, c) in enumerate(v))
    wall = f"fix wall all wall/gran {wall_args(mp)} zplane 0.0 NULL" if kind == "wall" else ""
    script = HEADER + f"""
region sim block 0.0 {L!r} 0.0 {L!r} {-0.1 * R!r} {L!r} units box
create_box 1 sim
{atoms}
set type 1 diameter {2 * R!r} density {mp.density!r}
velocity all set 0.0 0.0 0.0 units box
{vels}
pair_style granular
{pair_coeff(mp)}
{wall}
neighbor {0.3 * R!r} bin
neigh_modify delay 0 every 1 check yes
fix integ all nve/sphere
timestep {dt!r}
compute om all property/atom omegax omegay omegaz
variable vx equal vx[1]
variable vy equal vy[1]
variable vz equal vz[1]
variable wx equal c_om[1][1]
variable wy equal c_om[1][2]
variable wz equal c_om[1][3]
thermo_style custom step v_vx v_vz v_wx v_wy v_wz
thermo {steps}
run {steps}
print "RESULT $(v_vx:%.17g) $(v_vy:%.17g) $(v_vz:%.17g) $(v_wx:%.17g) $(v_wy:%.17g) $(v_wz:%.17g)"
"""
    log, _ = run(script, f"oblique_{kind}_{vn:g}_{vt:g}", workdir, exe)
    out = np.asarray(printed(log, "RESULT")[-1])
    return dict(v=out[:3], w=out[3:], steps=steps)


def _oblique_start(R: float, kind: str, vn: float, vt: float, L: float):
    """Positions and velocities of :func:`oblique_collision` (box frame, a cube of side L)."""
    if kind == "wall":
        return [(L / 2, L / 2, R)], [(vt, 0.0, -vn)]
    return ([(L / 2 - R, L / 2, L / 2), (L / 2 + R, L / 2, L / 2)],
            [(vn / 2, 0.0, vt / 2), (-vn / 2, 0.0, -vt / 2)])


def jaxdamp_oblique(cfg, mp: Mapping, kind: str, vn: float, vt: float, steps: int) -> dict:
    """:func:`oblique_collision` in jaxdamp: the configuration ``cfg``'s grains and walls
    (its tangential law; a box configuration), one or two grains in the resting cube of
    :data:`OBLIQUE_BOX` without gravity, its JAX engine at LAMMPS' time step ``mp.dt`` for
    ``steps`` steps. Grain 1's final ``v``, ``w``."""
    import jax.numpy as jnp

    from jaxdamp.config import apply_overrides
    from jaxdamp.engine import driver
    from jaxdamp.physics.model import build

    n = 1 if kind == "wall" else 2
    L = OBLIQUE_BOX
    c = apply_overrides(cfg, {"grains.0.count": n, "gravity": 0.0, "box.Lx": L, "box.Ly": L,
                              "box.Lz": L, "container": None, "drive.amplitude": 0.0})
    model, params = build(c)
    params = dataclasses.replace(params, dt=jnp.asarray(mp.dt))
    r, v = (np.asarray(x, float)[None] for x in _oblique_start(mp.R, kind, vn, vt, L))
    q = np.zeros((1, n, 4))
    q[..., 0] = 1.0
    zero = np.zeros(1)
    b = driver.start(model, driver.batched(params), r, v, np.zeros_like(r), q, zero, zero,
                     engine="jax")
    b, _ = driver.advance(b, 1, steps)
    s = driver.take(b.states, 0)
    return dict(v=np.asarray(s.v)[0], w=np.asarray(s.w)[0])


def oblique_checks(cfg, mp: Mapping, workdir: str, exe=None, vn: float = 1.0,
                   ratios=(0.1, 0.5, 2.0)) -> list[dict]:
    """Oblique impacts (:func:`oblique_collision`) on the floor and of two grains at normal
    speed ``vn`` and tangential speeds ``ratio · vn`` — sticking, partly slipping, sliding
    throughout for steel's μ — in LAMMPS and in jaxdamp (:func:`jaxdamp_oblique`); per impact
    the rebound (grain 1: normal restitution, tangential velocity and spin against the ones
    before) of both and their largest difference over ``vn``."""
    rows = []
    for kind in ("wall", "pair"):
        for ratio in ratios:
            vt = ratio * vn
            lm = oblique_collision(mp, kind, vn, vt, workdir, exe)
            jd = jaxdamp_oblique(cfg, mp, kind, vn, vt, lm["steps"])
            axis_n, sn = (2, -1.0) if kind == "wall" else (0, 1.0)  # grain 1's normal speed
            axis_t, vt1 = (0, vt) if kind == "wall" else (2, vt / 2)
            vn1 = vn if kind == "wall" else vn / 2
            row = dict(kind=kind, vn=vn, vt=vt, steps=lm["steps"])
            for code, x in (("lammps", lm), ("jaxdamp", jd)):
                row[code] = dict(restitution=-sn * x["v"][axis_n] / vn1,
                                 tangential=x["v"][axis_t] / vt1,
                                 spin=float(x["w"][1] * mp.R / vt1))
            row["difference"] = float(np.max(np.abs(np.concatenate(
                [lm["v"] - jd["v"], (lm["w"] - jd["w"]) * mp.R]))) / vn)
            rows.append(row)
    return rows


WALLS = {  # name: (fix arguments, gravity direction pressing the grain onto that wall, axis, lo)
    "floor": ("zplane 0.0 {L}", "0 0 -1", 2, True),
    "lid": ("zplane 0.0 {L}", "0 0 1", 2, False),
    "x0": ("xplane 0.0 {L}", "-1 0 0", 0, True),
    "x1": ("xplane 0.0 {L}", "1 0 0", 0, False),
    "y0": ("yplane 0.0 {L}", "0 -1 0", 1, True),
    "y1": ("yplane 0.0 {L}", "0 1 0", 1, False),
}


def static(mp: Mapping, wall: str, workdir: str, g: float = 9.8, compensated=True,
                  duration: float = 0.1, exe=None, Rc: float | None = None) -> dict:
    """One grain pressed on ``wall`` by gravity, starting just touching; damped to rest.

    ``wall``: a plane of :data:`WALLS` in a cube of 2 cm, or ``"side"``: the concave side of a
    cylinder of radius ``Rc`` (``zcylinder``, axis x = y = 0), the grain at ``(Rc − R, 0)``
    pressed on it by a lateral body force ``g`` along +x (no floor). Returns the equilibrium
    overlap and jaxdamp's Hertz value ``(m g / k)^{2/3}``: ``k = (4/3) E*_pw sqrt(R*)`` with
    ``R* = R`` (planes) or ``mp.R_side`` (the side; there also ``hertz_plane``, the overlap on
    a plane, and ``ratio_plane``).
    """
    R, dt, L = mp.R, mp.dt, 0.02
    steps = int(duration / dt)
    E_w = mp.E_wall_lammps if compensated else mp.E
    if wall == "side":
        if Rc is None:
            raise ValueError("static(wall='side') needs the cylinder's radius Rc")
        fix, gdir, coord = f"{side_args(mp, E_wall=E_w)} zcylinder {Rc!r}", "1 0 0", "x"
        pos = [Rc - R, 0.0, L / 2]
        region = (f"{-Rc - 0.001!r} {Rc + 0.001!r} {-Rc - 0.001!r} {Rc + 0.001!r} -0.001 "
                  f"{L + 0.001!r}")
    else:
        fixarg, gdir, axis, lo = WALLS[wall]
        fix, coord = f"{wall_args(mp, E_wall=E_w)} {fixarg.format(L=repr(L))}", "xyz"[axis]
        pos = [L / 2] * 3
        pos[axis] = R if lo else L - R
        region = " ".join([f"-0.001 {L + 0.001!r}"] * 3)
    script = HEADER + f"""
region sim block {region} units box
create_box 1 sim
create_atoms 1 single {pos[0]!r} {pos[1]!r} {pos[2]!r} units box
set type 1 diameter {2 * R!r} density {mp.density!r}
velocity all set 0.0 0.0 0.0 units box
pair_style granular
{pair_coeff(mp)}
fix wall all wall/gran {fix}
fix grav all gravity {g!r} vector {gdir}
fix integ all nve/sphere
timestep {dt!r}
variable c equal {coord}[1]
variable v equal v{coord}[1]
thermo 0
run {steps}
print "RESULT $(v_c:%.17g) $(v_v:%.17g)"
"""
    log, _ = run(script, f"static_{wall}_{'comp' if compensated else 'raw'}", workdir, exe)
    c, vel = printed(log, "RESULT")[-1]
    hertz = (mp.mass * g / mp.k_pw) ** (2.0 / 3.0)
    if wall == "side":
        overlap = c - (Rc - R)
        side = (mp.mass * g / mp.k_side) ** (2.0 / 3.0)
        return dict(wall=wall, compensated=compensated, overlap=overlap, hertz=side,
                    ratio=overlap / side, speed=abs(vel), hertz_plane=hertz,
                    ratio_plane=overlap / hertz, R_star=mp.R_side, Rc=Rc)
    overlap = R - c if lo else c - (L - R)
    return dict(wall=wall, compensated=compensated, overlap=overlap, hertz=hertz,
                ratio=overlap / hertz, speed=abs(vel))


def mapping_checks(mp: Mapping, workdir: str, exe=None, speeds=(1.0, 5.0, 20.0),
                   walls=tuple(WALLS), Rc: float | None = None) -> dict:
    """All LAMMPS checks of the mapping against jaxdamp's force law (exact integration); with
    ``Rc``, also the cylinder's side (``"side"``: collisions at ``R* = mp.R_side``, and a
    ``"side"`` row of ``"static"``). The walls' references are of the paper's ``A``."""
    from jaxdamp.physics.restitution import collision

    out = {"pair": [], "wall": [], "static": []}
    if Rc is not None:
        out["side"] = []
    A_w = 0.5 * (mp.A + mp.A_wall)
    for v in speeds:
        r = pair_collision(mp, v, workdir, exe)
        ref = collision(mp.mass / 2, mp.R / 2, mp.E_star_pp, v, A=mp.A)
        r.update(ref_restitution=ref.restitution, ref_duration=ref.duration)
        out["pair"].append(r)
        w = wall_collision(mp, v, workdir, exe)
        ref = collision(mp.mass, mp.R, mp.E_star_pw, v, A=A_w)
        w.update(ref_restitution=ref.restitution, ref_duration=ref.duration)
        out["wall"].append(w)
        if Rc is not None:
            w = wall_collision(mp, v, workdir, exe, Rc=Rc)
            ref = collision(mp.mass, mp.R_side, mp.E_star_pw, v, A=A_w)
            plane = collision(mp.mass, mp.R, mp.E_star_pw, v, A=A_w)
            w.update(ref_restitution=ref.restitution, ref_duration=ref.duration,
                     plane_duration=plane.duration)
            out["side"].append(w)
    for wall in walls:
        out["static"].append(static(mp, wall, workdir, exe=exe))
    if Rc is not None:
        out["static"].append(static(mp, "side", workdir, exe=exe, Rc=Rc))
    out["static_uncompensated"] = static(mp, "floor", workdir, compensated=False, exe=exe)
    return out


# ---------------------------------------------------------------------------------------------
# The driven bed in LAMMPS (box frame)


@dataclasses.dataclass(frozen=True)
class Cavity:
    """The container as LAMMPS builds it: the floor at z = 0 and the lid at ``Lz`` (``fix
    wall/gran ... zplane``), and the sides: the box's ``xplane 0 Lx`` and ``yplane 0 Ly``
    (``shape = "box"``), or the cylinder's ``zcylinder radius``. Positions in LAMMPS' frame are
    jaxdamp's box-frame positions minus :attr:`origin`: zero for the box, ``(R_c, R_c, 0)``
    for the cylinder, whose axis LAMMPS fixes at x = y = 0 (``fix_wall_gran.cpp`` line 653)."""

    shape: str
    Lz: float
    Lx: float = 0.0
    Ly: float = 0.0
    radius: float = 0.0

    @property
    def origin(self) -> np.ndarray:
        """jaxdamp's box-frame point at LAMMPS' origin [m]."""
        Rc = self.radius if self.shape == "cylinder" else 0.0
        return np.array([Rc, Rc, 0.0])

    def bounds(self) -> tuple[tuple[float, float], ...]:
        """``(lo, hi)`` of the inside along x, y, z in LAMMPS' frame [m]."""
        if self.shape == "cylinder":
            return (-self.radius, self.radius), (-self.radius, self.radius), (0.0, self.Lz)
        return (0.0, self.Lx), (0.0, self.Ly), (0.0, self.Lz)

    def walls(self, mp: Mapping, damped: bool = True) -> str:
        """The ``fix wall/gran`` lines (undamped: ``damped=False``)."""
        eta = mp.eta_pw if damped else 0.0
        if self.shape == "cylinder":
            return (f"fix wz all wall/gran {wall_args(mp, eta)} zplane 0.0 {self.Lz!r}\n"
                    f"fix wc all wall/gran {side_args(mp, damped)} zcylinder {self.radius!r}")
        return "\n".join(f"fix w{x} all wall/gran {wall_args(mp, eta)} {x}plane 0.0 {L!r}"
                         for x, L in zip("xyz", (self.Lx, self.Ly, self.Lz)))

    def gaps(self, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distances of the centres ``r`` (N, 3; LAMMPS' frame) to the plane walls (the box:
        x, Lx − x, y, Ly − y, z, Lz − z; the cylinder: z, Lz − z) and to the curved side
        (``R_c − sqrt(x² + y²)``; none in the box), both flattened [m]."""
        z = [r[:, 2], self.Lz - r[:, 2]]
        if self.shape == "cylinder":
            return np.concatenate(z), self.radius - np.hypot(r[:, 0], r[:, 1])
        return (np.concatenate([r[:, 0], self.Lx - r[:, 0], r[:, 1], self.Ly - r[:, 1]] + z),
                np.zeros(0))


def cavity(where) -> Cavity:
    """The :class:`Cavity` of a configuration (its ``[box]`` or ``[container]``), of a
    :class:`jaxdamp.config.Box`, or ``where`` itself if it is one."""
    if isinstance(where, Cavity):
        return where
    if hasattr(where, "Lx"):  # a Box
        return Cavity("box", float(where.Lz), float(where.Lx), float(where.Ly))
    from jaxdamp.physics.containers import container

    shape = container(where).name
    if shape == "box":
        return cavity(where.box)
    if shape == "cylinder":
        c = where.container
        return Cavity("cylinder", float(c.Lz), radius=float(c.dimension("radius")))
    raise ValueError(f"container {shape!r}: no LAMMPS walls for it (box and cylinder only)")


def write_data(path: str, r: np.ndarray, v: np.ndarray, mp: Mapping, box, w=None) -> None:
    """A LAMMPS data file of the grains at box-frame positions ``r`` (written in LAMMPS'
    frame: ``r − origin`` of :func:`cavity` ``(box)``: a :class:`Cavity`, a ``Box`` or a
    configuration), velocities ``v`` and angular velocities ``w`` (zero when not given)."""
    cav = cavity(box)
    w = np.zeros_like(np.asarray(v)) if w is None else np.asarray(w)
    r = np.asarray(r)
    if cav.origin.any():
        r = r - cav.origin
    pad = 0.001
    (xl, xh), (yl, yh), (zl, zh) = cav.bounds()
    lines = ["LAMMPS data file: jaxdamp settled bed, box frame (floor at z = 0)"
             + ("" if not cav.origin.any() else ", shifted: the cylinder's axis at x = y = 0"),
             "", f"{len(r)} atoms", "1 atom types", "",
             f"{xl - pad!r} {xh + pad!r} xlo xhi", f"{yl - pad!r} {yh + pad!r} ylo yhi",
             f"{zl - pad!r} {zh + pad!r} zlo zhi", "", "Atoms # sphere", ""]
    lines += [f"{i + 1} 1 {2 * mp.R!r} {mp.density!r} {x!r} {y!r} {z!r}"
              for i, (x, y, z) in enumerate(r.tolist())]
    lines += ["", "Velocities", ""]
    lines += [f"{i + 1} {a!r} {b!r} {c!r} {x!r} {y!r} {z!r}"
              for i, ((a, b, c), (x, y, z)) in enumerate(zip(v.tolist(), w.tolist()))]
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")


def boundary_steps(n_periods: int, T: float, dt: float) -> list[int]:
    """Step nearest to every period boundary ``t = nT``, n = 0..n_periods."""
    return [int(round(n * T / dt)) for n in range(n_periods + 1)]


def box_deck(mp: Mapping, cfg, amplitude: float, data: str, dt: float | None = None,
             t0: float = 0.0, damped: bool = True) -> str:
    """The input deck of the driven container (:func:`cavity` of ``cfg``: the box or the
    cylinder) in the box frame, up to its first ``run``: the grains of the data file ``data``,
    the mapped pair and wall contacts (undamped: ``damped=False``), the time step (default
    ``mp.dt``) and the effective gravity of the drive ``z = amplitude cos(ω (t + t0))`` of
    ``cfg.frequency`` along ``cfg.direction``: vertical, one effective gravity ``g − A_d ω²
    cos ωt`` along −z; along another axis ``d``, gravity and a second body force ``A_d ω² cos ωt``
    along ``d`` (the inertial force of the box's acceleration ``−A_d ω² cos(ωt) d``)."""
    omega = 2 * math.pi * cfg.frequency
    eta_pp = mp.eta_pp if damped else 0.0
    phase = "time" if t0 == 0.0 else f"(time+{t0!r})"
    d = drive_axis(cfg)
    if d is None:
        body = (f"variable geff equal {cfg.gravity!r}-v_Ad*v_w^2*cos(v_w*{phase})\n"
                "fix grav all gravity v_geff vector 0 0 -1")
    else:
        body = (f"fix grav all gravity {cfg.gravity!r} vector 0 0 -1\n"
                f"variable ain equal v_Ad*v_w^2*cos(v_w*{phase})\n"
                f"fix drive all gravity v_ain vector {d[0]!r} {d[1]!r} {d[2]!r}")
    return HEADER + f"""
read_data {data}
pair_style granular
{pair_coeff(mp, eta_pp)}
{cavity(cfg).walls(mp, damped)}
neighbor {0.3 * mp.R!r} bin
neigh_modify delay 0 every 1 check yes
timestep {mp.dt if dt is None else dt!r}
# box frame: gravity plus the inertial force of the box acceleration -A w^2 cos(w t)
variable Ad equal {amplitude!r}
variable w equal {omega!r}
{body}
fix integ all nve/sphere
"""


def drive_axis(cfg) -> tuple[float, float, float] | None:
    """The unit drive axis of ``cfg`` (``Config.direction``), ``None`` for the vertical."""
    d = np.asarray(cfg.direction, float)
    d = d / np.linalg.norm(d)
    return None if np.allclose(d, (0.0, 0.0, 1.0)) else tuple(float(x) for x in d)


def bed_script(mp: Mapping, cfg, amplitude: float, steps: list[int], data: str, snapdir: str,
               damped: bool = True, thermo_every: int | None = None) -> str:
    """:func:`box_deck` run in segments ending at ``steps`` (the period boundaries), with a
    full-precision snapshot and the cumulative input work ``W`` printed at each boundary."""
    segs = []
    for n in range(1, len(steps)):
        segs.append(f"run {steps[n] - steps[n - 1]} pre no post no\n"
                    f"write_dump all custom {snapdir}/snap.{n}.txt {SNAP} "
                    "modify sort id format float %.17g\n"
                    f'print "BOUNDARY {n} $(step) $(v_W:%.17g)"')
    te = thermo_every or max(1, int(round(1.0 / cfg.frequency / 200 / mp.dt)))
    d = drive_axis(cfg)
    v_d = "vcm(all,z)" if d is None else "+".join(
        f"{c!r}*vcm(all,{x})" for c, x in zip(d, "xyz") if c != 0.0)
    return box_deck(mp, cfg, amplitude, data, damped=damped) + f"""\
# power of the inertial force, its running mean over every step since step 0
variable P equal mass(all)*v_Ad*v_w^2*cos(v_w*time)*({v_d})
fix pin all ave/time 1 1 1 v_P ave running
variable W equal f_pin*(step+1)*dt
variable zc equal xcm(all,z)
variable vz equal vcm(all,z)
thermo_style custom step time v_zc v_vz v_W
thermo_modify format float %.17g norm no lost error
thermo {te}
write_dump all custom {snapdir}/snap.0.txt {SNAP} modify sort id format float %.17g
run 0 post no
print "BOUNDARY 0 $(step) $(v_W:%.17g)"
""" + "\n".join(segs) + "\n"


#: the columns of a snapshot (:func:`read_snap`)
SNAP = "id x y z vx vy vz omegax omegay omegaz"


def read_snap(path: str) -> np.ndarray:
    """(N, 10): the columns :data:`SNAP` of a ``write_dump`` file (older snapshots: 7, no
    spins)."""
    return np.loadtxt(path, skiprows=9)


def mechanical_energy(snap: np.ndarray, mp: Mapping, box, g: float) -> dict:
    """Box-frame kinetic (translation and, where the snapshot has spins, rotation: ``I =
    (2/5) m R²``), gravitational and elastic energy of a snapshot (LAMMPS' frame and
    stiffness; ``box``: the :func:`cavity` of the run, or what makes it). The tangential
    springs' energy (``mindlin``) is LAMMPS' contact history, not in a snapshot: left out
    (its size: the summary of ``experiments/lammps_friction.py``)."""
    from scipy.spatial import cKDTree

    cav = cavity(box)
    r, v = snap[:, 1:4], snap[:, 4:7]
    ke = 0.5 * mp.mass * float(np.sum(v * v))
    if snap.shape[1] >= 10:
        ke += 0.5 * 0.4 * mp.mass * mp.R**2 * float(np.sum(snap[:, 7:10] ** 2))
    pe = mp.mass * g * float(np.sum(r[:, 2]))
    el = 0.0
    pairs = cKDTree(r).query_pairs(2 * mp.R, output_type="ndarray")
    if len(pairs):
        d = np.linalg.norm(r[pairs[:, 0]] - r[pairs[:, 1]], axis=1)
        xi = np.clip(2 * mp.R - d, 0.0, None)
        el += 0.4 * mp.k_pp * float(np.sum(xi**2.5))
    k_w = mp.k_wall_lammps(mp.E_wall_lammps)
    planes, side = cav.gaps(r)
    xi = np.clip(mp.R - planes, 0.0, None)
    el += 0.4 * k_w * float(np.sum(xi**2.5))
    if len(side):  # the concave side: LAMMPS' stiffness at R* = R R_w/(R + R_w), R_w = −2 R_c
        R_w = -2.0 * cav.radius
        k_s = mp.k_wall_lammps(mp.E_wall_lammps, mp.R * R_w / (mp.R + R_w))
        xi = np.clip(mp.R - side, 0.0, None)
        el += 0.4 * k_s * float(np.sum(xi**2.5))
    return dict(kinetic=ke, gravitational=pe, elastic=el)


def driven_bed(mp: Mapping, cfg, amplitude: float, r0, v0, n_periods: int, workdir: str,
               damped: bool = True, exe=None, tag: str = "", w0=None) -> dict:
    """Run the driven bed for ``n_periods`` periods from ``r0, v0`` and spins ``w0`` (default
    none; box frame).

    Returns per-boundary cumulative input work, energies and dissipation, the thermo series
    and the wall time. ``tag`` names the bed (its working directory ``bed_A<cm>cm<tag>``).
    """
    name = f"bed_A{amplitude * 100:g}cm{tag}" + ("" if damped else "_undamped")
    sub = os.path.abspath(os.path.join(workdir, name))  # the deck names its files by path
    snapdir = os.path.join(sub, "snaps")
    os.makedirs(snapdir, exist_ok=True)
    for f in os.listdir(snapdir):
        os.remove(os.path.join(snapdir, f))
    data = os.path.join(sub, "bed.data")
    cav = cavity(cfg)
    write_data(data, np.asarray(r0), np.asarray(v0), mp, cav, w0)
    T = 1.0 / cfg.frequency
    steps = boundary_steps(n_periods, T, mp.dt)
    script = bed_script(mp, cfg, amplitude, steps, data, snapdir, damped=damped)
    log, wall = run(script, name, sub, exe)
    rows = np.asarray(printed(log, "BOUNDARY"))
    assert len(rows) == n_periods + 1, f"{len(rows)} boundaries printed, {n_periods + 1} expected"
    assert np.array_equal(rows[:, 1].astype(int), steps)
    W = rows[:, 2]
    en = [mechanical_energy(read_snap(os.path.join(snapdir, f"snap.{n}.txt")), mp, cav,
                            cfg.gravity) for n in range(n_periods + 1)]
    E = np.array([e["kinetic"] + e["gravitational"] + e["elastic"] for e in en])
    D = W - (E - E[0])
    loop = sum(float(x) for x in re.findall(r"Loop time of ([0-9.eE+-]+)", log))
    tab = thermo_table(log)
    return dict(steps=np.asarray(steps), t=np.asarray(steps) * mp.dt, W=W, E=E, D=D,
                elastic=np.array([e["elastic"] for e in en]),
                kinetic=np.array([e["kinetic"] for e in en]),
                thermo=tab, wall=wall, loop_time=loop, n_steps=steps[-1])


# ---------------------------------------------------------------------------------------------
# The paired comparison: one bed in both codes, across beds (the cross-check studies)


def jaxdamp_periods(cfg, n_periods: int, progress=False) -> dict:
    """``jaxdamp.studies.runner.run`` of the driven system ``cfg`` (its duration covering
    ``n_periods`` periods), its cumulative granular loss ``D`` at the period boundaries
    ``t = nT`` (n = 0…``n_periods``), timings, energy-balance figures and its settled bed."""
    from jaxdamp.physics.energy import granular_loss
    from jaxdamp.studies import runner

    T = 1.0 / cfg.frequency
    t0 = time.perf_counter()
    res = runner.run(cfg, progress=progress, snapshots=False, echo=None)
    elapsed = time.perf_counter() - t0
    rec = res.records
    t = np.concatenate([[0.0], rec["t"]])
    loss = np.concatenate([[0.0], granular_loss(rec["work"])])
    tb = np.arange(n_periods + 1) * T
    if t[-1] < tb[-1] - 1e-12:
        raise RuntimeError(f"jaxdamp records end at {t[-1]} s < last boundary {tb[-1]} s")
    D = np.interp(tb, t, loss)
    inp = np.concatenate([[0.0], rec["work"][:, 0]])
    resid = np.asarray(rec["balance_residual"])
    return dict(config=cfg, result=res, t=tb, D=D, dt=float(res.summary["dt"]),
                wall=float(res.summary["wall_time"]), elapsed=elapsed,
                balance=float(res.summary["balance_error"]),
                residual=float(np.max(np.abs(resid))), residual_final=float(resid[-1]),
                input_final=float(inp[-1]), bed=res.bed, bed_r=np.asarray(res.bed.r),
                bed_v=np.asarray(res.bed.v), bed_w=np.asarray(res.bed.w),
                settled=bool(res.bed.settled),
                bed_height=float(res.bed.height), bed_max_speed=float(res.bed.max_speed),
                records={k: np.asarray(rec[k]) for k in ("t", "z_cm", "z_box")})


# one bed in both codes, kept (raw/beds/) for a re-run with the same settings
JD_SCALARS = ("dt", "wall", "elapsed", "balance", "residual", "residual_final", "input_final",
              "settled", "bed_height", "bed_max_speed")
LM_ARRAYS = ("steps", "t", "W", "E", "D", "elastic", "kinetic", "thermo")
LM_SCALARS = ("wall", "loop_time", "n_steps")


def save_bed(path: str, key: dict, jd: dict, lm: dict) -> None:
    """One bed of :func:`paired_bed` (both codes' results) as ``path`` (.npz), under ``key``."""
    import json

    os.makedirs(os.path.dirname(path), exist_ok=True)
    meta = dict(key=key, jd={k: jd[k] for k in JD_SCALARS}, lm={k: lm[k] for k in LM_SCALARS})
    arrays = {f"lm_{k}": np.asarray(lm[k]) for k in LM_ARRAYS}
    arrays.update(jd_t=jd["t"], jd_D=jd["D"], bed_r=jd["bed_r"], bed_v=jd["bed_v"],
                  bed_w=jd["bed_w"],
                  **{f"rec_{k}": v for k, v in jd["records"].items()})
    tmp = path + ".tmp.npz"
    np.savez(tmp, meta=json.dumps(meta), **arrays)
    os.replace(tmp, path)


def load_bed(path: str, key: dict, cfg):
    """``(jd, lm)`` of a bed stored with this ``key`` (``jd["config"]``: ``cfg``), else None."""
    import json

    if not os.path.exists(path):
        return None
    with np.load(path) as z:
        meta = json.loads(str(z["meta"]))
        if meta["key"] != key:
            return None
        jd = dict(meta["jd"], t=z["jd_t"], D=z["jd_D"], bed_r=z["bed_r"], bed_v=z["bed_v"],
                  bed_w=z["bed_w"] if "bed_w" in z.files else np.zeros_like(z["bed_v"]),
                  records={k: z[f"rec_{k}"] for k in ("t", "z_cm", "z_box")})
        lm = dict(meta["lm"], **{k: z[f"lm_{k}"] for k in LM_ARRAYS})
    jd["config"] = cfg
    return jd, lm


def paired_bed(cfg, n_periods: int, key: dict, path: str, raw: str, exe, progress: bool,
               log, tag: str = "") -> dict:
    """One bed poured by jaxdamp (``cfg``: a driven system and its ``numerics.seed``), driven
    for ``n_periods`` at ``cfg.drive.amplitude`` in jaxdamp and, from the same settled state,
    in LAMMPS (in ``raw``); stored as ``path`` under ``key`` (the settings it must match) and
    reused from there by a re-run with the same ``key`` (``tag``: more of the LAMMPS run's
    directory name, for beds of one amplitude and seed in several variants)."""
    amplitude, seed = cfg.drive.amplitude, int(cfg.numerics.seed)
    got = load_bed(path, key, cfg)
    if got is not None:
        jd, lm = got
        log(f"A_d = {amplitude * 100:g} cm, seed {seed}: reused {path}")
        return dict(seed=seed, jd=jd, lm=lm, mp=build_mapping(cfg), reused=True)
    # jaxdamp first: its settled bed is the initial state of both codes
    log(f"A_d = {amplitude * 100:g} cm, seed {seed}: jaxdamp ...")
    jd = jaxdamp_periods(cfg, n_periods, progress=progress)
    mp = build_mapping(cfg)
    assert abs(mp.dt - jd["dt"]) < 1e-15
    log(f"  jaxdamp: dt = {jd['dt']:.6g} s, {jd['wall']:.1f} s stepping "
        f"({jd['elapsed']:.1f} s with settling); LAMMPS ...")
    lm = driven_bed(mp, cfg, amplitude, jd["bed_r"], jd["bed_v"], n_periods, raw, exe=exe,
                    tag=f"_seed{seed}{tag}", w0=jd["bed_w"])
    log(f"  LAMMPS: {lm['wall']:.1f} s")
    save_bed(path, key, jd, lm)
    return dict(seed=seed, jd=jd, lm=lm, mp=mp, reused=False)


def closure(bed: dict, amplitude: float, periods: int, raw: str, exe=None) -> dict:
    """LAMMPS' energy accounting on ``bed`` (of :func:`paired_bed`) undamped for ``periods``:
    the input work minus Δ(kinetic + gravitational + elastic) at the period boundaries (``D``,
    0 when exact) and its largest value relative to the largest ``|ΔE|``."""
    jd = bed["jd"]
    clo = driven_bed(bed["mp"], jd["config"], amplitude, jd["bed_r"], jd["bed_v"], periods, raw,
                     damped=False, exe=exe, tag=f"_seed{bed['seed']}", w0=jd.get("bed_w"))
    dE = float(np.max(np.abs(clo["E"] - clo["E"][0])))
    return dict(amplitude=amplitude, seed=bed["seed"], periods=periods, D=clo["D"].tolist(),
                W=clo["W"].tolist(), E=clo["E"].tolist(),
                relative=float(np.max(np.abs(clo["D"])) / max(dE, 1e-300)))


def phase_average(t, y, T, n_bins=50, t0=0.0):
    """Mean of ``y`` in ``n_bins`` phase bins of the drive over samples with ``t >= t0``."""
    t, y = np.asarray(t), np.asarray(y)
    keep = t >= t0
    ph = np.mod(t[keep] / T, 1.0)
    idx = np.minimum((ph * n_bins).astype(int), n_bins - 1)
    s = np.bincount(idx, y[keep], n_bins)
    c = np.bincount(idx, None, n_bins)
    return (np.arange(n_bins) + 0.5) / n_bins, s / np.maximum(c, 1)


def within_run(d) -> tuple[float, float, float]:
    """Mean, standard deviation and the within-run standard error (serial correlation
    allowed for: :func:`jaxdamp.analysis.uncertainty.ar1_standard_error`) of a per-period
    series."""
    from jaxdamp.analysis.uncertainty import ar1_standard_error

    d = np.asarray(d, float)
    sd = float(d.std(ddof=1)) if len(d) > 1 else math.nan
    return float(d.mean()), sd, ar1_standard_error(d)


KEY = "granular_loss_per_cycle"


def window(dl, dj, s: dict, T: float):
    """``(start, stationary, detections)`` of one bed: the window common to both codes'
    per-period series (MSER on both, never before the transient:
    :func:`jaxdamp.analysis.stats.shared_window`) and each code's own detection."""
    from jaxdamp.analysis import stats as jstats

    series = [{"t_start": np.arange(len(dl)) * T, KEY: np.asarray(x)} for x in (dl, dj)]
    kw = dict(min_discard=s["transient"], min_keep=min(5, s["periods"]))
    w = jstats.shared_window(series, keys=(KEY,), **kw)
    return int(w["start"]), bool(w["stationary"]), [jstats.detect(x, **kw) for x in series]


#: Units of the attributes in data.h5 (of the root and of each bed).
ATTR_UNITS = dict(lammps_wall_time="s", lammps_loop_time="s", jaxdamp_wall_time="s",
                  jaxdamp_elapsed="s", jaxdamp_residual_max="J", jaxdamp_residual_per_period="J",
                  z_cm_difference="m", z_cm_swing="m", window_start="periods",
                  checks_wall_time="s", bed_max_speed_range="m/s")
UNITS = dict(dissipation_per_period="J", cumulative_dissipation="J", input_work="J",
             mechanical_energy="J", elastic_energy="J", boundary_time="s", z_cm_phase="m")


def stored_bed(b: dict, s: dict, T: float):
    """One bed of :func:`paired_bed` as ``data.h5`` keeps it (a
    :class:`jaxdamp.io.study.Group`): per code the dissipation per period and the values at
    the period boundaries (``z_cm_phase``: jaxdamp's phase-averaged height); as attributes
    the window, times, residuals and the phase-averaged heights' comparison."""
    from jaxdamp.io.study import Group

    lm, jd = b["lm"], b["jd"]
    dl, dj = np.diff(lm["D"]), np.diff(jd["D"])
    start, stationary, _ = window(dl, dj, s, T)
    tab, rec = lm["thermo"], jd["records"]
    _, zl = phase_average(tab[:, 1], tab[:, 2], T, t0=start * T)
    lift = np.asarray(rec["z_box"]) if drive_axis(jd["config"]) is None else 0.0  # box frame
    _, zj = phase_average(rec["t"], np.asarray(rec["z_cm"]) - lift, T, t0=start * T)
    attrs = dict(seed=b["seed"], window_start=start, stationary=stationary,
                 lammps_wall_time=lm["wall"], lammps_loop_time=lm["loop_time"],
                 jaxdamp_wall_time=jd["wall"], jaxdamp_elapsed=jd["elapsed"],
                 jaxdamp_balance_error=jd["balance"], jaxdamp_residual_max=jd["residual"],
                 jaxdamp_residual_per_period=jd["residual_final"] / (len(jd["t"]) - 1),
                 bed_settled=bool(jd["settled"]), reused=bool(b["reused"]),
                 z_cm_difference=float(np.max(np.abs(zl - zj))),
                 z_cm_swing=float(zl.max() - zl.min()))
    return Group({"lammps": Group(dict(
        dissipation_per_period=dl, cumulative_dissipation=lm["D"], input_work=lm["W"],
        mechanical_energy=lm["E"], elastic_energy=lm["elastic"], boundary_time=lm["t"],
        thermo=tab)), "jaxdamp": Group(dict(
            dissipation_per_period=dj, cumulative_dissipation=jd["D"], boundary_time=jd["t"],
            z_cm_phase=zj))}, attrs)


def driven_case(amplitude: float, beds: list[dict], s: dict, T: float) -> dict:
    """The beds of one amplitude (:func:`paired_bed`), each with its :func:`stored_bed` form,
    the mapping, the granulate's mass ``m`` and ``E_max = 4 m A_d² ω²`` [J] (SPEC §4)."""
    for b in beds:
        b["stored"] = stored_bed(b, s, T)
    mp = beds[0]["mp"]
    m_gran = mp.mass * beds[0]["jd"]["config"].grains[0].count
    omega = 2 * math.pi * beds[0]["jd"]["config"].frequency
    return dict(beds=beds, mp=mp, e_max=4 * m_gran * amplitude**2 * omega**2, m=m_gran)


def analyse_bed(g, s: dict, T: float, dt: float) -> dict:
    """One bed in both codes (:func:`stored_bed`, or read back): its attributes, the window,
    each code's mean over it, their difference and the within-run figures."""
    from jaxdamp.analysis.uncertainty import lag1_autocorrelation

    lm, jd = g["lammps"], g["jaxdamp"]
    start, stationary, dets = window(lm["dissipation_per_period"], jd["dissipation_per_period"],
                                     s, T)
    dl, dj = lm["dissipation_per_period"][start:], jd["dissipation_per_period"][start:]
    ml, sl, el = within_run(dl)
    mj, sj, ej = within_run(dj)
    close = np.abs(dl - dj) <= 0.01 * np.abs(dj)
    half, n0 = max(1, len(dl) // 2), s["transient"]
    steps = int(round(lm["boundary_time"][-1] / dt))
    return dict(g.attrs, start=start, kept=len(dl), stationary=stationary,
                start_l=dets[0].period, start_j=dets[1].period,
                ml=ml, sl=sl, el=el, mj=mj, sj=sj, ej=ej, diff=ml - mj, comb=math.hypot(el, ej),
                rel=(ml - mj) / mj, lag_l=lag1_autocorrelation(dl), lag_j=lag1_autocorrelation(dj),
                corr=float(np.corrcoef(dl, dj)[0, 1]) if len(dl) > 2 else math.nan,
                first_apart=int(np.argmin(close)) if not close.all() else len(dl),
                transient_l=float(lm["cumulative_dissipation"][n0]),
                transient_j=float(jd["cumulative_dissipation"][n0]),
                el_max=float(np.max(lm["elastic_energy"])),
                halves_l=(float(dl[:half].mean()), float(dl[half:].mean())),
                halves_j=(float(dj[:half].mean()), float(dj[half:].mean())), dt=dt, steps=steps,
                us_l=g.attrs["lammps_wall_time"] / steps * 1e6,
                us_j=g.attrs["jaxdamp_wall_time"] / steps * 1e6)


def analyse_amplitude(A: float, beds: list[dict], e_max: float) -> dict:
    """Across the beds (:func:`analyse_bed`) of one amplitude: each code's mean ± SE of the
    beds' means, and the per-bed (paired) difference LAMMPS − jaxdamp with its Student-t 95 %
    interval; the unpaired Welch interval of the two codes' bed means alongside."""
    from jaxdamp.analysis import stats as jstats

    ok = np.array([r["stationary"] for r in beds])
    ml, mj = (np.array([r[k] for r in beds]) for k in ("ml", "mj"))
    el, ej, ed = (jstats.across(x, stationary=ok) for x in (ml, mj, ml - mj))
    wd, wh = jstats.welch(ml[ok], mj[ok])
    sd = lambda x: float(np.std(x[ok], ddof=1)) if ok.sum() > 1 else math.nan  # noqa: E731
    return dict(A=A, e_max=e_max, beds=beds, R=len(beds), n=ed.n,
                ml=el.mean, sel=el.se, mj=ej.mean, sej=ej.se, sdl=sd(ml), sdj=sd(mj),
                within_l=float(np.mean([r["el"] for r in beds])),
                within_j=float(np.mean([r["ej"] for r in beds])),
                d=ed.mean, sed=ed.se, hw=ed.ci95, welch_d=wd, welch_hw=wh,
                agree=bool(np.isfinite(ed.ci95) and abs(ed.mean) <= ed.ci95),
                rel=ed.mean / ej.mean, rel_hw=ed.ci95 / ej.mean)


def within(r: dict, target: float) -> bool:
    """Whether the paired 95 % interval of a row ``r`` of :func:`analyse_amplitude` lies
    inside ±``target`` (relative) of jaxdamp's mean: the cross-check studies' agreement rule."""
    return bool(np.isfinite(r["rel_hw"]) and abs(r["rel"]) + r["rel_hw"] <= target)


def analyse_group(A: float, g, s: dict, T: float) -> dict:
    """:func:`analyse_amplitude` of an amplitude's group of ``data.h5`` (:func:`write_case`)."""
    beds = [analyse_bed(g[f"bed_{k}"], s, T, g.attrs["dt"]) for k in range(len(g["seed"]))]
    return analyse_amplitude(A, beds, g.attrs["e_max"])


def write_case(h, A: float, c: dict, r: dict, seeds) -> None:
    """One amplitude into the open ``data.h5`` ``h``: the group ``A_<cm>cm`` with the mapping,
    the across-bed figures ``r`` (:func:`analyse_amplitude`), the per-bed means and each bed
    of ``c`` (:func:`driven_case`) as ``bed_<k>``; LAMMPS' thermo series of bed 0 only."""
    import json

    from jaxdamp.io.common import put

    g = h.create_group(f"A_{A * 100:g}cm")
    g.attrs["mapping"] = json.dumps(c["mp"].as_dict())
    g.attrs.update(dt=c["mp"].dt, e_max=c["e_max"], granulate_mass=c["m"],
                   n_stationary=r["n"], lammps_mean=r["ml"], lammps_se=r["sel"],
                   jaxdamp_mean=r["mj"], jaxdamp_se=r["sej"], difference_mean=r["d"],
                   difference_se=r["sed"], difference_ci95=r["hw"],
                   welch_difference=r["welch_d"], welch_ci95=r["welch_hw"],
                   agree=r["agree"])
    bs = r["beds"]
    g.create_dataset("seed", data=np.asarray(seeds))
    g.create_dataset("stationary", data=np.asarray([x["stationary"] for x in bs]))
    put(g, "window_start", [x["start"] for x in bs], "periods")
    for key, name in (("ml", "lammps/mean_per_bed"), ("mj", "jaxdamp/mean_per_bed"),
                      ("diff", "difference_per_bed")):
        put(g, name, [x[key] for x in bs], "J per period")
    for k, b in enumerate(c["beds"]):
        gb = g.create_group(f"bed_{k}")
        gb.attrs["config"] = b["jd"]["config"].to_json()
        gb.attrs.update(b["stored"].attrs)
        for code in ("lammps", "jaxdamp"):
            for name, data in b["stored"][code].items():
                if name != "thermo":
                    put(gb, f"{code}/{name}", data, UNITS[name], **(
                        {"note": "every period from t = 0; the window starts at "
                                 "window_start"} if name == "dissipation_per_period"
                        else {}))
                elif k == 0:  # the figure's bed (the others' stay in raw/beds)
                    gb.create_dataset(f"{code}/thermo", data=data, compression="gzip",
                                      shuffle=True).attrs["columns"] = \
                        "step time z_cm vz_cm W (box frame)"
