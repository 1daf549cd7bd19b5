"""LAMMPS as an independent DEM: jaxdamp's contact constants mapped onto its GRANULAR package,
the mapping's checks (small LAMMPS runs), input decks of the driven box, and running ``lmp``.

Used by the cross-check study (``experiments/lammps_crosscheck.py``), the speed comparison
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
* walls: the Debian build of LAMMPS (29 Sep 2021) builds the wall's effective modulus as
  ``E/(2(1-ν))`` instead of ``E/(2(1-ν²))``, i.e. walls ``1+ν`` = 1.3× too stiff (measured by
  :func:`static` and read in ``fix_wall_gran.cpp``). The walls are therefore given
  ``E_w = 2(1-ν) E*_pw`` (= ``E/(1+ν)`` for like materials), which makes their stiffness
  jaxdamp's ``(4/3) E*_pw sqrt(R)``.

**The driven box** (:func:`box_deck`) is simulated in the box frame: the walls are static and
every grain feels ``g_eff = g - A_d ω² cos(ωt)`` along ``-z`` (``fix gravity`` with an
equal-style variable of ``time``): gravity plus the inertial force of the box's acceleration.
Contact forces depend on relative positions and velocities only, so the contact dissipation is
the same as in the lab frame.
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
    (``R* = R``, ``m* = m``, ``A`` = arithmetic mean of grain and wall A).
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

    def k_wall_lammps(self, E_fed: float) -> float:
        """Wall Hertz stiffness LAMMPS builds from ``E_fed`` (its ``E/(2(1-ν))`` formula)."""
        return 4.0 / 3.0 * E_fed / (2.0 * (1.0 - self.nu)) * math.sqrt(self.R)

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def build_mapping(cfg) -> Mapping:
    """The numbers jaxdamp uses (``jaxdamp.physics.model.build``) and their LAMMPS equivalents.

    One monodisperse species. The normal damping may be given as the paper's ``A`` or the
    thesis' ``γ_n`` (jaxdamp's damping coefficient ``g = γ_n + (3/2) A k`` either way); with
    friction, jaxdamp's ``F_t = γ_s sqrt(ξ) v_s`` capped at ``μ F_n`` is LAMMPS'
    ``tangential linear_nohistory x_γt μ`` with ``x_γt = γ_s / g`` (LAMMPS' tangential damping
    is ``x_γt`` times its normal damping ``η_n0 a m* = g sqrt(ξ)``)."""
    from jaxdamp.physics.model import build, contact_law

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
    g_pw = float(wall[col("gamma_n")]) + 1.5 * 0.5 * (A + A_w) * k_pw
    xt = lambda row, g: float(row[col("gamma_s")]) / g if g > 0 else 0.0  # noqa: E731
    E, nu = mat.E * cfg.numerics.stiffness_scale, mat.nu
    # LAMMPS' pair builds E_eff = 1/(2(1-ν²)/E): must equal jaxdamp's from its compliance.
    assert abs(1.0 / (2 * (1 - nu**2) / E) - E_pp) < 1e-9 * E_pp, "compliance != (1-ν²)/E"
    E_wall = 2.0 * (1.0 - nu) * E_pw
    return Mapping(
        R=R, density=mat.density, mass=m, E=E, nu=nu, A=A, A_wall=A_w, compliance=c,
        wall_compliance=c_w, dt=float(p.dt), E_star_pp=E_pp, E_star_pw=E_pw, k_pp=k_pp,
        k_pw=k_pw, gamma_pp=g_pp, gamma_pw=g_pw, eta_pp=g_pp / (m_pp * math.sqrt(R_pp)),
        eta_pw=g_pw / (m * math.sqrt(R)), E_wall_lammps=E_wall,
        wall_bug_factor=(E / (2 * (1 - nu))) / E_pw, mu=mu, xt_pp=xt(pair, g_pp),
        xt_pw=xt(wall, g_pw),
    )


def pair_coeff(mp: Mapping, eta: float | None = None) -> str:
    eta = mp.eta_pp if eta is None else eta
    return (f"pair_coeff * * hertz/material {mp.E!r} {eta!r} {mp.nu!r} "
            f"tangential linear_nohistory {mp.xt_pp!r} {mp.mu!r} damping viscoelastic "
            "limit_damping")


def wall_args(mp: Mapping, eta: float | None = None, E_wall: float | None = None) -> str:
    eta = mp.eta_pw if eta is None else eta
    E_wall = mp.E_wall_lammps if E_wall is None else E_wall
    return (f"granular hertz/material {E_wall!r} {eta!r} {mp.nu!r} "
            f"tangential linear_nohistory {mp.xt_pw!r} {mp.mu!r} damping viscoelastic "
            "limit_damping")


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


def wall_collision(mp: Mapping, v: float, workdir: str, exe=None) -> dict:
    """One grain hitting the floor (``fix wall/gran zplane``) at ``v``: restitution."""
    R, dt = mp.R, mp.dt
    z0 = R + 5 * v * dt
    tc = 3.2 * (mp.mass / mp.k_pw) ** 0.4 * v**-0.2
    steps = int(5 + 3 * tc / dt) + 20
    L = 4 * R + 2 * v * steps * dt
    script = HEADER + f"""
