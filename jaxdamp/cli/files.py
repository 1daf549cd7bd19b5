"""``jaxdamp presets``, ``info``, ``plot``, ``export``: the reference cases and output files."""

from __future__ import annotations

import argparse
import textwrap

from jaxdamp.cli.common import add_overwrite, check_outputs, finite_float, positive_int, to_toml
from jaxdamp.config import ConfigError


def cmd_presets(args) -> int:
    from jaxdamp.cases import presets

    if args.show:
        cfg = presets.get(args.show)
        print(to_toml(cfg.to_dict()))
        return 0
    for name, line in presets.describe():
        print(f"{name:28s} {line}")
    return 0


def cmd_info(args) -> int:
    if args.devices:
        from jaxdamp.engine.choice import describe_devices

        print("\n".join(describe_devices(tuple(args.batch)) if args.batch
                        else describe_devices()))
        if args.file is None:
            return 0
    if args.file is None:
        raise ConfigError("info: give a FILE.h5 to summarise, or --devices")
    from jaxdamp.io import describe

    print(describe(args.file))
    return 0


PLOT_KINDS = {
    "band": "run file: floor and lid of the box, the band between the lowest and highest grain "
            "centre, the centre of mass, and the force of the grains on the box, versus time "
            "(default window: the last few drive periods)",
    "energy": "run file: cumulative work channels (input, primary damper, the four granular "
              "losses) and the energy-balance residual, versus time",
    "frf": "sweep file (jaxdamp frf): amplitude ratio Z/U versus frequency per Lz, with the "
           "analytic FRFs and the fitted M_ef, C_ef",
    "snapshot": "run file: the grains at one snapshot (--frame) and the container, in 3-D, "
                "or (--view) from the side, from above, or several views side by side",
    "poincare": "run file: stroboscopic section (z_cm, vz_cm) of the bed's centre of mass once "
                "per drive period",
}


#: The family of file (:data:`jaxdamp.io.describe.FAMILIES`) each kind of plot draws.
PLOT_FILES = {"band": "jaxdamp-run", "energy": "jaxdamp-run", "frf": "jaxdamp-sweep",
              "snapshot": "jaxdamp-run", "poincare": "jaxdamp-run"}


def _plots_of_files() -> str:
    """``"band, energy, snapshot and poincare draw run files; frf draws sweep files"``."""
    from jaxdamp.io.describe import FAMILIES

    parts = []
    for family in dict.fromkeys(PLOT_FILES.values()):
        kinds = [k for k, f in PLOT_FILES.items() if f == family]
        noun = FAMILIES[family][0].split(" (")[0].removeprefix("a ")
        parts.append((", ".join(kinds[:-1]) + " and " + kinds[-1] if len(kinds) > 1
                      else kinds[0]) + (" draw " if len(kinds) > 1 else " draws ") + noun + "s")
    return "; ".join(parts)


def cmd_plot(args) -> int:
    import os

    stem = os.path.splitext(os.fspath(args.file))[0]
    out = args.out or f"{stem}_{args.kind}.png"
    if args.kind == "frf" and (args.t0 is not None or args.t1 is not None):
        raise ConfigError("--t0/--t1 do not apply to --kind frf (a sweep's FRF has no time axis)")
    if args.view is not None:
        if args.kind != "snapshot":
            raise ConfigError(f"--view applies to --kind snapshot only, not {args.kind}")
        from jaxdamp.figures.bed import parse_views

        parse_views(args.view)  # a bad view named before anything is read or written
    from jaxdamp.io.describe import file_family, what_file
    from jaxdamp.io.export import open_output

    with open_output(args.file) as h5:  # a missing or non-HDF5 input is named first
        family, what = file_family(h5), what_file(h5)
        refuse_damaged(args.file, h5)
    if family not in PLOT_FILES.values():
        raise ConfigError(f"{args.file} is {what}: no --kind of jaxdamp plot draws it "
                          f"({_plots_of_files()}); `jaxdamp info {args.file}` shows what it "
                          "holds")
    check_outputs([out], args.overwrite)
    from jaxdamp import figures

    if args.kind == "frf":
        fig = figures.frf_from_file(args.file)
    elif args.kind == "band":
        fig = figures.band_from_file(args.file, args.t0, args.t1)
    elif args.kind == "energy":
        fig = figures.energy_from_file(args.file, args.t0, args.t1)
    elif args.kind == "snapshot":
        fig = figures.snapshot_from_file(args.file, args.frame, args.color, args.view or "3d")
    else:
        fig = figures.poincare_from_file(args.file, args.t0, args.t1, args.phase)
    figures.save(fig, out)
    print(f"wrote {out}")
    return 0


