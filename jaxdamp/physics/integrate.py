"""The time step: velocity Verlet for grains (translation, rotation) and the box (docs/physics.md §3).

One step from ``t`` to ``t + dt``::

    r(t+dt)  = r + v dt + a dt²/2                       (same for the primary's z in S1)
    v_pred   = v + a dt                                 velocity-dependent forces use these
    a(t+dt)  = F(r(t+dt), v_pred, ω_pred, box) / m
    v(t+dt)  = v + (a + a(t+dt)) dt/2
    q(t+dt)  = exp(ω_mid dt / 2) ⊗ q, renormalised      ω_mid = ω + α dt/2

The box moves as its mount says (:mod:`jaxdamp.physics.mounts`: the primary system of S1,
a multi-DOF structure, or the prescribed motion of S2): the mount predicts the box's position
and velocity, gives its acceleration from the grains' force and its powers and energy; a
prescribed motion's velocity is the drive's, an integrated one's is velocity Verlet's. Work
channels (:data:`jaxdamp.physics.model.CHANNELS`) are integrated with the trapezoid rule over
the powers at consecutive force evaluations.

The pieces the native kernel (:mod:`jaxdamp.engine.native`) shares are defined here once: the
body force (gravity and settling drag: pure arithmetic, one function serves JAX arrays and,
compiled, the kernel's scalars) and the quaternion rotation (JAX form :func:`rotate`, scalar
form :func:`rotate_scalar` side by side).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxdamp.physics.contact import safe_norm, scalar_form
from jaxdamp.physics.energy import mechanical_energy
from jaxdamp.physics.model import (
    INCREMENT_OF,
    N_CHANNELS,
    Model,
    Params,
    State,
    grain_positions_of_boxes,
)
from jaxdamp.physics.mounts import mount_of
from jaxdamp.physics.pairs import pair_forces
from jaxdamp.physics.walls import wall_forces


class Forces(NamedTuple):
    """Everything one force evaluation yields (single system)."""

    force: jnp.ndarray  # (N, 3) total on grains, gravity and drag included [N]
    torque: jnp.ndarray  # (N, 3) [N m]
    box_z: jnp.ndarray  # vertical force of grains on the box [N]
    floor_lid_z: jnp.ndarray  # on floor + lid only [N]
    n_floor: jnp.ndarray
    n_lid: jnp.ndarray
    n_side: jnp.ndarray
    elastic_energy: jnp.ndarray  # [J]
    losses: jnp.ndarray  # (4,) pp_normal, pp_friction, pw_normal, pw_friction powers [W]
    wall_groups: jnp.ndarray  # (3,) pw_floor, pw_lid, pw_side powers [W]
    cell_losses: jnp.ndarray  # (cells,) each cell's granular loss power [W]
    dof_forces: jnp.ndarray  # (dofs,) the grains' forces on the degrees of freedom along e [N]
    spring_pair: jnp.ndarray  # (N, K, 3) the grain–grain springs' forces after the step [N]
    spring_wall: jnp.ndarray  # (N, 2 + W, 3) the grain–wall springs' forces after it [N]
    turned: jnp.ndarray  # the energy the step starts the springs with (Spring.turned) [J]
    spring_energy: jnp.ndarray  # the springs' energy after the step [J] (in elastic_energy)
    slip_losses: jnp.ndarray  # (2,) pp_slip, pw_slip powers [W]


def forces(r, v, w, z_box, zd_box, y, yd, idx, p: Params, model: Model, spring_pair=None,
           spring_wall=None, step_vw=None) -> Forces:
    """All forces on the grains of one system for the given (predicted) kinematics: the box
    at ``z_box`` moving at ``zd_box``, the structure's other degrees of freedom at ``y``,
    ``yd`` (cells may sit on them, :attr:`Model.cell_dofs`). With tangential springs
    (``model.springs``), ``spring_pair`` ``(N, K, 3)`` (per slot of ``idx``) and
    ``spring_wall`` are their forces (the history) before this force evaluation (``None``: none
    yet); each evaluation advances them by one step, with the velocities ``step_vw = (v, w,
    zd_box, yd)`` over the step (``None``: the evaluation's)."""
    pf = pair_forces(r, v, w, idx, p, model, spring_pair,
                     None if step_vw is None else step_vw[:2])
    wall_step = None
    if step_vw is not None:
        wall_step = (step_vw[0], step_vw[1],
                     grain_positions_of_boxes(step_vw[2], step_vw[3], model))
    wf = wall_forces(r, v, w, grain_positions_of_boxes(z_box, y, model),
                     grain_positions_of_boxes(zd_box, yd, model), p, model, spring_wall,
                     wall_step)
    losses = jnp.stack([pf.normal_loss, pf.friction_loss, wf.normal_loss, wf.friction_loss])
    fx, fy, fz = body_force(p.mass, v[:, 0], v[:, 1], v[:, 2], p.gravity, p.drag)
    f = pf.force + wf.force + jnp.stack([fx, fy, fz], axis=-1)
    return Forces(
        force=f,
        torque=pf.torque + wf.torque,
        box_z=wf.box_z,
        floor_lid_z=wf.floor_lid_z,
        n_floor=wf.n_floor,
        n_lid=wf.n_lid,
        n_side=wf.n_side,
        elastic_energy=pf.elastic_energy + wf.elastic_energy,
        losses=losses,
        wall_groups=wf.group_loss,
        cell_losses=cell_losses(losses, pf.grain_loss + wf.grain_loss, model),
        dof_forces=dof_forces(wf, model),
        spring_pair=pf.history,
        spring_wall=wf.history,
        turned=pf.turned + wf.turned,
        spring_energy=pf.spring_energy + wf.spring_energy,
        slip_losses=jnp.stack([pf.slip_loss, wf.slip_loss]),
    )


def dof_forces(wf, model: Model):
    """The grains' forces on the degrees of freedom along ``e`` ``(dofs,)`` [N]: the box's
    ``box_z`` on the first, or each cell's on its own (:attr:`Model.cell_dofs`)."""
    if not model.cell_dofs:
        return jnp.zeros(model.dofs, wf.box_z.dtype).at[0].set(wf.box_z)
    per_cell = jax.ops.segment_sum(wf.grain_box_z, jnp.asarray(model.cell_index()),
                                   num_segments=model.cells)
    return jax.ops.segment_sum(per_cell, jnp.asarray(model.dofs_of_cells()),
                               num_segments=model.dofs)


def cell_losses(losses, grain_loss, model: Model):
    """Each cell's granular loss power ``(cells,)`` [W]: the sum of ``grain_loss`` ``(N,)``
    over the cell's grains (:meth:`Model.cell_index`); for one cell, the sum of the damper's
    ``losses`` (the four granular channels)."""
    if model.cells == 1:
        return losses.sum()[None]
    return jax.ops.segment_sum(grain_loss, jnp.asarray(model.cell_index()),
                               num_segments=model.cells)


def body_force(m, vx, vy, vz, gravity, drag):
    """Gravity along ``-z`` and the settling drag on a grain of mass ``m`` [kg]:
    ``m (g - drag v)`` [N] with ``g = (0, 0, -gravity)`` [m/s²], ``drag`` [1/s]. Arithmetic
    only: elementwise on JAX arrays, and compiled as :data:`body_force_scalar`."""
    return -m * drag * vx, -m * drag * vy, m * (-gravity - drag * vz)


body_force_scalar = scalar_form(body_force)


def _powers(fo: Forces, mount, z, zd, y, yd, t, v_pred, p: Params, e_spring):
    """Channel powers [W] at one force evaluation (see :data:`jaxdamp.physics.model.CHANNELS`):
    the mount's input and damping, the granular losses, the settling drag, the grain–wall
    losses by wall group, the springs' slip losses and the energy their change of stiffness
    took since the last evaluation, ``(e_spring - turned)/dt`` (``e_spring``: the springs'
    energy then)."""
    p_in, p_c = mount.powers(fo.dof_forces, z, zd, y, yd, t, p)
    p_drag = p.drag * jnp.sum(p.mass * jnp.sum(v_pred * v_pred, axis=-1))
    p_stiff = (e_spring - fo.turned) / p.dt
    return jnp.concatenate([jnp.stack([p_in, p_c]), fo.losses, p_drag[None], fo.wall_groups,
                            fo.slip_losses, p_stiff[None]])


def _integrate(power_old, power_new, dt):
    """The work channels' change over a step [J]: the trapezoid rule of the powers at its two
    ends, except for the parts that are the step's own energy over ``dt``
    (:data:`jaxdamp.physics.model.INCREMENT_OF`), taken whole from its end."""
    src = jnp.asarray(INCREMENT_OF)
    part = lambda p: jnp.where(src >= 0, p[jnp.maximum(src, 0)], 0.0)  # noqa: E731
    return 0.5 * dt * (power_old + power_new) + 0.5 * dt * (part(power_new) - part(power_old))


def rotate(q, w, dt):
    """Quaternions ``(N, 4)`` advanced by a rotation of angular velocity ``w`` over ``dt``:
    ``q ← dq ⊗ q / |dq ⊗ q|`` with ``dq = (cos h, sin(h) ŵ)``, half angle ``h = |w| dt / 2``."""
    speed = safe_norm(w)
    half = 0.5 * speed * dt
    moving = speed > 0
    axis_scale = jnp.where(moving, jnp.sin(half) / jnp.where(moving, speed, 1.0), 0.5 * dt)
    dw = jnp.cos(half)
    dv = axis_scale[:, None] * w
    qw, qv = q[:, :1], q[:, 1:]
    # Hamilton product dq ⊗ q
    new_w = dw[:, None] * qw - jnp.sum(dv * qv, axis=-1, keepdims=True)
    new_v = dw[:, None] * qv + qw * dv + jnp.cross(dv, qv)
    out = jnp.concatenate([new_w, new_v], axis=-1)
    return out / jnp.linalg.norm(out, axis=-1, keepdims=True)


@scalar_form
def _turn(qw, qx, qy, qz, cw, dx, dy, dz):
    """The Hamilton product ``(cw, d) ⊗ q`` and ``e = |dq ⊗ q|² - 1``, before renormalising."""
    nw = cw * qw - (dx * qx + dy * qy + dz * qz)
    nx = cw * qx + qw * dx + (dy * qz - dz * qy)
    ny = cw * qy + qw * dy + (dz * qx - dx * qz)
    nz = cw * qz + qw * dz + (dx * qy - dy * qx)
    return nw, nx, ny, nz, nw * nw + nx * nx + ny * ny + nz * nz - 1.0


@scalar_form
def _half_angle_series(h2, dt):
    """``cos h`` and ``sin(h)/|w|`` from their series in ``h² = (|w| dt/2)²``."""
    return (1.0 - h2 * (0.5 - h2 * (1.0 / 24.0 - h2 / 720.0)),
            0.5 * dt * (1.0 - h2 * (1.0 / 6.0 - h2 * (1.0 / 120.0 - h2 / 5040.0))))


@scalar_form
def _inv_sqrt_series(e):
    """``1/sqrt(1 + e)`` from its series ``1 - e/2 + 3e²/8``."""
    return 1.0 - e * (0.5 - 0.375 * e)


#: Where the series forms of :func:`rotate_series_scalar` hold to float64 precision: half
#: angles ``h² < ROTATE_H2`` (next terms of ``cos h`` and ``sin(h)/h`` < 3e-21) and quaternions
#: off the unit sphere by ``|e| < ROTATE_E`` (next term of ``1/sqrt(1 + e)`` < 4e-25).
ROTATE_H2, ROTATE_E = 1e-4, 1e-8


@scalar_form
def rotate_series_scalar(qw, qx, qy, qz, ox, oy, oz, dt):
    """:func:`rotate_scalar` from series alone, without a branch, so that a loop of it over
    grains stored component by component compiles to SIMD code (the native kernel's rotation
    pass: 1.8–2.0 ns per grain against 10–11 for the branching form, measured in a standalone
    loop of 250 grains). Returns the new quaternion and ``ok``: whether the series hold
    (:data:`ROTATE_H2`, :data:`ROTATE_E`); where not, use :func:`rotate_scalar`."""
    h2 = 0.25 * dt * dt * (ox * ox + oy * oy + oz * oz)  # (half angle)^2
    cw, s = _half_angle_series(h2, dt)
    nw, nx, ny, nz, e = _turn(qw, qx, qy, qz, cw, s * ox, s * oy, s * oz)
    inv = _inv_sqrt_series(e)
    ok = (h2 < ROTATE_H2) & (abs(e) < ROTATE_E)
    return nw * inv, nx * inv, ny * inv, nz * inv, ok


@scalar_form
def rotate_scalar(qw, qx, qy, qz, ox, oy, oz, dt):
    """Scalar form of :func:`rotate` for one quaternion ``(qw, qx, qy, qz)`` and angular
    velocity ``(ox, oy, oz)`` [rad/s]. For half angles ``h² < ROTATE_H2`` ``cos h`` and
    ``sin(h)/|w|`` are taken from their series (exact in float64: next terms < 3e-21), and the
    renormalisation of a quaternion that left the unit sphere by ``|e| < ROTATE_E`` from the
    series of ``1/sqrt`` (next term < 4e-25): free of ``sin``/``cos``/``sqrt`` calls and
    divisions per grain and step (in the moving thesis bed the rotation pass was a third of the
    kernel's time; 4 divisions and a square root per grain were ~5–10 % of a step). The native
    kernel runs :func:`rotate_series_scalar` over all grains and this form only where those
    series do not hold."""
    h2 = 0.25 * dt * dt * (ox * ox + oy * oy + oz * oz)  # (half angle)^2
    if h2 < ROTATE_H2:
        cw, s = _half_angle_series(h2, dt)
    else:
        speed = math.sqrt(ox * ox + oy * oy + oz * oz)
        cw = math.cos(0.5 * speed * dt)
        s = math.sin(0.5 * speed * dt) / speed
    nw, nx, ny, nz, e = _turn(qw, qx, qy, qz, cw, s * ox, s * oy, s * oz)
    # renormalise: |q|² = 1 + e with |e| ~ 1e-16 after a step from a unit q, where
    # 1/sqrt(1 + e) = 1 - e/2 + 3e²/8 (next term < 4e-25): no sqrt and no division per grain
    if abs(e) < ROTATE_E:
        inv = _inv_sqrt_series(e)
    else:
        inv = 1.0 / math.sqrt(1.0 + e)
    return nw * inv, nx * inv, ny * inv, nz * inv


def _finish(state_fields: dict, fo: Forces, power, p: Params) -> State:
    return State(
        **state_fields,
        spring_pair=fo.spring_pair,
        spring_wall=fo.spring_wall,
        e_spring=fo.spring_energy,
        power=power,
        power_cell=fo.cell_losses,
        e_elastic=fo.elastic_energy,
        f_floor_lid=fo.floor_lid_z,
        f_box=fo.box_z,
        n_floor=fo.n_floor,
        n_lid=fo.n_lid,
        n_side=fo.n_side,
    )


def initial_state(r, v, w, q, z, zd, t, idx, p: Params, model: Model, e_start=None) -> State:
    """A state at time ``t`` with accelerations and powers evaluated there (single system).

    ``z``, ``zd``: the box's position and velocity, or for a structure of ``model.dofs``
    degrees of freedom the vectors ``(dofs,)`` in the engines' order (the box first). For S2
    they are ignored and taken from the drive. ``e_start`` is the reference mechanical energy
    of the balance; by default the energy of this state. With tangential springs
    (``model.springs``) every contact starts without history: the evaluation at ``t`` is its
    first step (a contact that forms between steps starts the same way).
    """
    r, v, w = jnp.asarray(r), jnp.asarray(v), jnp.asarray(w)
    t = jnp.asarray(t, jnp.float64)
    x = jnp.reshape(jnp.asarray(z, jnp.float64), (-1,))
    xd = jnp.reshape(jnp.asarray(zd, jnp.float64), (-1,))
    if x.shape[0] < model.dofs:  # S2 (and settling) carry the other DOFs at rest
        x = jnp.concatenate([x, jnp.zeros(model.dofs - x.shape[0])])
        xd = jnp.concatenate([xd, jnp.zeros(model.dofs - xd.shape[0])])
    y, yd = x[1:model.dofs], xd[1:model.dofs]
    mount = mount_of(model)
    if mount.prescribed:
        z, zd = mount.predict(x[0], xd[0], 0.0, t, 0.0, p)
    else:
        z, zd = x[0], xd[0]
    fo = forces(r, v, w, z, zd, y, yd, idx, p, model)
    zdd, ydd = mount.accelerate(z, zd, y, yd, t, fo.dof_forces, p)
    power = _powers(fo, mount, z, zd, y, yd, t, v, p, jnp.zeros(()))
    st = _finish(
        dict(
            r=r, v=v, w=w, q=jnp.asarray(q), a=fo.force / p.mass[:, None],
            alpha=fo.torque / p.inertia[:, None], z=z, zd=zd, zdd=zdd, y=y, yd=yd, ydd=ydd, t=t,
            step=jnp.zeros((), jnp.int64), work=jnp.zeros(N_CHANNELS),
            work_cell=jnp.zeros(model.cells), e_start=jnp.zeros(()),
            z_max=jnp.asarray(-jnp.inf), z_min=jnp.asarray(jnp.inf),
            spring_partner=partners(idx, model),
        ),
        fo,
        power,
        p,
    )
    e0 = mechanical_energy(st, p, model) if e_start is None else e_start
    return dataclasses.replace(st, e_start=jnp.asarray(e0, jnp.float64))


def partners(idx, model: Model):
    """``State.spring_partner`` of springs written against the neighbour block ``idx``
    ``(N, K)``: ``idx`` itself (int32) with springs, else an empty ``(N, 0)``."""
    if model.springs:
        return jnp.asarray(idx, jnp.int32)
    return jnp.zeros((model.n, 0), jnp.int32)


def step(st: State, idx, p: Params, model: Model) -> State:
    """Advance one system by one time step ``p.dt``. ``idx``: neighbour block ``(N, K)``;
    with tangential springs it must be the list their history was written against
    (``st.spring_partner``; after a rebuild, :func:`jaxdamp.engine.history.rekey`)."""
    dt = p.dt
    t1 = st.t + dt
    mount = mount_of(model)
    r1 = st.r + dt * st.v + 0.5 * dt * dt * st.a
    v_pred = st.v + dt * st.a
    w_pred = st.w + dt * st.alpha
    z1, zd_pred = mount.predict(st.z, st.zd, st.zdd, t1, dt, p)
    y1 = st.y + dt * st.yd + 0.5 * dt * dt * st.ydd
    yd_pred = st.yd + dt * st.ydd

    step_vw = None
    if model.springs:  # the springs grow with the displacements over the step (half-steps)
        step_vw = (st.v + 0.5 * dt * st.a, st.w + 0.5 * dt * st.alpha, (z1 - st.z) / dt,
                   (y1 - st.y) / dt)
    fo = forces(r1, v_pred, w_pred, z1, zd_pred, y1, yd_pred, idx, p, model, st.spring_pair,
                st.spring_wall, step_vw)
    a1 = fo.force / p.mass[:, None]
    alpha1 = fo.torque / p.inertia[:, None]
    zdd1, ydd1 = mount.accelerate(z1, zd_pred, y1, yd_pred, t1, fo.dof_forces, p)
    zd1 = zd_pred if mount.prescribed else st.zd + 0.5 * dt * (st.zdd + zdd1)

    power = _powers(fo, mount, z1, zd_pred, y1, yd_pred, t1, v_pred, p, st.e_spring)
    in_window = t1 >= p.t_window
    return _finish(
        dict(
            r=r1,
            v=st.v + 0.5 * dt * (st.a + a1),
            w=st.w + 0.5 * dt * (st.alpha + alpha1),
            q=rotate(st.q, st.w + 0.5 * dt * st.alpha, dt),
            a=a1,
            alpha=alpha1,
            z=z1,
            zd=zd1,
            zdd=zdd1,
            y=y1,
            yd=st.yd + 0.5 * dt * (st.ydd + ydd1),
            ydd=ydd1,
            t=t1,
            step=st.step + 1,
            work=st.work + _integrate(st.power, power, dt),
            work_cell=st.work_cell + 0.5 * dt * (st.power_cell + fo.cell_losses),
            e_start=st.e_start,
            z_max=jnp.where(in_window, jnp.maximum(st.z_max, z1), st.z_max),
            z_min=jnp.where(in_window, jnp.minimum(st.z_min, z1), st.z_min),
            spring_partner=partners(idx, model),
        ),
        fo,
        power,
        p,
    )


def box_frame(st: State, p: Params, dt=None):
    """Grain positions relative to the box's corner ``e z``, ``(..., N, 3)`` (for neighbour
    lists; ``p`` gives the excitation axis ``e``, batched like ``st``).

    With ``dt`` [s] (shape of ``st.z``): at the predicted positions ``r + dt v + ½ dt² a`` of
    the next force evaluation (box likewise), where a list must hold every touching pair;
    deciding on the current positions left a contact unlisted when a grain's predictor step
    outran the list's margin (strongly overlapping start of ``tests/test_mixtures.py``)."""
    r, z = st.r, st.z
    if dt is not None:
        h = dt[..., None, None]
        r = r + h * st.v + 0.5 * h * h * st.a
        z = z + dt * st.zd + 0.5 * dt * dt * st.zdd
    shift = jnp.stack([p.ex, p.ey, p.ez], axis=-1) * z[..., None]  # the box's corner (..., 3)
    return r - shift[..., None, :]

