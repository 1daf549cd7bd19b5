"""Energies, the energy balance and the per-sample records of a run (docs/physics.md §4).

Mechanical energy of one system::

    E = Σ ½ m v² + Σ ½ I ω² + Σ m g z + E_elastic            (grains, contacts)
        + ½ M z'² + ½ K (z - u)²                            (primary, S1 only)

and the balance ``W_input = E(t) - E(0) + W_primary_damping + Σ granular losses + W_drag``,
whose residual is recorded. For S2 the input is the work of the moving walls on the grains.
The losses are the channels :data:`~jaxdamp.physics.model.LOSSES`; the grain–wall losses are
also reported by wall group (``pw_floor``, ``pw_lid``, ``pw_side``), a breakdown of
``pw_normal + pw_friction`` outside the balance.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxdamp.physics.contact import scalar_form
from jaxdamp.physics.model import (
    CH,
    LOSSES,
    N_CHANNELS,
    Model,
    Params,
    State,
    grain_positions_of_boxes,
)
from jaxdamp.physics.mounts import mount_of


def grain_energies(st: State, p: Params):
    """Translational kinetic, rotational kinetic and gravitational energy of the grains [J]."""
    kin = 0.5 * jnp.sum(p.mass * jnp.sum(st.v * st.v, axis=-1))
    rot = 0.5 * jnp.sum(p.inertia * jnp.sum(st.w * st.w, axis=-1))
    grav = p.gravity * jnp.sum(p.mass * st.r[:, 2])
    return kin, rot, grav


def primary_energy(st: State, p: Params, model: Model):
    """Mechanical energy of the box's mount [J] (:mod:`jaxdamp.physics.mounts`: the primary's
    kinetic + spring energy, a structure's, 0 for a prescribed motion)."""
    return mount_of(model).energy(st.z, st.zd, st.y, st.yd, st.t, p)


def mechanical_energy(st: State, p: Params, model: Model):
    kin, rot, grav = grain_energies(st, p)
    return kin + rot + grav + st.e_elastic + primary_energy(st, p, model)


def balance_residual(st: State, p: Params, model: Model):
    """``E(t) - E(0) + losses - input`` [J]; zero for exact bookkeeping."""
    losses = st.work[LOSSES].sum()
    return mechanical_energy(st, p, model) - st.e_start + losses - st.work[CH["input"]]


def granular_loss(work):
    """Total granular dissipation [J] from the work channels ``(..., N_CHANNELS)``."""
    return work[..., CH["pp_normal"] : CH["pw_friction"] + 1].sum(axis=-1)


#: Whether each channel is a loss of the balance (:data:`LOSSES`), for the scalar form.
_IS_LOSS = tuple(bool(c in set(LOSSES.tolist())) for c in range(N_CHANNELS))

#: Time series recorded at every sample, with units.
RECORD_UNITS = {
    "t": "s",
    "z_box": "m",
    "v_box": "m/s",
    "y_dofs": "m",
    "z_cm": "m",
    "vz_cm": "m/s",
    "z_lowest": "m",
    "z_highest": "m",
    "force_floor_lid": "N",
    "force_box": "N",
    "n_floor": "1",
    "n_lid": "1",
    "n_side": "1",
    "z_cm_species": "m",
    "vz_cm_species": "m/s",
    "n_floor_species": "1",
    "n_lid_species": "1",
    "z_cm_cell": "m",
    "vz_cm_cell": "m/s",
    "n_floor_cell": "1",
    "n_lid_cell": "1",
    "e_kinetic_cell": "J",
    "loss_cell": "J",
    "e_kinetic": "J",
    "e_rotational": "J",
    "e_gravitational": "J",
    "e_elastic": "J",
    "e_primary": "J",
    "work": "J",
    "balance_residual": "J",
}


