"""Optimiser and search logs (``jaxdamp optimize --out``; ``docs/output.md``).

``jaxdamp-optimize/1``: one row per iterate of the gradient optimiser, appended and flushed as
it runs (:func:`open_log`, :func:`log`); ``jaxdamp-optimize/2``: a scan or trust-region search
with every evaluated point (:func:`write_search`); ``jaxdamp-optimize/3``: a search over
several design variables (:func:`write_design`).
"""

from __future__ import annotations

import json
import time

import h5py
import numpy as np

from jaxdamp.analysis.uncertainty import pm
from jaxdamp.io.common import stamp

#: Iterate fields of the gradient optimiser's log and their units.
LOG_FIELDS = {
    "x": "m", "lz": "m", "objective": "", "objective_se": "", "gradient": "1/m",
    "gradient_se": "1/m", "step": "m", "learning_rate": "m", "wall_time": "s",
    "sim_seconds": "s",
}


def open_log(out, problem, x0, lo, hi, settings, config_json):
    if out is None:
        return None
    h5 = h5py.File(out, "w")
    stamp(h5, "jaxdamp-optimize/1")
    h5.attrs["config"] = config_json or problem.config.to_json()
    h5.attrs["objective"] = problem.objective.to_json(problem.config)
    h5.attrs["variable"] = problem.variable
    h5.attrs["problem"] = json.dumps(problem.describe())
    h5.attrs["settings"] = json.dumps(dict(settings, x0=float(x0), lo=float(lo), hi=float(hi)))
    h5.attrs["status"] = "running"
    g = h5.create_group("iterations")
    for k, unit in LOG_FIELDS.items():
        g.create_dataset(k, shape=(0,), maxshape=(None,), dtype="f8").attrs["units"] = unit
    return h5


def log(h5, hist, x, problem, est, step, lr, t_start, sim_total):
    row = {"x": x, "lz": float(problem.to_lz(x)), "objective": est.value,
           "objective_se": est.value_se, "gradient": est.grad, "gradient_se": est.grad_se,
           "step": step, "learning_rate": lr, "wall_time": time.perf_counter() - t_start,
           "sim_seconds": sim_total}
    for k, v in row.items():
        hist[k].append(float(v))
    if h5 is not None:
        g = h5["iterations"]
        for k, v in row.items():
            ds = g[k]
            ds.resize(ds.shape[0] + 1, axis=0)
            ds[-1] = v
        h5.flush()



def write_status(h5, status) -> None:
    """The result's status by the convergence rule (:class:`jaxdamp.design.status.Status`):
    root attributes ``convergence`` (``converged``, ``not converged`` or ``failed``),
    ``convergence_reason`` (why, in words) and ``iterations``. (``status`` stays the file's
    own: ``running`` or ``finished``.)"""
    h5.attrs["convergence"] = status.state
    h5.attrs["convergence_reason"] = status.reason
    h5.attrs["iterations"] = int(status.iterations)


def write_search(path, cfg, objective, prob, sr, method, sim) -> None:
    """HDF5 log of a scan or trust-region search (``docs/output.md``)."""
    with h5py.File(path, "w") as h:
        stamp(h, "jaxdamp-optimize/2")
        h.attrs["config"] = cfg.to_json()
        h.attrs["objective"] = objective.to_json(cfg)
        h.attrs["variable"] = prob.variable
        h.attrs["method"] = method
        h.attrs["problem"] = json.dumps(prob.describe())
        h.attrs["rounds"] = json.dumps(sr.rounds)
        h.attrs["status"] = "finished"
        g = h.create_group("points")
        for name, data, unit in (("x", sr.x, "m"), ("lz", prob.to_lz(sr.x), "m"),
                                 ("mean", sr.mean, objective.unit), ("se", sr.se, objective.unit),
                                 ("values", sr.J, objective.unit)):
            g.create_dataset(name, data=data).attrs["units"] = unit
        h.attrs["sim_seconds"] = sim
        write_status(h, sr.status)




