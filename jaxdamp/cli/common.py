"""What the commands share: building a configuration from --preset/--config/--set, parsing
lists, printing steady-state estimates, writing TOML."""

from __future__ import annotations

import argparse
import math

from jaxdamp.config import ConfigError, apply_overrides, load_toml


def _number(kind, least, strict):
    def parse(text: str):
        try:
            v = kind(text)
        except ValueError:
            what = "an integer" if kind is int else "a number"
            raise argparse.ArgumentTypeError(f"{text!r} is not {what}") from None
        if not math.isfinite(v) or (v <= least if strict else v < least):
            raise argparse.ArgumentTypeError(
                f"{text}: must be {'>' if strict else '≥'} {least:g}")
        return v

    parse.__name__ = f"{'positive' if strict else 'non-negative'} {kind.__name__}"
    return parse


#: argparse types that refuse zero or negative counts and durations (never a silent default).
positive_int = _number(int, 0, True)
nonnegative_int = _number(int, 0, False)
positive_float = _number(float, 0.0, True)


def base_config(args):
    from jaxdamp.cases import presets

    if args.preset is None and args.config is None:
        raise ConfigError("give --preset NAME or --config FILE.toml (see `jaxdamp presets`)")
    base = presets.get(args.preset) if args.preset else None
    cfg = load_toml(args.config, base) if args.config else base
    return cfg


def run_config(args):
    cfg = base_config(args)
    overrides = list(args.set or [])
    if args.quick:
        # A demo of about a minute on 2 cores: short drive, quick settling, coarser samples.
        overrides = ["numerics.duration=1.0", "numerics.settle_time=0.3", "numerics.chunk=0.1"] + overrides
    if args.frequency is not None:
        overrides.append(f"frequency={args.frequency}")
    if args.duration is not None:
        overrides.append(f"numerics.duration={args.duration}")
    if args.seed is not None:
        overrides.append(f"numerics.seed={args.seed}")
    return apply_overrides(cfg, overrides)


def print_steady(steady: dict, keys=("amplitude", "granular_loss_per_cycle", "phase")) -> None:
    """Print the steady-state estimates of one point (:func:`jaxdamp.analysis.stats.summarise` arrays):
    mean ± SE over replicates, the detected start of the steady state, the batch-means error."""
    import numpy as np

    from jaxdamp.analysis.stats import format_estimate, unit

    a = steady[keys[0]]
    start = np.atleast_1d(a["start"]).ravel()
    ok = np.atleast_1d(a["stationary"]).ravel()
    R = len(start)
    print(f"steady state detected (MSER on per-period amplitude and dissipation) in "
          f"{int(ok.sum())} of {R} replicate(s); starts at t = "
          + ", ".join(f"{t:.3g}" if k else "never" for t, k in zip(start, ok)) + " s")
    for k in keys:
        e = steady[k]
        bse = np.atleast_1d(e["batch_se"]).ravel()
        extra = (f"; within-run batch-means SE {np.nanmean(bse):.2g}"
                 if np.isfinite(bse).any() else "")
        print(f"  {k} = {format_estimate(float(e['mean']), float(e['se']), int(e['n']), unit(k))}"
              + extra)


def replicates(args) -> int:
    R = getattr(args, "replicates", None)
    R = 1 if R is None else R
    if R < 1:
        raise ConfigError(f"--replicates {R}: need at least 1 independent bed")
    return R


def float_list(text):
    try:
        return [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise ConfigError(f"expected a comma-separated list of numbers, got {text!r}") from None


def to_toml(data: dict, prefix: str = "") -> str:
    """Minimal TOML writer for configuration trees (tables, arrays of tables, scalars)."""
    lines, tables = [], []
    for key, value in data.items():
        if isinstance(value, dict):
            tables.append((key, value))
        elif isinstance(value, (list, tuple)) and value and isinstance(value[0], dict):
            tables.append((key, list(value)))
        elif value is None:
            lines.append(f"# {key} = (unset)")
        else:
            lines.append(f"{key} = {_toml_value(value)}")
    out = "\n".join(lines)
    for key, value in tables:
        full = f"{prefix}{key}"
        if isinstance(value, list):
            for item in value:
                out += f"\n\n[[{full}]]\n" + to_toml(item, f"{full}.").lstrip("\n")
        else:
            out += f"\n\n[{full}]\n" + to_toml(value, f"{full}.").lstrip("\n")
    return out.strip("\n") + ("\n" if not prefix else "")


def _toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(v)