def record(st: State, p: Params, model: Model, mean_forces) -> dict:
    """One sample of the time series (single system).

    ``mean_forces`` = ``(floor+lid, whole box)`` vertical grain forces averaged over the
    sampling interval [N] (impulse / interval: collisions are shorter than the interval).
    ``z_lowest``/``z_highest`` are the lowest and highest grain centres; ``work`` the
    cumulative channels ``(N_CHANNELS,)``. ``*_species`` are shaped ``(S,)``, one entry per
    species (:meth:`Model.species_slices`): centre of mass height and vertical velocity, and
    the grains touching floor / lid at this instant (overlap > 0). ``*_cell`` are shaped
    ``(k,)``, one entry per cell of the damper (:meth:`Model.cell_index`, ``k = Model.cells``):
    the same three, the cell's translational kinetic energy ``Σ ½ m v²`` (they sum to
    ``e_kinetic``) and ``loss_cell``, the granular loss of the cell's contacts since the run
    started [J] (``State.work_cell``: they sum to the damper's ``pp_normal + pp_friction +
    pw_normal + pw_friction``); the forces, contact counts on the side walls, the other
    energies and the work channels are the whole damper's.
    """
    kin, rot, grav = grain_energies(st, p)
    m_tot = jnp.maximum(p.mass.sum(), 1e-300)
    has = p.mass.shape[0] > 0
    z = st.r[:, 2]
    return dict(
        t=st.t,
        z_box=st.z,
        v_box=st.zd,
        y_dofs=st.y,
        z_cm=jnp.sum(p.mass * z) / m_tot,
        vz_cm=jnp.sum(p.mass * st.v[:, 2]) / m_tot,
        z_lowest=z.min() if has else jnp.zeros(()),
        z_highest=z.max() if has else jnp.zeros(()),
        force_floor_lid=mean_forces[0],
        force_box=mean_forces[1],
        n_floor=st.n_floor.astype(jnp.int32),
        n_lid=st.n_lid.astype(jnp.int32),
        n_side=st.n_side.astype(jnp.int32),
        **_species_records(st, p, model),
        **_cell_records(st, p, model),
        e_kinetic=kin,
        e_rotational=rot,
        e_gravitational=grav,
        e_elastic=st.e_elastic,
        e_primary=primary_energy(st, p, model),
        work=st.work,
        balance_residual=balance_residual(st, p, model),
    )


#: Integer-valued records (stored as int32).
INT_RECORDS = ("n_floor", "n_lid", "n_side", "n_floor_species", "n_lid_species",
               "n_floor_cell", "n_lid_cell")


def record_layout(model: Model) -> list[tuple[str, tuple]]:
    """``[(name, shape)]`` of one sample of :func:`record`, in its order: the flat row of
    :func:`record_row` (scalars ``()``, per-species ``(S,)``, per-cell ``(k,)``, ``work``
    ``(N_CHANNELS,)``)."""
    S = (len(model.species_slices()),)
    k = (model.cells,)
    shapes = {"z_cm_species": S, "vz_cm_species": S, "n_floor_species": S,
              "n_lid_species": S, "work": (N_CHANNELS,), "y_dofs": (model.dofs - 1,),
              "z_cm_cell": k, "vz_cm_cell": k, "n_floor_cell": k, "n_lid_cell": k,
              "e_kinetic_cell": k, "loss_cell": k}
    return [(name, shapes.get(name, ())) for name in RECORD_UNITS]


@scalar_form
def record_row(out, t, z, zd, y, e_prim, r, v, w, mass, inertia, radius, gravity, Lz, ez,
               e_elastic, e_start, f_floor_lid, f_box, n_floor, n_lid, n_side, work, work_cell,
               bounds, zc):
    """Scalar form of :func:`record` (the native engine's samples): one sample written into
    the flat row ``out`` in the order of :func:`record_layout`. ``y``: the structure's other
    degrees of freedom, ``e_prim``: the primary's energy at ``t`` (:func:`primary_energy`),
    ``ez``: the vertical component of the excitation axis (the floor is at height ``ez z``);
    ``work``, ``work_cell``: ``State.work``, ``State.work_cell``; ``zc`` ``(k,)``: each
    cell's container's position along the axis [m] (``z`` for every cell on the box's degree
    of freedom, :func:`jaxdamp.physics.model.cell_positions`); ``bounds`` ``(S, k + 1)``:
    the grains of species ``s`` in cell ``c`` are ``bounds[s, c] … bounds[s, c + 1] − 1``
    (:func:`cell_bounds`), so species ``s`` is ``bounds[s, 0] … bounds[s, k] − 1``."""
    n = r.shape[0]
    S = bounds.shape[0]
    K = bounds.shape[1] - 1
    m_tot = 0.0
    mz = 0.0
    mv = 0.0
    kin = 0.0
    rot = 0.0
    lo = r[0, 2] if n else 0.0
    hi = r[0, 2] if n else 0.0
    for i in range(n):
        m_tot += mass[i]
        mz += mass[i] * r[i, 2]
        mv += mass[i] * v[i, 2]
        kin += mass[i] * (v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1] + v[i, 2] * v[i, 2])
        rot += inertia[i] * (w[i, 0] * w[i, 0] + w[i, 1] * w[i, 1] + w[i, 2] * w[i, 2])
        lo = min(lo, r[i, 2])
        hi = max(hi, r[i, 2])
    kin *= 0.5
    rot *= 0.5
    grav = gravity * mz
    m_tot = max(m_tot, 1e-300)
    out[0], out[1], out[2] = t, z, zd
    k = 3
    for j in range(y.shape[0]):
        out[k + j] = y[j]
    k += y.shape[0]
    out[k], out[k + 1], out[k + 2], out[k + 3] = mz / m_tot, mv / m_tot, lo, hi
    out[k + 4], out[k + 5], out[k + 6], out[k + 7] = f_floor_lid, f_box, n_floor, n_lid
    out[k + 8] = n_side
    k += 9
    for s in range(S):
        ms = 0.0
        msz = 0.0
        msv = 0.0
        nf = 0.0
        nl = 0.0
        for c in range(K):
            for i in range(bounds[s, c], bounds[s, c + 1]):
                ms += mass[i]
                msz += mass[i] * r[i, 2]
                msv += mass[i] * v[i, 2]
                h = r[i, 2] - ez * zc[c]
                nf += 1.0 if h < radius[i] else 0.0
                nl += 1.0 if Lz - h < radius[i] else 0.0
        ms = max(ms, 1e-300)
        out[k + s] = msz / ms
        out[k + S + s] = msv / ms
        out[k + 2 * S + s] = nf
        out[k + 3 * S + s] = nl
    k += 4 * S
    for c in range(K):  # per cell: its grains of every species
        ms = 0.0
        msz = 0.0
        msv = 0.0
        nf = 0.0
        nl = 0.0
        kc = 0.0
        for s in range(S):
            for i in range(bounds[s, c], bounds[s, c + 1]):
                ms += mass[i]
                msz += mass[i] * r[i, 2]
                msv += mass[i] * v[i, 2]
                kc += mass[i] * (v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1] + v[i, 2] * v[i, 2])
                h = r[i, 2] - ez * zc[c]
                nf += 1.0 if h < radius[i] else 0.0
                nl += 1.0 if Lz - h < radius[i] else 0.0
        ms = max(ms, 1e-300)
        out[k + c] = msz / ms
        out[k + K + c] = msv / ms
        out[k + 2 * K + c] = nf
        out[k + 3 * K + c] = nl
        out[k + 4 * K + c] = 0.5 * kc
        out[k + 5 * K + c] = work_cell[c]
    k += 6 * K
    out[k], out[k + 1], out[k + 2], out[k + 3], out[k + 4] = kin, rot, grav, e_elastic, e_prim
    k += 5
    losses = 0.0
    for c in range(work.shape[0]):
        out[k + c] = work[c]
        if _IS_LOSS[c]:  # primary damping, granular losses, drag, spring stiffness (LOSSES)
            losses += work[c]
    k += work.shape[0]
    out[k] = kin + rot + grav + e_elastic + e_prim - e_start + losses - work[0]