region sim block {-L!r} {L!r} {-L!r} {L!r} {-0.1 * R!r} {L!r} units box
create_box 1 sim
create_atoms 1 single 0.0 0.0 {z0!r} units box
set type 1 diameter {2 * R!r} density {mp.density!r}
velocity all set 0.0 0.0 {-v!r} units box
pair_style granular
{pair_coeff(mp)}
fix wall all wall/gran {wall_args(mp)} zplane 0.0 NULL
fix integ all nve/sphere
timestep {dt!r}
variable vz equal vz[1]
variable z equal z[1]
thermo_style custom step v_z v_vz
thermo_modify format float %.17g
thermo 1
run {steps}
print "RESULT $(v_vz:%.17g)"
"""
    log, _ = run(script, f"wall_v{v:g}", workdir, exe)
    vz = printed(log, "RESULT")[-1][0]
    tab = thermo_table(log)
    assert tab[-1, 1] > R, "grain still touching the floor at the end"
    return dict(v=v, restitution=vz / v, duration=int(np.sum(tab[:, 1] < R)) * dt)


WALLS = {  # name: (fix arguments, gravity direction pressing the grain onto that wall, axis, lo)
    "floor": ("zplane 0.0 {L}", "0 0 -1", 2, True),
    "lid": ("zplane 0.0 {L}", "0 0 1", 2, False),
    "x0": ("xplane 0.0 {L}", "-1 0 0", 0, True),
    "x1": ("xplane 0.0 {L}", "1 0 0", 0, False),
    "y0": ("yplane 0.0 {L}", "0 -1 0", 1, True),
    "y1": ("yplane 0.0 {L}", "0 1 0", 1, False),
}


def static(mp: Mapping, wall: str, workdir: str, g: float = 9.8, compensated=True,
                  duration: float = 0.1, exe=None) -> dict:
    """One grain pressed on ``wall`` by gravity, starting just touching; damped to rest.

    Returns the equilibrium overlap and the Hertz value ``(m g / k_pw)^{2/3}``.
    """
    R, dt, L = mp.R, mp.dt, 0.02
    fixarg, gdir, axis, lo = WALLS[wall]
    pos = [L / 2] * 3
    pos[axis] = R if lo else L - R
    steps = int(duration / dt)
    E_w = mp.E_wall_lammps if compensated else mp.E
    coord = "xyz"[axis]
    script = HEADER + f"""
region sim block -0.001 {L + 0.001!r} -0.001 {L + 0.001!r} -0.001 {L + 0.001!r} units box
create_box 1 sim
create_atoms 1 single {pos[0]!r} {pos[1]!r} {pos[2]!r} units box
set type 1 diameter {2 * R!r} density {mp.density!r}
velocity all set 0.0 0.0 0.0 units box
pair_style granular
{pair_coeff(mp)}
fix wall all wall/gran {wall_args(mp, E_wall=E_w)} {fixarg.format(L=repr(L))}
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
    overlap = R - c if lo else c - (L - R)
    hertz = (mp.mass * g / mp.k_pw) ** (2.0 / 3.0)
    return dict(wall=wall, compensated=compensated, overlap=overlap, hertz=hertz,
                ratio=overlap / hertz, speed=abs(vel))