def write_design(path, cfg, objective, problem, method, result, confirm, settings) -> None:
    """HDF5 log of a search over several design variables (``jaxdamp-optimize/3``,
    ``docs/output.md``): every evaluated system, the iterates (SPSA) and the confirmation."""
    names = list(problem.space.names)
    units = [v.unit for v in problem.space.variables]
    with h5py.File(path, "w") as h:
        stamp(h, "jaxdamp-optimize/3")
        h.attrs["config"] = cfg.to_json()
        h.attrs["objective"] = objective.to_json(cfg)
        h.attrs["variables"] = json.dumps(names)
        h.attrs["units"] = json.dumps(units)
        h.attrs["method"] = method
        h.attrs["problem"] = json.dumps(problem.describe())
        h.attrs["settings"] = json.dumps(settings)
        h.attrs["status"] = "finished"
        h.attrs["sim_seconds"] = problem.sim_seconds
        write_status(h, result.status)
        ev = h.create_group("evaluations")  # every system the search ran
        X = np.concatenate([e["X"] for e in problem.history])
        for name, data, unit in (
                ("X", X, json.dumps(units)),
                ("seed", np.concatenate([e["seeds"] for e in problem.history]), ""),
                ("J", np.concatenate([e["J"] for e in problem.history]), objective.unit)):
            ev.create_dataset(name, data=data).attrs["units"] = unit
        if getattr(result, "history", None) is not None:
            it = h.create_group("iterations")
            for k, v in result.history.items():
                it.create_dataset(k, data=v)
        if confirm is None:  # a failed search: nothing to confirm
            return
        c = h.create_group("confirmation")
        for k in ("X", "mean", "ci95", "J"):
            c.create_dataset(k, data=np.asarray(confirm[k], float)).attrs["units"] = (
                json.dumps(units) if k == "X" else objective.unit)
        c.attrs["labels"] = json.dumps(confirm["labels"])


def describe_lines(h, path: str) -> list[str]:
    """Human-readable overview of an open optimiser or search log (``jaxdamp info``)."""
    fmt = h.attrs.get("format", "?")
    obj = json.loads(h.attrs.get("objective", "{}"))
    what = "maximise" if obj.get("maximise") else "minimise"
    var = h.attrs.get("variables", h.attrs.get("variable", "?"))
    lines = [f"{path}: {fmt} (optimiser log), jaxdamp {h.attrs.get('jaxdamp_version', '?')}",
             f"  {what} {obj.get('kind')} [{obj.get('unit')}] at "
             + ", ".join(f"{f:.4g}" for f in obj.get("frequencies", [])) + f" Hz over {var}"
             + (f" by {h.attrs['method']}" if "method" in h.attrs else " by gradient (optax)")
             + f"; status {h.attrs.get('status')}"]
    if "convergence" in h.attrs:
        state = str(h.attrs["convergence"])
        n = int(h.attrs.get("iterations", 0))
        lines.append(f"  convergence: {state if state == 'converged' else state.upper()} "
                     f"({n} iteration{'' if n == 1 else 's'}): "
                     f"{h.attrs.get('convergence_reason', '')}")
    elif "reason" in h.attrs:
        lines.append(f"  stopped: {h.attrs['reason']}")
    for key in ("optimum", "result"):
        if key in h.attrs:
            lines.append(f"  {key}: " + ", ".join(
                f"{k} = {v:.6g}" if isinstance(v, float) else f"{k} = {v}"
                for k, v in json.loads(h.attrs[key]).items()))
    if "sim_seconds" in h.attrs:
        lines.append(f"  simulated system-seconds: {float(h.attrs['sim_seconds']):.5g}")
    if "iterations" in h:
        k = next(iter(h["iterations"]))
        lines.append(f"  {h['iterations'][k].shape[0]} iterates: "
                     + ", ".join(sorted(h["iterations"])))
    if "points" in h:
        lines.append(f"  {h['points/x'].shape[0]} evaluated points")
    if "confirmation" in h:
        c = h["confirmation"]
        labels = json.loads(c.attrs.get("labels", "[]"))
        for lab, x, m, ci in zip(labels, c["X"][()], c["mean"][()], c["ci95"][()]):
            lines.append(f"  {lab}: {', '.join(f'{v:.5g}' for v in x)} -> {pm(m, ci)}")
    return lines
