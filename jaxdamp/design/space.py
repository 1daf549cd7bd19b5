"""Designs of several variables: the design space and its replicated DEM objective.

A designer sets more than the box height. :data:`VARIABLES` names the continuous knobs of an
S1 damper that keep the grains (hence one static ``Model``) and so run together in one batch:

* ``Lz`` — the box height [m];
* ``base`` — the side of the square base, ``Lx = Ly`` [m] (the same grains in a wider box
  make a flatter bed);
* ``friction`` — the grains' Coulomb coefficient ``μ`` (every species; grain–grain and, for
  walls without their own material, grain–wall), a coating a designer chooses.

:class:`DesignSpace` is the box ``[lo, hi]`` of the chosen variables with normalised
coordinates ``u ∈ [0, 1]^d`` (every optimiser step is taken there, so that metres and a
friction coefficient are comparable) and **projection** onto the feasible set: the box, and
the bed must fit, ``Lz ≥ h_bed(base) + margin`` with ``h_bed(b) = h_ref (b_ref / b)²`` (the
bed's volume is kept; ``h_ref`` measured on settled beds at the reference base).

:class:`DesignProblem` evaluates the steady objective at scattered designs: every system is
one design with its **own settled bed** (its own seed, :class:`jaxdamp.studies.grid.Points`),
all in one batch through :func:`jaxdamp.studies.sweep.sweep`; seeds are handed out fresh for
every evaluation (independent realisations), and are shared only where the caller asks for
common random numbers (the two members of a difference pair). The steady mean of each system
(or of each pair, over one common window: :func:`jaxdamp.analysis.stats.shared_window`) is
taken after the start detected by MSER. The cost counts simulated system-seconds of the runs
**and of the settling** (every design point needs its own bed here).

Example::

    >>> from jaxdamp.cases import presets
    >>> from jaxdamp.design.space import DesignSpace
    >>> s = DesignSpace.of(presets.get("sanchez2012-optimal"), ("Lz", "base"))
    >>> [round(float(v), 4) for v in s.to_x(s.to_u([0.12, 0.04]))]
    [0.12, 0.04]
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from jaxdamp.analysis.uncertainty import standard_error
from jaxdamp.config import Config, ConfigError, apply_overrides, get_path
from jaxdamp.physics.containers import container
from jaxdamp.validation import validate


@dataclass(frozen=True)
class Variable:
    """A design variable: ``name``, ``unit``, what it means, and how it is read from and
    written to a configuration."""

    name: str
    unit: str
    description: str

    def keys(self, config: Config) -> tuple:
        """The configuration keys this variable sets (the container's lid height, its base —
        :class:`jaxdamp.physics.containers.Container` — or every species' ``μ``)."""
        if self.name == "Lz":
            return (container(config).lid_key,)
        if self.name == "base":
            return container(config).base_keys
        if self.name == "mass_ratio":
            return tuple(f"grains.{i}.mass_ratio" for i in range(len(config.grains)))
        if self.name == "radius":
            return ("grains.0.radius",)
        return tuple(f"grains.{i}.material.mu" for i in range(len(config.grains)))

    def value(self, config: Config) -> float:
        if self.name == "mass_ratio":  # the whole damper's, however the fill is stated
            from jaxdamp.cases.filling import mass_ratio

            return mass_ratio(validate(config))
        return float(get_path(config, self.keys(config)[0]))

    def default_range(self, config: Config) -> tuple:
        """Range searched unless told: ``Lz`` 0.07–0.25 m, ``base`` ±25 % of the preset's
        ``Lx`` (at most 0.8–1.25×), ``friction`` 0.05–0.8, ``mass_ratio`` 0.02–0.2 (the
        thesis' 0.096 inside), ``radius`` ±33 % of the preset's."""
        if self.name == "Lz":
            return 0.07, 0.25
        if self.name in ("base", "radius"):
            v = self.value(config)
            return (0.8 * v, 1.25 * v) if self.name == "base" else (0.67 * v, 1.33 * v)
        if self.name == "mass_ratio":
            return 0.02, 0.2
        return 0.05, 0.8


VARIABLES = {v.name: v for v in (
    Variable("Lz", "m", "box height"),
    Variable("base", "m", "side of the square base, Lx = Ly"),
    Variable("friction", "", "grains' Coulomb friction coefficient (all species)"),
    Variable("mass_ratio", "", "the grains' mass over the primary's mass M (the fill)"),
    Variable("radius", "m", "the grains' radius (one species; the fill kept by mass)"),
)}
#: Variables that change the grains, hence the batch's shape: designs differing in them run in
#: separate batches (:meth:`DesignProblem.measure` groups the rows by their ``Model``).
SHAPING = ("mass_ratio", "radius")


def parse_bounds(text: str | None) -> dict:
    """``"Lz=0.08:0.2,base=0.03:0.045"`` → ``{"Lz": (0.08, 0.2), "base": (0.03, 0.045)}``."""
    out = {}
    for item in (text or "").split(","):
        if not item.strip():
            continue
        try:
            name, rng = item.split("=")
            lo, hi = (float(v) for v in rng.split(":"))
        except ValueError:
            raise ConfigError(f"--bounds {item!r}: expected NAME=LO:HI, e.g. Lz=0.08:0.2") from None
        out[name.strip()] = (lo, hi)
    return out


class DesignSpace:
    """The box ``[lo, hi]`` of named variables, normalised coordinates, projection (module
    doc). ``h_ref`` [m]: settled bed height at ``base_ref``; ``margin`` [m]: least free height
    above the bed."""

    def __init__(self, config: Config, names, lo, hi, h_ref: float = 0.0,
                 base_ref: float | None = None, margin: float = 0.01,
                 mass_ref: float | None = None):
        self.config = config
        self.names = tuple(names)
        self.variables = [VARIABLES[n] for n in self.names]
        self.lo = np.asarray(lo, float)
        self.hi = np.asarray(hi, float)
        self.h_ref = float(h_ref)
        self.base_ref = float(base_ref or VARIABLES["base"].value(config))
        self.mass_ref = float(mass_ref or (VARIABLES["mass_ratio"].value(config)
                                           if "mass_ratio" in self.names else 1.0))
        self.margin = float(margin)

    @classmethod
    def of(cls, config: Config, names, bounds: dict | None = None, **kw) -> "DesignSpace":
        """The space of ``names`` with ``bounds`` (``{name: (lo, hi)}``) or the variables'
        default ranges; refuses unknown names, empty ranges and values a variable cannot
        take, naming the variable and its limit."""
        names = tuple(names)
        bounds = dict(bounds or {})
        unknown = [n for n in list(names) + list(bounds) if n not in VARIABLES]
        if unknown:
            raise ConfigError(f"design variable(s) {', '.join(unknown)}: expected some of "
                              f"{', '.join(VARIABLES)}")
        if len(set(names)) != len(names) or not names:
            raise ConfigError(f"--vars {','.join(names)}: name each design variable once")
        stray = [n for n in bounds if n not in names]
        if stray:
            raise ConfigError(f"--bounds {', '.join(stray)}: not among --vars {','.join(names)}")
        lo, hi = [], []
        for n in names:
            a, b = bounds.get(n, VARIABLES[n].default_range(config))
            if not (a < b):
                raise ConfigError(f"bounds of {n}: lower {a:g} must be below upper {b:g}")
            if a <= 0:
                raise ConfigError(f"bounds of {n}: lower {a:g} must be > 0")
            if n == "friction" and b > 2.0:
                raise ConfigError(f"bounds of friction: upper {b:g} above 2 (a Coulomb "
                                  "coefficient of grains is 0.05–1)")
            lo.append(a)
            hi.append(b)
        return cls(config, names, lo, hi, **kw)

    @property
    def dim(self) -> int:
        return len(self.names)

    def to_x(self, u) -> np.ndarray:
        return self.lo + np.asarray(u, float) * (self.hi - self.lo)

    def to_u(self, x) -> np.ndarray:
        return (np.asarray(x, float) - self.lo) / (self.hi - self.lo)

    def value(self, config: Config | None = None) -> np.ndarray:
        """The design of ``config`` (default: the base configuration) in physical units."""
        c = config or self.config
        return np.array([v.value(c) for v in self.variables])

    def bed_height(self, x) -> float:
        """``h_bed`` of design ``x`` [m] (module doc): ``h_ref (b_ref / b)² (μ / μ_ref)``, the
        bed's volume kept but for the fill (the grains' radius at a fixed mass moves it only
        through the packing fraction, a few per cent: not counted)."""
        x = np.asarray(x, float)
        b = x[self.names.index("base")] if "base" in self.names else self.base_ref
        mu = x[self.names.index("mass_ratio")] / self.mass_ref if "mass_ratio" in self.names \
            else 1.0
        return self.h_ref * (self.base_ref / b) ** 2 * mu

    def project(self, u, shrink: float = 0.0) -> np.ndarray:
        """Nearest feasible ``u``: inside ``[shrink, 1 − shrink]`` (room for perturbations of
        size ``shrink``) with the bed fitting at every point within ``shrink``."""
        u = np.clip(np.asarray(u, float), shrink, 1.0 - shrink)
        x = self.to_x(u)
        if "Lz" in self.names and self.h_ref > 0:
            i = self.names.index("Lz")
            xb = x.copy()
            if "base" in self.names:  # the narrowest base within the perturbation
                j = self.names.index("base")
                xb[j] = self.to_x(np.maximum(u - shrink, 0.0))[j]
            need = self.bed_height(xb) + self.margin + shrink * (self.hi[i] - self.lo[i])
            if x[i] < need:
                x[i] = need
                if need > self.hi[i] - shrink * (self.hi[i] - self.lo[i]):
                    raise ConfigError(f"no feasible design: the bed ({self.bed_height(xb):.4g} "
                                      f"m) plus margin does not fit below Lz = {self.hi[i]:.4g} m")
            u = self.to_u(x)
        return u

    def overrides(self, x) -> dict:
        out = {}
        for v, val in zip(self.variables, np.asarray(x, float)):
            out.update({k: float(val) for k in v.keys(self.config)})
        return out

    def describe(self) -> dict:
        return {"variables": list(self.names), "units": [v.unit for v in self.variables],
                "lo": self.lo.tolist(), "hi": self.hi.tolist(), "h_ref": self.h_ref,
                "base_ref": self.base_ref, "mass_ref": self.mass_ref, "margin": self.margin}


def stated_by_mass(config: Config) -> Config:
    """``config`` with every species' fill stated by its ``mass_ratio`` (the mass its count or
    fraction gives): the fill a change of radius, density or cavity keeps."""
    from jaxdamp.cases.filling import mass_ratio

    cfg = validate(config)
    return apply_overrides(cfg, {
        f"grains.{i}.mass_ratio": mass_ratio(dataclasses.replace(cfg, grains=(sp,)))
        for i, sp in enumerate(cfg.grains)})


class DesignProblem:
    """Replicated steady-state objective of an S1 damper at scattered designs (module doc).

    Args:
      config: an S1 configuration, e.g. ``sanchez2012-optimal``.
      objective: :class:`~jaxdamp.design.objectives.Objective`.
      names: design variables (keys of :data:`VARIABLES`).
      bounds: ``{name: (lo, hi)}`` (default: the variables' default ranges).
      duration: simulated time per system [s] (transient + steady part).
      seed: first seed handed out; every evaluation takes fresh ones after it.
      margin: least free height above the bed [m].
    """

    def __init__(self, config: Config, objective, names=("Lz", "base", "friction"),
                 bounds: dict | None = None, duration: float = 3.0, seed: int = 0,
                 margin: float = 0.01, progress: bool = False):
        from jaxdamp.engine.packing import settle_many
        from jaxdamp.physics.model import build

        if config.system != "primary":
            raise ConfigError("a design of several variables needs an S1 configuration "
                              "(system = 'primary')")
        if not duration > 0:
            raise ConfigError(f"duration = {duration}: must be > 0 s")
        if "radius" in names and len(config.grains) != 1:
            raise ConfigError(f"design variable radius: one species only ({len(config.grains)} "
                              "given; a mixture's radii are not one knob)")
        config = apply_overrides(config, {"numerics.duration": float(duration)})
        if any(v in SHAPING for v in names):  # the fill stated by mass: a new radius keeps it
            config = stated_by_mass(config)
        self.config = validate(config)
        self.objective = objective
        self.freqs = objective.frequencies(self.config)
        #: What each design runs at, one dict of overrides per condition, its bed shared (here
        #: the objective's frequencies; an envelope's points in :mod:`jaxdamp.design.envelope`).
        self.conditions = [{"frequency": float(f)} for f in self.freqs]
        self.duration = float(duration)
        self.progress = progress
        self.settle_time = self.config.numerics.settle_time
        self._seed = int(seed)
        self.sim_seconds = 0.0
        self.history: list[dict] = []
        t0 = time.perf_counter()
        model, p = build(self.config)
        ref = settle_many([self.config], model, [p])[0]  # the reference bed: h_ref
        self.sim_seconds += self.settle_time
        self.settle_wall = time.perf_counter() - t0
        self.space = DesignSpace.of(self.config, names, bounds, h_ref=ref.height,
                                    base_ref=VARIABLES["base"].value(self.config),
                                    margin=margin)

    variable = "design"

    def seeds(self, n: int) -> np.ndarray:
        """``n`` fresh seeds (never handed out before by this problem)."""
        s = np.arange(self._seed, self._seed + n)
        self._seed += n
        return s

    def measure(self, X, seeds, pairs: bool = False) -> dict:
        """Objective of every design ``X`` ``(n, d)`` [physical units] with its own bed
        ``seeds`` ``(n,)`` at every condition (:attr:`conditions`: the objective's
        frequencies; an envelope's points, :mod:`jaxdamp.design.envelope`), the bed shared by
        a design's conditions. One batch, or one per shape where the designs change the grains
        (:data:`SHAPING`: rows grouped by the grains they validate to). ``pairs``: rows ``2k``
        and ``2k+1`` share a seed and one common steady window (a difference pair). Returns
        ``{"J": (n,), "Z", "E": (C, n), "stationary": (n,) bool, "sim_seconds", "wall"}``
        (``J``: :meth:`combine` of each row)."""
        from jaxdamp.analysis import stats
        from jaxdamp.studies.grid import Points, grid_configs
        from jaxdamp.studies.sweep import sweep

        X = np.atleast_2d(np.asarray(X, float))
        n, C = len(X), len(self.conditions)
        seeds = [int(s) for s in seeds]
        rows = [{**self.space.overrides(x), **cond, "numerics.seed": s}
                for cond in self.conditions for x, s in zip(X, seeds)]  # condition-major
        shaping = any(v in SHAPING for v in self.space.names)
        key = [()] * len(rows)
        if shaping:  # the grains each row validates to: one batch per distinct set
            cfgs = grid_configs(self.config, Points({k: [r[k] for r in rows] for k in rows[0]}))
            key = [tuple((sp.count, sp.radius, sp.radius_spread) for sp in c.grains)
                   for c in cfgs]
        t0 = time.perf_counter()
        recs: dict = {}
        for k in dict.fromkeys(key):
            idx = [i for i, kk in enumerate(key) if kk == k]
            res = sweep(self.config, Points({c: [rows[i][c] for i in idx] for c in rows[0]}),
                        progress=self.progress, echo=None)
            for name in ("t", "z_box", "work"):
                a = np.asarray(res.records[name])
                recs.setdefault(name, np.empty((len(rows),) + a.shape[1:], a.dtype))[idx] = a
        Z, E = np.empty((C, n)), np.empty((C, n))
        ok = np.ones(n, bool)
        groups = [[2 * k, 2 * k + 1] for k in range(n // 2)] if pairs else [[i] for i in range(n)]
        for ci, cond in enumerate(self.conditions):
            for g in groups:
                w = stats.rows_window(recs, [ci * n + i for i in g], cond["frequency"])
                Z[ci, g] = w["amplitude"]
                E[ci, g] = w["granular_loss_per_cycle"]
                ok[g] &= w["stationary"]
        J = np.asarray(self.combine(Z, E), float)
        geo = [i for i, nm in enumerate(self.space.names) if nm != "Lz"]  # Lz keeps the bed
        beds = len({(s, tuple(np.round(x[geo], 12))) for x, s in zip(X, seeds)})
        cost = C * n * self.duration + beds * self.settle_time
        self.sim_seconds += cost
        out = {"X": X, "seeds": np.asarray(seeds), "J": J, "Z": Z, "E": E, "stationary": ok,
               "sim_seconds": cost, "wall": time.perf_counter() - t0}
        self.history.append(out)
        return out

    def combine(self, Z, E):
        """The objective of each row from its amplitudes ``Z`` and dissipations ``E`` ``(C,
        n)`` at the conditions (the objective's frequencies)."""
        return self.objective.combine(Z, E, self.freqs)

    def cost_per_system(self) -> float:
        """Simulated system-seconds of one design evaluated once (run + its bed)."""
        return len(self.conditions) * self.duration + self.settle_time

    def evaluate(self, X, replicates: int) -> dict:
        """Every design of ``X`` ``(n, d)`` on ``replicates`` fresh independent beds, one
        batch: ``{"mean", "se", "ci95" (n,), "J" (n, R), "stationary" (n, R), "sim_seconds"}``
        (95 % Student-t intervals across the beds)."""
        from jaxdamp.analysis.stats import t_quantile

        X = np.atleast_2d(np.asarray(X, float))
        R = int(replicates)
        if R < 1:
            raise ConfigError(f"replicates = {R}: need at least 1")
        rows = np.repeat(X, R, axis=0)
        m = self.measure(rows, self.seeds(len(rows)))
        J = m["J"].reshape(len(X), R)
        se = standard_error(J, axis=1) if R > 1 else np.full(len(X), np.nan)
        half = t_quantile(0.975, R - 1) * se if R > 1 else se
        return {"mean": J.mean(axis=1), "se": se, "ci95": half, "J": J,
                "stationary": m["stationary"].reshape(len(X), R), "sim_seconds": m["sim_seconds"]}

    def describe(self) -> dict:
        return {"model": "DEM", "estimator": "replicated steady states, one bed per design",
                "duration": self.duration, "settle_time": self.settle_time,
                "frequencies": list(self.freqs), "space": self.space.describe(),
                "detection": "MSER on per-period amplitude and dissipation"}
