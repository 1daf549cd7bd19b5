"""The ``/efficiency`` group of a sweep file (``jaxdamp efficiency``; ``docs/output.md``)."""

from __future__ import annotations

import h5py
import numpy as np

from jaxdamp.io.common import write_steady


def write(path: str, result, transient: int, samples_per_period: int, summary_units: dict,
          per_period_units: dict, phase_units: dict) -> None:
    """Store ``result`` (:class:`jaxdamp.studies.efficiency.EfficiencyResult`) in the ``/efficiency``
    group of the sweep file ``path``; units of its summary, per-period and phase arrays as
    given."""
    with h5py.File(path, "a") as h5:
        if "efficiency" in h5:
            del h5["efficiency"]
        g = h5.create_group("efficiency")
        g.attrs["E_max"] = "4 m A_d^2 omega^2 (Sack et al. 2013 read literally; docs/physics.md §4)"
        g.attrs["energies"] = "J per drive period (the paper's eqs. 4-5 times T)"
        g.attrs["E_d_fit"] = ("linear fit to E_d(t) (one-period integrals from every sample t "
                              "in the window), read at the window's middle")
        g.attrs["transient_periods"] = transient
        g.attrs["samples_per_period"] = samples_per_period
        g.create_dataset("amplitude", data=result.amplitudes).attrs["units"] = "m"
        g.attrs["replicates"] = result.replicates
        if result.steady is not None:
            write_steady(g, result.steady, result.replicates,
                         lambda q: "1/kg" if q.endswith("per_mass") else "1")
        if result.replicate_summary is not None:
            rs = g.create_group("replicate_summary")
            for k, v in result.replicate_summary.items():
                rs.create_dataset(k, data=v).attrs["units"] = summary_units.get(k, "")
        for part, units in (("summary", summary_units), ("per_period", per_period_units),
                            ("phase", phase_units), ("replicate_per_period", per_period_units),
                            ("replicate_phase", phase_units)):
            if getattr(result, part) is None:
                continue
            sub = g.create_group(part)
            for k, v in getattr(result, part).items():
                sub.create_dataset(k, data=v).attrs["units"] = units.get(k, "")


def read(path: str) -> dict:
    """The fields of the :class:`jaxdamp.studies.efficiency.EfficiencyResult` stored by :func:`write`
    (the configuration as JSON under ``config_json``)."""
    from jaxdamp.config import ConfigError

    with h5py.File(path, "r") as h5:
        if "efficiency" not in h5:
            raise ConfigError(f"{path} holds no efficiency analysis (run `jaxdamp efficiency`)")
        g = h5["efficiency"]
        out = {p: {k: g[p][k][()] for k in g[p]} for p in ("summary", "per_period", "phase")}
        out["snapshots"] = ({k: h5["snapshots"][k][()] for k in h5["snapshots"]}
                            if "snapshots" in h5 else None)
        out.update(amplitudes=g["amplitude"][()], config_json=h5.attrs["base_config"],
                   wall_time=float(h5.attrs.get("wall_time", np.nan)), path=path,
                   replicates=int(g.attrs.get("replicates", 1)))
        if "replicate_summary" in g:
            out["replicate_summary"] = {k: g["replicate_summary"][k][()]
                                        for k in g["replicate_summary"]}
        for part in ("replicate_per_period", "replicate_phase"):
            if part in g:
                out[part] = {k: g[part][k][()] for k in g[part]}
        if "steady" in g:
            out["steady"] = {q: {f: g["steady"][q][f][()] for f in g["steady"][q]}
                             for q in g["steady"]}
        return out