def refuse_damaged(path, h5) -> None:
    """Refuse (one line) to draw or export the open run file ``h5`` when it is damaged
    (:func:`jaxdamp.io.runfile.damage`): what came out of it would be garbage."""
    from jaxdamp.io.describe import file_family
    from jaxdamp.io.runfile import damage

    if file_family(h5) == "jaxdamp-run" and (why := damage(h5)) is not None:
        raise ConfigError(f"{path} is damaged ({why}): nothing drawn or exported from it "
                          "(`jaxdamp info` shows what it holds)")


def cmd_export(args) -> int:
    import os

    from jaxdamp.io.export import export, planned_outputs

    if args.format in ("gif", "mp4"):
        out = args.out or os.path.splitext(os.fspath(args.file))[0] + "." + args.format
        if os.path.splitext(out)[1].lower() != "." + args.format:
            raise ConfigError(f"--out {out}: --format {args.format} writes a .{args.format} file")
    check_outputs(planned_outputs(args.file, args.format, args.out, args.every), args.overwrite,
                  new_folders=True)
    from jaxdamp.io.export import open_output

    with open_output(args.file) as h5:
        refuse_damaged(args.file, h5)
    if args.format in ("gif", "mp4"):
        from jaxdamp.figures import animate

        animate(args.file, out, every=args.every, fps=args.fps, color=args.color)
        print(f"wrote {out}")
        return 0
    paths = export(args.file, args.format, args.out, args.every)
    if args.format == "vtk":
        print(f"wrote {paths[0]} indexing {(len(paths) - 1) // 2} frames of the grains and "
              f"of the container ({paths[1]} …)")
    else:
        print(f"wrote {paths[0]}")
    return 0