def mapping_checks(mp: Mapping, workdir: str, exe=None, speeds=(1.0, 5.0, 20.0),
                   walls=tuple(WALLS)) -> dict:
    """All LAMMPS checks of the mapping against jaxdamp's force law (exact integration)."""
    from jaxdamp.physics.restitution import collision

    out = {"pair": [], "wall": [], "static": []}
    for v in speeds:
        r = pair_collision(mp, v, workdir, exe)
        ref = collision(mp.mass / 2, mp.R / 2, mp.E_star_pp, v, A=mp.A)
        r.update(ref_restitution=ref.restitution, ref_duration=ref.duration)
        out["pair"].append(r)
        w = wall_collision(mp, v, workdir, exe)
        ref = collision(mp.mass, mp.R, mp.E_star_pw, v, A=0.5 * (mp.A + mp.A_wall))
        w.update(ref_restitution=ref.restitution, ref_duration=ref.duration)
        out["wall"].append(w)
    for wall in walls:
        out["static"].append(static(mp, wall, workdir, exe=exe))
    out["static_uncompensated"] = static(mp, "floor", workdir, compensated=False, exe=exe)
    return out


# ---------------------------------------------------------------------------------------------
# The driven bed in LAMMPS (box frame)


def write_data(path: str, r: np.ndarray, v: np.ndarray, mp: Mapping, box, w=None) -> None:
    """A LAMMPS data file of the grains (box frame), velocities ``v`` and angular velocities
    ``w`` (zero when not given)."""
    w = np.zeros_like(np.asarray(v)) if w is None else np.asarray(w)
    pad = 0.001
    lines = ["LAMMPS data file: jaxdamp settled bed, box frame (floor at z = 0)", "",
             f"{len(r)} atoms", "1 atom types", "",
             f"{-pad!r} {box.Lx + pad!r} xlo xhi", f"{-pad!r} {box.Ly + pad!r} ylo yhi",
             f"{-pad!r} {box.Lz + pad!r} zlo zhi", "", "Atoms # sphere", ""]
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
    """The input deck of the driven box in the box frame, up to its first ``run``: the grains
    of the data file ``data``, the mapped pair and wall contacts (undamped: ``damped=False``),
    the time step (default ``mp.dt``) and the effective gravity of the drive
    ``z = amplitude cos(ω (t + t0))`` of ``cfg.frequency``."""
    box = cfg.box
    omega = 2 * math.pi * cfg.frequency
    eta_pp, eta_pw = (mp.eta_pp, mp.eta_pw) if damped else (0.0, 0.0)
    phase = "time" if t0 == 0.0 else f"(time+{t0!r})"
    walls = "\n".join(f"fix w{x} all wall/gran {wall_args(mp, eta_pw)} {x}plane 0.0 {L!r}"
                      for x, L in zip("xyz", (box.Lx, box.Ly, box.Lz)))
    return HEADER + f"""
read_data {data}
pair_style granular
{pair_coeff(mp, eta_pp)}
{walls}
neighbor {0.3 * mp.R!r} bin
neigh_modify delay 0 every 1 check yes
timestep {mp.dt if dt is None else dt!r}
# box frame: gravity plus the inertial force of the box acceleration -A w^2 cos(w t)
variable Ad equal {amplitude!r}
variable w equal {omega!r}
variable geff equal {cfg.gravity!r}-v_Ad*v_w^2*cos(v_w*{phase})
fix grav all gravity v_geff vector 0 0 -1
fix integ all nve/sphere
"""


def bed_script(mp: Mapping, cfg, amplitude: float, steps: list[int], data: str, snapdir: str,
               damped: bool = True, thermo_every: int | None = None) -> str:
    """:func:`box_deck` run in segments ending at ``steps`` (the period boundaries), with a
    full-precision snapshot and the cumulative input work ``W`` printed at each boundary."""
    segs = []
    for n in range(1, len(steps)):
        segs.append(f"run {steps[n] - steps[n - 1]} pre no post no\n"
                    f"write_dump all custom {snapdir}/snap.{n}.txt id x y z vx vy vz "
                    "modify sort id format float %.17g\n"
                    f'print "BOUNDARY {n} $(step) $(v_W:%.17g)"')
    te = thermo_every or max(1, int(round(1.0 / cfg.frequency / 200 / mp.dt)))
    return box_deck(mp, cfg, amplitude, data, damped=damped) + f"""\
# power of the inertial force, its running mean over every step since step 0
variable P equal mass(all)*v_Ad*v_w^2*cos(v_w*time)*vcm(all,z)
fix pin all ave/time 1 1 1 v_P ave running
variable W equal f_pin*(step+1)*dt
variable zc equal xcm(all,z)
variable vz equal vcm(all,z)
thermo_style custom step time v_zc v_vz v_W
thermo_modify format float %.17g norm no lost error
thermo {te}
write_dump all custom {snapdir}/snap.0.txt id x y z vx vy vz modify sort id format float %.17g
run 0 post no
print "BOUNDARY 0 $(step) $(v_W:%.17g)"
""" + "\n".join(segs) + "\n"


