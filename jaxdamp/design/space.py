"""Designs of several variables: the design space and its replicated DEM objective.

A designer sets more than the box height. :data:`VARIABLES` names the knobs of an S1 damper.
Three keep the grains (hence one static ``Model``) and so run together in one batch:

* ``Lz`` — the box height [m];
* ``base`` — the side of the square base, ``Lx = Ly`` [m], or a cylinder's radius (the same
  grains in a wider cavity make a flatter bed);
* ``friction`` — the grains' Coulomb coefficient ``μ`` (every species; grain–grain and, for
  walls without their own material, grain–wall), a coating a designer chooses.

Four change the grains (:data:`SHAPING`; the fill is then stated by mass,
:func:`stated_by_mass`, and the designs of one grain set run in a batch of their own):

* ``mass_ratio`` — the fill, the grains' mass over the primary's mass;
* ``radius`` — the grains' radius [m] (one species), at the same mass;
* ``material`` — the grains' material, categorical over the material table (or the
  choices given), at the same mass;
* ``cells`` — the number of identical cells (integer), the mass shared among them.

A discrete variable of ``K`` values takes value ``k`` on ``u ∈ [k/K, (k+1)/K)``.

:class:`DesignSpace` is the box ``[lo, hi]`` of the chosen variables with normalised
coordinates ``u ∈ [0, 1]^d`` (every optimiser step is taken there, so that metres and a
friction coefficient are comparable) and **projection** onto the feasible set: the box, and
the bed must fit, ``Lz ≥ h_bed(x) + margin`` with ``h_bed = h_ref (b_ref / b)²`` (the bed's
volume is kept; ``h_ref`` measured on settled beds at the reference base) times the fill's,
the inverse density's and the inverse cell count's ratios to the reference.

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
    #: ``"real"``, ``"integer"`` (rounded) or ``"choice"`` (a categorical variable: its value
    #: is the index of one of :attr:`DesignSpace.choices`, its coordinate spread evenly).
    kind: str = "real"

    def keys(self, config: Config) -> tuple:
        """The configuration keys this variable sets (the container's lid height, its base —
        :class:`jaxdamp.physics.containers.Container` — every species' ``μ``, fill or
        material, the first species' radius, the cells)."""
        n = range(len(config.grains))
        if self.name == "Lz":
            return (container(config).lid_key,)
        if self.name == "base":
            return container(config).base_keys
        if self.name == "mass_ratio":
            return tuple(f"grains.{i}.mass_ratio" for i in n)
        if self.name == "radius":
            return ("grains.0.radius",)
        if self.name == "material":
            return tuple(f"grains.{i}.material" for i in n)
        if self.name == "cells":
            return ("cells",)
        return tuple(f"grains.{i}.material.mu" for i in n)

    def value(self, config: Config) -> float:
        """The variable's value in ``config`` (a material: the name of the table's entry the
        first species' material is, :func:`material_name`)."""
        if self.name == "mass_ratio":  # the whole damper's, however the fill is stated
            from jaxdamp.cases.filling import mass_ratio

            return mass_ratio(validate(config))
        if self.name == "material":
            return material_name(config.grains[0].material)
        return float(get_path(config, self.keys(config)[0]))

    def default_range(self, config: Config) -> tuple:
        """Range searched unless told: ``Lz`` 0.07–0.25 m, ``base`` ±25 % of the preset's
        ``Lx`` (at most 0.8–1.25×), ``friction`` 0.05–0.8, ``mass_ratio`` 0.02–0.2 (the
        thesis' 0.096 inside), ``radius`` ±33 % of the preset's, ``cells`` 1–8; ``material``:
        every entry of the material table."""
        if self.name == "Lz":
            return 0.07, 0.25
        if self.name == "material":
            from jaxdamp import materials

            return materials.names()
        if self.name == "cells":
            return 1, 8
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
    Variable("material", "", "the grains' material from the material table (every species; "
             "the fill kept by mass)", kind="choice"),
    Variable("cells", "", "identical cells of the damper, each its own cavity and bed (the "
             "fill kept by mass)", kind="integer"),
)}
#: Variables that change the grains, hence the batch's shape: designs differing in them run in
#: separate batches (:meth:`DesignProblem.measure` groups the rows by the grains they give).
SHAPING = ("mass_ratio", "radius", "material", "cells")


def material_name(material) -> str:
    """The material table's name of ``material`` (a resolved :class:`~jaxdamp.config.Material`:
    its density and modulus match the entry's), or a :class:`ConfigError` for one not from
    the table."""
    from jaxdamp import materials

    for name in materials.names():
        f = materials.lookup(name).fields()
        if material.density == f["density"] and material.E == f["E"]:
            return name
    raise ConfigError(f"design variable material: the grains' material (E = {material.E:g} Pa, "
                      f"density {material.density:g} kg/m³) is not an entry of the material "
                      f"table ({', '.join(materials.names())}); set it by name first")


