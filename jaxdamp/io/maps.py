"""The ``/map`` group of a sweep file (``jaxdamp map``; :mod:`jaxdamp.studies.maps`;
``docs/output.md``): per quantity the values of every grid point and bed ``(A, F, R)`` with
their units, the mean and standard error over beds ``(A, F)``, each bed's steady start and
whether it was detected stationary."""

from __future__ import annotations

import h5py
import numpy as np

from jaxdamp.io.common import put


def write(path: str, field, periods: int, transient: int, units: dict, labels: dict) -> None:
    """Store ``field`` (:class:`jaxdamp.studies.maps.EffectiveField`) in the ``/map`` group of
    the sweep file ``path`` (replacing one there); the quantities' ``units`` and ``labels``
    (:data:`jaxdamp.studies.maps.UNITS`, :data:`~jaxdamp.studies.maps.LABELS`)."""
    with h5py.File(path, "a") as h5:
        if "map" in h5:
            del h5["map"]
        put_map(h5, field, periods, transient, units, labels)


def put_map(h5, field, periods: int, transient: int, units: dict, labels: dict):
    """The ``map`` group of ``field`` created in the open file or group ``h5`` (a sweep file's,
    or a study's ``data.h5``) and returned: the one layout :func:`fields` reads back."""
    g = h5.create_group("map")
    g.attrs.update(periods=periods, transient=transient, grain_mass=field.grain_mass,
                   replicates=field.replicates, config=field.config.to_json(),
                   wall_time=field.wall_time,
                   motion="z = A cos(2 pi f t), the damper alone (system driven)",
                   force="first harmonic F = (m_eff W^2 - i W c_eff) Z of the grains' "
                         "force on the container along its axis")
    put(g, "amplitude", field.amplitudes, "m")
    put(g, "frequency", field.frequencies, "Hz")
    dims = "amplitude, frequency, replicate"
    put(g, "stationary", field.stationary, "1", dims=dims)
    put(g, "start", field.start, "s", dims=dims,
        what="each bed's steady start (MSER on its per-period losses), or where its "
             "fixed fallback window began")
    for q, unit in units.items():
        put(g, f"values/{q}", field.values[q], unit, dims=dims, what=labels[q])
        put(g, f"mean/{q}", field.mean(q), unit, dims="amplitude, frequency")
        put(g, f"se/{q}", field.se(q), unit, dims="amplitude, frequency",
            what="standard error over the beds")
    return g


def fields(g) -> dict:
    """The fields of the :class:`jaxdamp.studies.maps.EffectiveField` in a ``map`` group
    :func:`put_map` wrote — an open h5py group, or the same group as
    :func:`jaxdamp.io.study.load` reads it (``config`` then already parsed); the configuration
    under ``config`` as JSON text or a dict (:func:`jaxdamp.studies.maps.from_group` builds the
    map)."""
    return dict(amplitudes=np.asarray(g["amplitude"][()]),
                frequencies=np.asarray(g["frequency"][()]),
                values={q: np.asarray(g["values"][q][()]) for q in g["values"]},
                stationary=np.asarray(g["stationary"][()], bool),
                start=np.asarray(g["start"][()]), grain_mass=float(g.attrs["grain_mass"]),
                config=g.attrs["config"], wall_time=float(g.attrs["wall_time"]))


def read(path: str) -> dict:
    """:func:`fields` of the ``/map`` group of the sweep file ``path``."""
    from jaxdamp.config import ConfigError

    with h5py.File(path, "r") as h5:
        if "map" not in h5:
            raise ConfigError(f"{path} holds no map (write one with `jaxdamp map --out FILE`)")
        return fields(h5["map"])
