"""What every study script shares: the command line, the provenance, the result file, the
report from it, figures, tables and the one estimate and formatter.

A study (``experiments/<name>.py``, or a script of yours) computes and records its numbers in
``data.h5`` (:mod:`jaxdamp.io.study`); its report draws the figures and writes ``summary.md``
from that file alone, so a stored ``data.h5`` reproduces its summary (``--from-data``). Both go
into ``--out`` (default: the folder ``<name>/`` beside the script)::

    from jaxdamp.studies import scaffold

    def compute(quick, log, ctx):          # ctx: Context (out folder, progress, options)
        result = ...                       # the study's numbers and verdicts
        return result, lambda out, prov: record(result, out, prov)

    def record(result, out, prov):         # data.h5 and nothing else
        with scaffold.data_file(out, prov, settings=...) as h:
            ...

    def report(data, out):                 # data: data.h5 read back (io.study.Group)
        ...                                # figures, then scaffold.write_summary(out, lines)

    main = scaffold.entry(__file__, __doc__, compute, report=report)

    if __name__ == "__main__":
        main()

``python <name>.py [--quick] [--out DIR] [--no-progress] [--from-data]``; ``record`` uses
:func:`data_file`; ``report`` uses :func:`subplots` and :func:`save_figure` (the figures' style
of :mod:`jaxdamp.figures`), :func:`table`, :func:`head` (title and the provenance kept in
``data.attrs``) and :func:`write_summary`; every "mean ± SE" is :func:`pm` of :func:`mean_se`
or of an :class:`~jaxdamp.analysis.stats.Estimate` (:func:`across`).
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import time
from dataclasses import dataclass

import jaxdamp
from jaxdamp.analysis.stats import across  # noqa: F401 - the one estimate over replicates
from jaxdamp.analysis.uncertainty import mean_se, pm, standard_error  # noqa: F401 - the one "±"


def _git(folder: str, *args: str) -> str | None:
    try:
        return subprocess.run(["git", *args], capture_output=True, text=True, cwd=folder,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def git_revision(folder: str) -> str:
    """The short commit of the checkout holding ``folder``, or ``"unknown"`` outside one."""
    return _git(folder, "rev-parse", "--short", "HEAD") or "unknown"


def script_path(file: str) -> str:
    """How the study ``file`` is run: its path from the root of its checkout
    (``experiments/gap_scan.py``), or its file name outside one."""
    file = os.path.abspath(file)
    top = _git(os.path.dirname(file), "rev-parse", "--show-toplevel")
    return os.path.relpath(file, top) if top else os.path.basename(file)


def provenance(file: str, quick: bool, elapsed: float, flags: str = "") -> dict:
    """``command``, ``jaxdamp_version``, ``git``, ``machine`` and ``elapsed_s`` of a run of the
    study ``file`` (``flags``: the study's own options as given, after ``--quick``)."""
    return {"command": f"python {script_path(file)}" + (" --quick" if quick else "")
            + (f" {flags}" if flags else ""),
            "jaxdamp_version": jaxdamp.__version__,
            "git": git_revision(os.path.dirname(os.path.abspath(file))),
            "machine": f"{platform.machine()}, {os.cpu_count()} cores, Python "
                       f"{platform.python_version()}", "elapsed_s": elapsed}


def data_file(out: str, prov: dict, name: str = "data.h5", **attrs):
    """``out/name`` opened for writing (an ``h5py.File``, to use in ``with``): a study file
    (:func:`jaxdamp.io.study.create`) with the provenance and ``attrs`` (settings, verdicts:
    JSON unless a string or a number)."""
    from jaxdamp.io.study import create

    return create(os.path.join(out, name), prov, **attrs)


def subplots(nrows: int = 1, ncols: int = 1, figsize=(7.0, 4.5), **kwargs):
    """``(fig, axes)`` of a new figure in the figures' style (:func:`jaxdamp.figures.figure`:
    no pyplot, the package's resolution); ``axes`` as ``Figure.subplots`` returns them."""
    from jaxdamp.figures import figure

    fig = figure(figsize)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def save_figure(fig, out: str, name: str = "figure.png", dpi: int = 120) -> str:
    """Lay out (unless the figure has its own layout engine) and write ``out/name``
    (:func:`jaxdamp.figures.save`); returns the path."""
    from jaxdamp.figures import save

    if fig.get_layout_engine() is None:
        fig.tight_layout()
    return save(fig, os.path.join(out, name), dpi=dpi)


def quick_note(settings: dict) -> list[str]:
    """The summary's line saying a run was quick (``settings["quick_mode"]``), or none."""
    return (["- Quick mode: runs far shorter than the protocol — the estimates are rough."]
            if settings.get("quick_mode", False) else [])


def table(header, rows) -> list[str]:
    """A markdown table's lines: ``header`` (cells) and ``rows`` (each a list of cells, any
    value ``str``-ed)."""
    line = lambda cells: "| " + " | ".join(str(c) for c in cells) + " |"  # noqa: E731
    return [line(header), "|" + "---|" * len(header)] + [line(r) for r in rows]


def write_summary(out: str, lines: list[str]) -> str:
    """``out/summary.md`` from its lines; returns the path."""
    path = os.path.join(out, "summary.md")
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    return path


def provenance_line(prov: dict, sweep_wall: float | None = None) -> str:
    """The summary's line saying what ran, where and how long: this invocation's wall time
    and, with ``sweep_wall`` [s], the sweeps' own compute time as kept in their raw files
    (settling excluded; it survives re-runs that only read finished sweeps back)."""
    line = (f"Command: `{prov['command']}` — jaxdamp {prov['jaxdamp_version']} ({prov['git']}), "
            f"{prov['machine']}; {prov['elapsed_s'] / 60:.1f} min wall this invocation.")
    if sweep_wall is not None:
        line += (f" The sweeps' own compute time: {sweep_wall / 60:.1f} min (kept in the raw "
                 "files across re-runs; settling excluded).")
    return line


def head(title: str, prov: dict, sweep_wall: float | None = None) -> list[str]:
    """The summary's first lines: ``# title`` and the :func:`provenance_line`."""
    return [f"# {title}", "", provenance_line(prov, sweep_wall), ""]


@dataclass(frozen=True)
class Context:
    """What ``compute`` may need besides ``quick``: the output folder ``out`` (for raw,
    resumable files under ``out/raw``), whether to show progress bars and ``args``, the
    parsed command line (a study's own options: ``entry(..., options=)``)."""

    out: str
    progress: bool
    args: argparse.Namespace | None = None

    def raw(self, name: str) -> str:
        """``out/raw/name``, the folder created: files kept for resuming, not committed."""
        os.makedirs(os.path.join(self.out, "raw"), exist_ok=True)
        return os.path.join(self.out, "raw", name)


def _study_flags(argv: list[str]) -> str:
    """The options of a command line that change the study: without ``--quick`` (written
    first), ``--out DIR`` and ``--no-progress`` (where and how, not what)."""
    out, skip = [], False
    for a in argv:
        if skip:
            skip = False
        elif a == "--out":
            skip = True
        elif a not in ("--quick", "--no-progress") and not a.startswith("--out="):
            out.append(a)
    return " ".join(out)


def run(file: str, doc: str, argv, compute, options=None, report=None):
    """Parse ``--quick``, ``--out`` (default: ``<name>/`` beside the study ``file``),
    ``--no-progress``, ``--from-data`` and, with ``options(parser)``, the study's own options
    (in ``ctx.args``); ``compute(quick, log, ctx)`` (``ctx``: :class:`Context`) returns
    ``(result, writer)``; ``writer(out_dir, provenance)`` writes ``data.h5`` (with a
    ``report``; without one, every file) and ``report(data, out_dir)`` writes the figures and
    the summary from ``data.h5`` read back (:func:`jaxdamp.io.study.load`). With
    ``--from-data`` nothing is computed: the report is written from the ``data.h5`` in
    ``--out``. Returns ``result`` (with ``--from-data``, the data read)."""
    file = os.path.abspath(file)
    ap = argparse.ArgumentParser(description=doc,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="test-sized settings (minutes)")
    ap.add_argument("--out", default=os.path.splitext(file)[0], help="output folder")
    ap.add_argument("--no-progress", action="store_true")
    if report is not None:
        ap.add_argument("--from-data", action="store_true",
                        help="compute nothing: redraw the figures and rewrite summary.md from "
                             "the data.h5 in --out (a stored result reproduces its summary)")
    if options is not None:
        options(ap)
    argv = sys.argv[1:] if argv is None else list(argv)
    args = ap.parse_args(argv)
    data_path = os.path.join(args.out, "data.h5")
    if getattr(args, "from_data", False):
        if not os.path.isfile(data_path):
            ap.error(f"--from-data: no result file {data_path} (run the study first, or give "
                     "--out the folder that holds it)")
        from jaxdamp.io.study import load

        data = load(data_path)
        report(data, args.out)
        return data
    log = (lambda m: print(m, flush=True)) if not args.no_progress else (lambda m: None)
    t0 = time.perf_counter()
    result, writer = compute(args.quick, log, Context(args.out, not args.no_progress, args))
    os.makedirs(args.out, exist_ok=True)
    writer(args.out, provenance(file, args.quick, time.perf_counter() - t0, _study_flags(argv)))
    if report is not None:
        from jaxdamp.io.study import load

        report(load(data_path), args.out)
    return result


def entry(file: str, doc: str, compute, options=None, report=None):
    """The study's ``main(argv=None)`` (:func:`run` of the study ``file`` with its docstring
    ``doc``): ``main = scaffold.entry(__file__, __doc__, compute, report=report)``."""
    return lambda argv=None: run(file, doc, argv, compute, options, report)
