"""What the commands share: building a configuration from --preset/--config/--set, parsing
lists, the checks of every output file before any compute (:func:`check_outputs`), printing
steady-state estimates, writing TOML."""

from __future__ import annotations

import argparse
import math
import os

from jaxdamp.config import ConfigError, apply_overrides, load_toml


def _number(kind, least, strict):
    def parse(text: str):
        try:
            v = kind(text)
        except ValueError:
            what = "an integer" if kind is int else "a number"
            raise argparse.ArgumentTypeError(f"{text!r} is not {what}") from None
        if least is None and not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"{text}: must be a finite number")
        if least is not None and (not math.isfinite(v) or (v <= least if strict else v < least)):
            raise argparse.ArgumentTypeError(
                f"{text}: must be {'>' if strict else '≥'} {least:g}")
        return v

    parse.__name__ = ("finite number" if least is None else
                      f"{'positive' if strict else 'non-negative'} {kind.__name__}")
    return parse


#: argparse types that refuse zero or negative counts and durations (never a silent default).
positive_int = _number(int, 0, True)
nonnegative_int = _number(int, 0, False)
positive_float = _number(float, 0.0, True)
#: argparse type of a real option of any sign (a time, a phase): ``nan`` and ``±inf`` refused.
finite_float = _number(float, None, False)


class OutputError(ConfigError):
    """An output file cannot be written, or would replace an existing file."""


def add_config_options(parser, preset: str = "a named reference case (list: `jaxdamp presets`)",
                       example: str = "box.Lz=0.1") -> None:
    """The options that build a command's configuration (:func:`command_config`): ``--preset``
    (its help: ``preset``), ``--config``, ``--set`` (its example: ``example``)."""
    parser.add_argument("--preset", help=preset)
    parser.add_argument("--config", metavar="FILE",
                        help="TOML configuration (its keys override the preset's)")
    parser.add_argument("--set", action="append", metavar="KEY=VALUE",
                        help=f"override one value by dotted key (repeatable), e.g. {example}")


def add_no_progress(parser) -> None:
    """``--no-progress``: no progress bars (logs, batch jobs)."""
    parser.add_argument("--no-progress", action="store_true",
                        help="no progress bars (for logs and batch jobs)")


def add_overwrite(parser, resume: bool = False) -> None:
    """The ``--overwrite`` flag of a command that writes files (with ``resume``: the command
    also has ``--resume``, which keeps its checkpoint file instead)."""
    parser.add_argument(
        "--overwrite", action="store_true",
        help="replace output files that already exist (default: refuse, leaving them untouched"
             + ("; --resume continues a checkpoint instead)" if resume else ")"))


def check_outputs(paths, overwrite: bool = False, keep=(), resumable=(),
                  new_folders: bool = False) -> None:
    """Refuse, before any compute, to write any of ``paths`` (``None`` entries are skipped):

    * its folder must exist, be a folder and accept a new file (tried, not guessed from the
      permission bits: root may write where the bits say no, a read-only mount refuses all);
      with ``new_folders`` (``export``, whose VTK frames fill a folder of their own) a missing
      folder is fine when its nearest existing parent is a folder that accepts one (the
      writer creates it);
    * the path must not be a folder;
    * an existing file is replaced only with ``overwrite`` (the ``--overwrite`` flag) or when
      it is in ``keep`` (a checkpoint the command continues, e.g. ``--resume``), and must then
      be writable; for a file in ``resumable`` the message also suggests ``--resume``.

    Every path that passes is then claimed for this process (:func:`jaxdamp.io.claims.claim`,
    held to the end of the command): a second process given the same output is refused here,
    before either computes, instead of truncating the file the first one writes.

    Raises :class:`OutputError` (or :class:`~jaxdamp.io.claims.FileBusy`) naming the file and
    the flag; nothing is created or changed."""
    from jaxdamp.io import claims

    keep = {os.path.abspath(os.fspath(k)) for k in keep if k is not None}
    resumable = {os.path.abspath(os.fspath(k)) for k in resumable if k is not None}
    taken = []
    try:
        for path in paths:
            if path is None or claims.held(path) and os.path.abspath(path) in taken:
                continue
            path = os.fspath(path)
            _check_folder(path, new_folders)
            if not claims.held(path):  # before the existence check: a file being written by
                claims.claim(path)     # another process is named as such
                taken.append(os.path.abspath(path))
            _check_existing(path, overwrite, keep, resumable)
    except BaseException:
        for full in taken:
            claims.release(full)
        raise


def _check_folder(path: str, new_folders: bool) -> None:
    import tempfile

    full = os.path.abspath(path)
    folder = os.path.dirname(full)
    shown = os.path.dirname(path) or "."
    if new_folders:
        while not os.path.exists(folder) and os.path.dirname(folder) != folder:
            folder = os.path.dirname(folder)
        shown = folder
    if not os.path.exists(folder):
        raise OutputError(f"{path}: the folder {shown}/ does not exist (create it first)")
    if not os.path.isdir(folder):
        raise OutputError(f"{path}: {shown} is not a folder")
    if os.path.isdir(full):
        raise OutputError(f"{path} is a folder; name a file to write")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as err:
        raise OutputError(f"{path}: cannot write into the folder {shown}/ "
                          f"({err.strerror or err})") from None