def parse_bounds(text: str | None) -> dict:
    """``"Lz=0.08:0.2,base=0.03:0.045"`` → ``{"Lz": (0.08, 0.2), "base": (0.03, 0.045)}``; a
    categorical variable's choices by name, ``"material=steel/glass/lead"`` →
    ``{"material": ("steel", "glass", "lead")}``."""
    out = {}
    for item in (text or "").split(","):
        if not item.strip():
            continue
        name, _, rng = item.partition("=")
        if name.strip() in VARIABLES and VARIABLES[name.strip()].kind == "choice":
            out[name.strip()] = tuple(v.strip() for v in rng.split("/") if v.strip())
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
                 mass_ref: float | None = None, choices: dict | None = None):
        self.config = config
        self.names = tuple(names)
        self.variables = [VARIABLES[n] for n in self.names]
        #: a categorical variable's values by name; its design value is the index
        self.choices = dict(choices or {})
        self.density_ref = config.grains[0].material.density if config.grains else 1.0
        self.cells_ref = config.cells
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
        lo, hi, choices = [], [], {}
        for n in names:
            if VARIABLES[n].kind == "choice":
                from jaxdamp import materials

                names_n = tuple(bounds.get(n, VARIABLES[n].default_range(config)))
                bad = [c for c in names_n if c not in materials.names()]
                if bad or len(names_n) < 2:
                    raise ConfigError(f"bounds of {n}: give two or more of "
                                      f"{', '.join(materials.names())} as NAME/NAME/..."
                                      + (f" ({', '.join(bad)} not in the table)" if bad else ""))
                choices[n] = names_n
                lo.append(0.0)
                hi.append(float(len(names_n) - 1))
                continue
            a, b = bounds.get(n, VARIABLES[n].default_range(config))
            if VARIABLES[n].kind == "integer" and (a != int(a) or b != int(b) or a < 1):
                raise ConfigError(f"bounds of {n}: whole numbers ≥ 1, got {a:g}:{b:g}")
            if not (a < b):
                raise ConfigError(f"bounds of {n}: lower {a:g} must be below upper {b:g}")
            if a <= 0:
                raise ConfigError(f"bounds of {n}: lower {a:g} must be > 0")
            if n == "friction" and b > 2.0:
                raise ConfigError(f"bounds of friction: upper {b:g} above 2 (a Coulomb "
                                  "coefficient of grains is 0.05–1)")
            lo.append(a)
            hi.append(b)
        return cls(config, names, lo, hi, choices=choices, **kw)

    @property
    def dim(self) -> int:
        return len(self.names)

    def _discrete(self):
        """Columns of integer and categorical variables and their counts of values."""
        return [(i, int(round(self.hi[i] - self.lo[i])) + 1)
                for i, v in enumerate(self.variables) if v.kind != "real"]

    def to_x(self, u) -> np.ndarray:
        """Physical design of normalised ``u``; an integer or categorical variable of ``K``
        values takes value ``k`` on ``u ∈ [k/K, (k+1)/K)`` (each value an equal share)."""
        u = np.asarray(u, float)
        x = self.lo + u * (self.hi - self.lo)
        for i, K in self._discrete():
            x[..., i] = self.lo[i] + np.minimum(np.floor(u[..., i] * K), K - 1)
        return x

    def to_u(self, x) -> np.ndarray:
        """Normalised coordinates of ``x`` (a discrete value at the middle of its share)."""
        x = np.asarray(x, float)
        u = (x - self.lo) / (self.hi - self.lo)
        for i, K in self._discrete():
            u[..., i] = (x[..., i] - self.lo[i] + 0.5) / K
        return u

    def value(self, config: Config | None = None) -> np.ndarray:
        """The design of ``config`` (default: the base configuration) in physical units (a
        categorical variable: the index of its value among :attr:`choices`)."""
        c = config or self.config
        out = []
        for v in self.variables:
            val = v.value(c)
            if v.kind == "choice":
                if val not in self.choices[v.name]:
                    raise ConfigError(f"design variable {v.name}: the configuration's {val!r} "
                                      f"is not among the choices {self.choices[v.name]}")
                val = self.choices[v.name].index(val)
            out.append(val)
        return np.array(out, float)

    def label(self, x) -> list:
        """``["Lz = 0.12 m", "material = glass", ...]`` of design ``x``."""
        out = []
        for v, val in zip(self.variables, np.asarray(x, float)):
            if v.kind == "choice":
                out.append(f"{v.name} = {self.choices[v.name][int(val)]}")
            elif v.kind == "integer":
                out.append(f"{v.name} = {int(val)}")
            else:
                out.append(f"{v.name} = {val:.5g}{(' ' + v.unit) if v.unit else ''}")
        return out

    def bed_height(self, x) -> float:
        """``h_bed`` of design ``x`` [m] (module doc): ``h_ref (b_ref / b)² (μ / μ_ref)``, the
        bed's volume kept but for the fill (the grains' radius at a fixed mass moves it only
        through the packing fraction, a few per cent: not counted)."""
        x = np.asarray(x, float)
        b = x[self.names.index("base")] if "base" in self.names else self.base_ref
        mu = x[self.names.index("mass_ratio")] / self.mass_ref if "mass_ratio" in self.names \
            else 1.0
        if "material" in self.names:  # the same mass of a lighter material: a taller bed
            from jaxdamp import materials

            name = self.choices["material"][int(x[self.names.index("material")])]
            mu *= self.density_ref / materials.lookup(name).fields()["density"]
        if "cells" in self.names:  # the mass shared by more cells: a lower bed in each
            mu *= self.cells_ref / x[self.names.index("cells")]
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
        """The configuration keys of design ``x`` and their values (a material by name, set
        before any ``μ`` so that a friction variable applies to it)."""
        first, out = {}, {}
        for v, val in zip(self.variables, np.asarray(x, float)):
            if v.kind == "choice":
                first.update({k: self.choices[v.name][int(val)] for k in v.keys(self.config)})
            else:
                out.update({k: int(val) if v.kind == "integer" else float(val)
                            for k in v.keys(self.config)})
        return {**first, **out}

    def describe(self) -> dict:
        return {"variables": list(self.names), "units": [v.unit for v in self.variables],
                "lo": self.lo.tolist(), "hi": self.hi.tolist(), "h_ref": self.h_ref,
                "base_ref": self.base_ref, "mass_ref": self.mass_ref, "margin": self.margin,
                "choices": {k: list(v) for k, v in self.choices.items()}}


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
        ``{"J": (n,), "Z", "E": (C, n), "stationary": (n,) bool (at every condition),
        "stationary_each": (C, n) bool, "sim_seconds", "wall"}`` (``J``: :meth:`combine` of
        each row)."""
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
            key = [(c.cells,) + tuple((sp.count, sp.radius, sp.radius_spread)
                                      for sp in c.grains) for c in cfgs]
        t0 = time.perf_counter()
        recs: dict = {name: [None] * len(rows) for name in ("t", "z_box", "work")}
        for k in dict.fromkeys(key):  # per row: batches may differ in dt, hence in samples
            idx = [i for i, kk in enumerate(key) if kk == k]
            res = sweep(self.config, Points({c: [rows[i][c] for i in idx] for c in rows[0]}),
                        progress=self.progress, echo=None)
            for name in recs:
                for j, i in enumerate(idx):
                    recs[name][i] = np.asarray(res.records[name][j])
        Z, E = np.empty((C, n)), np.empty((C, n))
        each = np.ones((C, n), bool)
        groups = [[2 * k, 2 * k + 1] for k in range(n // 2)] if pairs else [[i] for i in range(n)]
        for ci, cond in enumerate(self.conditions):
            for g in groups:
                w = stats.rows_window(recs, [ci * n + i for i in g], cond["frequency"])
                Z[ci, g] = w["amplitude"]
                E[ci, g] = w["granular_loss_per_cycle"]
                each[ci, g] = w["stationary"]
        ok = each.all(axis=0)
        J = np.asarray(self.combine(Z, E), float)
        geo = [i for i, nm in enumerate(self.space.names) if nm != "Lz"]  # Lz keeps the bed
        beds = len({(s, tuple(np.round(x[geo], 12))) for x, s in zip(X, seeds)})
        cost = C * n * self.duration + beds * self.settle_time
        self.sim_seconds += cost
        out = {"X": X, "seeds": np.asarray(seeds), "J": J, "Z": Z, "E": E, "stationary": ok,
               "stationary_each": each, "sim_seconds": cost, "wall": time.perf_counter() - t0}
        self.history.append(out)
        return out

    def combine(self, Z, E):
        """The objective of each row from its amplitudes ``Z`` and dissipations ``E`` ``(C,
        n)`` at the conditions (the objective's frequencies)."""
        return self.objective.combine(Z, E, self.freqs)

    #: Beds per design of :meth:`scan`.
    scan_replicates = 2

    def scan(self, xs):
        """The searches' interface in one variable (:func:`jaxdamp.design.search.trust_region`,
        :func:`~jaxdamp.design.search.adaptive_scan`): every design of ``xs`` on
        :attr:`scan_replicates` fresh beds, ``(mean (L,), se (L,), J (L, R))`` (:meth:`evaluate`'s
        ``J``: each bed's value)."""
        if self.space.dim != 1 or self.space.variables[0].kind != "real":
            raise ConfigError(f"scan: one continuous design variable (the space has "
                              f"{', '.join(self.space.names)})")
        ev = self.evaluate(np.asarray(xs, float)[:, None], self.scan_replicates)
        return ev["mean"], ev["se"], ev["J"]

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