def read_snap(path: str) -> np.ndarray:
    """(N, 7): id x y z vx vy vz of a ``write_dump`` file."""
    return np.loadtxt(path, skiprows=9)


def mechanical_energy(snap: np.ndarray, mp: Mapping, box, g: float) -> dict:
    """Box-frame kinetic, gravitational and elastic energy of a snapshot (LAMMPS' stiffness)."""
    from scipy.spatial import cKDTree

    r, v = snap[:, 1:4], snap[:, 4:7]
    ke = 0.5 * mp.mass * float(np.sum(v * v))
    pe = mp.mass * g * float(np.sum(r[:, 2]))
    el = 0.0
    pairs = cKDTree(r).query_pairs(2 * mp.R, output_type="ndarray")
    if len(pairs):
        d = np.linalg.norm(r[pairs[:, 0]] - r[pairs[:, 1]], axis=1)
        xi = np.clip(2 * mp.R - d, 0.0, None)
        el += 0.4 * mp.k_pp * float(np.sum(xi**2.5))
    k_w = mp.k_wall_lammps(mp.E_wall_lammps)
    dist = np.concatenate([r[:, 0], box.Lx - r[:, 0], r[:, 1], box.Ly - r[:, 1],
                           r[:, 2], box.Lz - r[:, 2]])
    xi = np.clip(mp.R - dist, 0.0, None)
    el += 0.4 * k_w * float(np.sum(xi**2.5))
    return dict(kinetic=ke, gravitational=pe, elastic=el)


def driven_bed(mp: Mapping, cfg, amplitude: float, r0, v0, n_periods: int, workdir: str,
               damped: bool = True, exe=None, tag: str = "") -> dict:
    """Run the driven bed for ``n_periods`` periods from ``r0, v0`` (box frame).

    Returns per-boundary cumulative input work, energies and dissipation, the thermo series
    and the wall time. ``tag`` names the bed (its working directory ``bed_A<cm>cm<tag>``).
    """
    name = f"bed_A{amplitude * 100:g}cm{tag}" + ("" if damped else "_undamped")
    sub = os.path.join(workdir, name)
    snapdir = os.path.join(sub, "snaps")
    os.makedirs(snapdir, exist_ok=True)
    for f in os.listdir(snapdir):
        os.remove(os.path.join(snapdir, f))
    data = os.path.join(sub, "bed.data")
    write_data(data, np.asarray(r0), np.asarray(v0), mp, cfg.box)
    T = 1.0 / cfg.frequency
    steps = boundary_steps(n_periods, T, mp.dt)
    script = bed_script(mp, cfg, amplitude, steps, data, snapdir, damped=damped)
    log, wall = run(script, name, sub, exe)
    rows = np.asarray(printed(log, "BOUNDARY"))
    assert len(rows) == n_periods + 1, f"{len(rows)} boundaries printed, {n_periods + 1} expected"
    assert np.array_equal(rows[:, 1].astype(int), steps)
    W = rows[:, 2]
    en = [mechanical_energy(read_snap(os.path.join(snapdir, f"snap.{n}.txt")), mp, cfg.box,
                            cfg.gravity) for n in range(n_periods + 1)]
    E = np.array([e["kinetic"] + e["gravitational"] + e["elastic"] for e in en])
    D = W - (E - E[0])
    loop = sum(float(x) for x in re.findall(r"Loop time of ([0-9.eE+-]+)", log))
    tab = thermo_table(log)
    return dict(steps=np.asarray(steps), t=np.asarray(steps) * mp.dt, W=W, E=E, D=D,
                elastic=np.array([e["elastic"] for e in en]),
                kinetic=np.array([e["kinetic"] for e in en]),
                thermo=tab, wall=wall, loop_time=loop, n_steps=steps[-1])