def _check_existing(path: str, overwrite: bool, keep: set, resumable: set) -> None:
    full = os.path.abspath(path)
    if os.path.lexists(full):
        if full not in keep and not overwrite:
            raise OutputError(
                f"{path} already exists; give --overwrite to replace it"
                + (" or --resume to continue its checkpoint" if full in resumable else "")
                + " (it was left untouched)")
        if not os.access(full, os.W_OK):
            raise OutputError(f"{path} exists and is not writable")


def resume_or_overwrite(args) -> list:
    """The outputs a ``--resume`` may continue (``[args.out]``, or none); ``--resume`` with
    ``--overwrite`` is a contradiction (continue the file, or replace it)."""
    if getattr(args, "resume", False) and getattr(args, "overwrite", False):
        raise ConfigError("--resume continues the file and --overwrite replaces it: give one")
    if getattr(args, "resume", False) and not args.out:
        raise ConfigError("--resume needs --out FILE.h5 (the file to continue)")
    if not getattr(args, "resume", False):
        return []
    _check_resumable(args)
    return [args.out]


def _check_resumable(args) -> None:
    """The file ``--resume`` continues exists, is HDF5 (not cut short) and of the family the
    command writes — a run file for ``run``, a sweep file for ``run --replicates`` and the
    sweeps — else one line naming it (before JAX)."""
    from jaxdamp.io.describe import FAMILIES, file_family, what_file
    from jaxdamp.io.export import open_output

    out = args.out
    if not os.path.exists(out):
        raise ConfigError(f"--resume: no file at {out!r} to continue (run without --resume to "
                          "start it)")
    single = args.command == "run" and (getattr(args, "replicates", None) or 1) == 1
    family = "jaxdamp-run" if single else "jaxdamp-sweep"
    try:
        with open_output(out) as h5:
            have, what = file_family(h5), what_file(h5)
    except ConfigError as err:
        raise ConfigError(f"--resume: {err}") from None
    if have != family:
        raise ConfigError(f"--resume: {out} is {what}; `jaxdamp {args.command}"
                          + (" --replicates" if args.command == "run" and not single else "")
                          + f" --resume` continues {FAMILIES[family][0].split(' (')[0]}")


def say_written(*paths) -> None:
    """``wrote a and b`` for the outputs that were asked for (``None``: not asked)."""
    written = [x for x in paths if x]
    if written:
        print("wrote " + " and ".join(written))


def base_config(args):
    from jaxdamp.cases import presets

    if args.preset is None and args.config is None:
        raise ConfigError("give --preset NAME or --config FILE.toml (see `jaxdamp presets`)")
    base = presets.get(args.preset) if args.preset else None
    cfg = load_toml(args.config, base) if args.config else base
    return cfg


def command_config(args, quick=(), options=()):
    """The configuration a command runs: ``--preset``/``--config``, then (with ``--quick``) the
    command's ``quick`` overrides, then the user's ``--set`` (which win over them), then the
    command's own ``options`` as overrides (``None`` entries: options not given)."""
    overrides = list(quick) if getattr(args, "quick", False) else []
    overrides += list(args.set or []) + [o for o in options if o is not None]
    return apply_overrides(base_config(args), overrides)


def _given(key, value):
    return None if value is None else f"{key}={value}"


def run_config(args):
    # --quick: a demo of about a minute on 2 cores: short drive, quick settling, coarser samples
    return command_config(
        args, ["numerics.duration=1.0", "numerics.settle_time=0.3", "numerics.chunk=0.1"],
        [_given("frequency", args.frequency), _given("numerics.duration", args.duration),
         _given("numerics.seed", args.seed)])


def print_steady(steady: dict, keys=("amplitude", "granular_loss_per_cycle", "phase")) -> None:
    """Print the steady-state estimates of one point (:func:`jaxdamp.analysis.stats.summarise` arrays):
    mean ± SE over replicates, the detected start of the steady state, the batch-means error."""
    import numpy as np

    from jaxdamp.analysis.stats import format_estimate, unit

    a = steady[keys[0]]
    start = np.atleast_1d(a["start"]).ravel()
    ok = np.atleast_1d(a["stationary"]).ravel()
    R = len(start)
    if not ok.any():
        print(f"steady state: not detected in {'the run' if R == 1 else f'any of {R} replicates'}"
              " (MSER on per-period amplitude and dissipation): it is too short or still "
              "drifting, so the numbers above are a fixed window, not a steady state — "
              "lengthen --duration (numerics.duration) for one")
        return
    print(f"steady state detected (MSER on per-period amplitude and dissipation) in "
          f"{int(ok.sum())} of {R} replicate(s); starts at t = "
          + ", ".join(f"{t:.3g} s" if k else "(not stationary)" for t, k in zip(start, ok)))
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


def float_list(text, option: str = "", what: str = "numbers", example: str = "1,2.5") -> list[float]:
    """``"1,2.5,3"`` -> ``[1.0, 2.5, 3.0]``; otherwise (not numbers, or none at all) a one-line
    error naming ``option``: "expected a comma-separated list of ``what``, e.g. ``example``"."""
    where = f"{option} {text!r}: " if option else ""
    wanted = f"{where}expected a comma-separated list of {what}, e.g. {example}"
    try:
        values = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise ConfigError(wanted) from None
    if not values:
        raise ConfigError(wanted)
    return values


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