def _species_records(st: State, p: Params, model: Model) -> dict:
    floor = st.r[:, 2] - p.ez * grain_positions_of_boxes(st.z, st.y, model)  # above the floor
    on_floor = floor < p.radius
    on_lid = p.Lz - floor < p.radius
    out = {k: [] for k in ("z_cm_species", "vz_cm_species", "n_floor_species", "n_lid_species")}
    for sl in model.species_slices():
        m = p.mass[sl]
        m_tot = jnp.maximum(m.sum(), 1e-300)
        out["z_cm_species"].append(jnp.sum(m * st.r[sl, 2]) / m_tot)
        out["vz_cm_species"].append(jnp.sum(m * st.v[sl, 2]) / m_tot)
        out["n_floor_species"].append(on_floor[sl].sum().astype(jnp.int32))
        out["n_lid_species"].append(on_lid[sl].sum().astype(jnp.int32))
    return {k: jnp.stack(v) for k, v in out.items()}


def _cell_records(st: State, p: Params, model: Model) -> dict:
    """The per-cell records of :func:`record`, ``(k,)`` each."""
    k = model.cells
    cell = jnp.asarray(model.cell_index())
    one_hot = (cell[None, :] == jnp.arange(k)[:, None]).astype(p.mass.dtype)  # (k, N)
    floor = st.r[:, 2] - p.ez * grain_positions_of_boxes(st.z, st.y, model)
    m_cell = jnp.maximum(one_hot @ p.mass, 1e-300)
    count = lambda b: (one_hot @ b.astype(p.mass.dtype)).astype(jnp.int32)  # noqa: E731
    return dict(
        z_cm_cell=one_hot @ (p.mass * st.r[:, 2]) / m_cell,
        vz_cm_cell=one_hot @ (p.mass * st.v[:, 2]) / m_cell,
        n_floor_cell=count(floor < p.radius),
        n_lid_cell=count(p.Lz - floor < p.radius),
        e_kinetic_cell=0.5 * (one_hot @ (p.mass * jnp.sum(st.v * st.v, axis=-1))),
        loss_cell=st.work_cell,
    )


def cell_bounds(model: Model) -> np.ndarray:
    """``(S, k + 1)`` int64: grain ``bounds[s, c]`` is the first of species ``s`` in cell
    ``c`` and ``bounds[s, k]`` the end of the species (grains stored species after species
    and, within a species, cell after cell; :func:`record_row`)."""
    k = model.cells
    rows = [[sl.start + c * ((sl.stop - sl.start) // k) for c in range(k)] + [sl.stop]
            for sl in model.species_slices()]
    return np.array(rows, np.int64)