def register(sub) -> None:
    """Add the subcommand(s) to the ``jaxdamp`` parser."""
    pr = sub.add_parser("presets", help="list the reference cases (or --show one as TOML)")
    pr.add_argument("--show", metavar="NAME", help="print the full configuration of a preset")
    pr.set_defaults(func=cmd_presets)

    i = sub.add_parser("info", help="summarise any file jaxdamp writes (run, sweep, optimiser "
                                    "log), or this machine's devices (--devices)",
                       description="Summarise an output file, or (--devices) list the devices "
                                   "JAX sees and the engine numerics.engine = 'auto' picks "
                                   "for each batch and precision.",
                       epilog="examples:\n  jaxdamp info run.h5\n  jaxdamp info --devices\n"
                              "  jaxdamp info --devices --batch 1 --batch 2400",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    i.add_argument("file", metavar="FILE.h5", nargs="?",
                   help="a run, sweep or optimiser file (HDF5) written by jaxdamp")
    i.add_argument("--devices", action="store_true",
                   help="the devices, the host's cores, the engine 'auto' picks by batch and "
                        "the float64/float32 advice")
    i.add_argument("--batch", type=positive_int, action="append", metavar="N",
                   help="with --devices: a batch to show the choice for (repeatable; default "
                        "1, 32, 1024, 16384)")
    i.set_defaults(func=cmd_info)

    pl = sub.add_parser(
        "plot", help="figures from a run or sweep file (band, energy, frf, snapshot, poincare)",
        description="Draw one figure from an HDF5 output file and write it as PNG.",
        epilog="kinds:\n" + "\n".join(
            textwrap.fill(f"{k}: {v}", 92, initial_indent="  ", subsequent_indent="      ")
            for k, v in PLOT_KINDS.items()) + textwrap.dedent("""

            examples:
              jaxdamp plot run.h5 --kind band                 (writes run_band.png)
              jaxdamp plot run.h5 --kind band --t0 0.5 --t1 0.7 --out bed.png
              jaxdamp plot run.h5 --kind snapshot --frame 0 --color height
              jaxdamp plot run.h5 --kind snapshot --view side,top     (side and top views)
              jaxdamp plot frf.h5 --kind frf --out frf.png
            Run files come from `jaxdamp run --out`, sweep files from `jaxdamp frf --out`
            (`jaxdamp info FILE` tells which); times are in seconds from the start of the
            drive."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    pl.add_argument("file", metavar="FILE.h5", help="run file or sweep file")
    pl.add_argument("--kind", required=True, choices=list(PLOT_KINDS), help="which figure")
    pl.add_argument("--out", metavar="FILE.png", help="output image (default: FILE_<kind>.png)")
    pl.add_argument("--t0", type=finite_float, metavar="S", help="start of the time window [s] "
                    "(band: default the last few drive periods; energy, poincare: the whole run)")
    pl.add_argument("--t1", type=finite_float, metavar="S",
                    help="end of the time window [s] (default: the end of the run)")
    pl.add_argument("--frame", type=int, default=-1, metavar="K",
                    help="snapshot index for --kind snapshot (default -1, the last)")
    pl.add_argument("--color", choices=["species", "height"], default="species",
                    help="grain colour for snapshot: species, or height above the floor")
    pl.add_argument("--view", metavar="VIEW[,VIEW]",
                    help="snapshot: 3d (default; lab frame), side (x-z), top (x-y, from above), "
                         "or several side by side, e.g. side,top (box frame, grains to scale)")
    pl.add_argument("--phase", type=finite_float, default=0.0, metavar="RAD",
                    help="poincare: section phase within the drive period [rad] (default 0, "
                         "the drive's maximum)")
    add_overwrite(pl)
    pl.set_defaults(func=cmd_plot)

    ex = sub.add_parser(
        "export", help="trajectories of a run file for OVITO / ParaView, or an animation",
        description="Write the grain snapshots of a run file (/snapshots, one after every "
        "chunk) for external viewers.",
        epilog=textwrap.dedent("""\
            formats:
              xyz  one extended-XYZ file, one frame per snapshot (OVITO, ASE): species, position,
                   radius, orientation quaternion (x, y, z, w); the box as Lattice + Origin.
              vtk  one legacy-VTK polydata file per snapshot (FILE_0000.vtk, ...) with radius,
                   species and orientation point data, the container's edges beside it
                   (FILE_container_0000.vtk, ...), a ParaView .pvd collection indexing both by
                   time, and .vtk.series files (ParaView >= 5.5) with the same times.
              gif  animation through Pillow;  mp4  animation through ffmpeg (needs it on PATH).
            examples:
              jaxdamp export run.h5 --format xyz                 (writes run.xyz)
              jaxdamp export run.h5 --format vtk --out vtk/run.pvd --every 2   (creates vtk/)
              jaxdamp export run.h5 --format gif --fps 8
            Positions are in metres in the lab frame (the box moves: its floor is z_box).
            Existing files are never replaced without --overwrite."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ex.add_argument("file", metavar="FILE.h5", help="run file (jaxdamp run --out)")
    ex.add_argument("--format", required=True, choices=["xyz", "vtk", "gif", "mp4"],
                    help="what to write: xyz (OVITO, ASE), vtk (ParaView), gif or mp4 (an "
                         "animation); see formats below")
    ex.add_argument("--out", metavar="PATH", help="output file (.xyz, .pvd, .gif, .mp4; "
                    "default: next to FILE)")
    ex.add_argument("--every", type=positive_int, default=1, metavar="K",
                    help="every K-th snapshot (default 1: all)")
    ex.add_argument("--fps", type=positive_int, default=10,
                    help="frames per second of gif, mp4 (default 10)")
    ex.add_argument("--color", choices=["species", "height"], default="species",
                    help="grain colour in animations: species (default), or height above the "
                         "floor")
    add_overwrite(ex)
    ex.set_defaults(func=cmd_export)
