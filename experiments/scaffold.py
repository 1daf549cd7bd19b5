"""What the experiment scripts share: the command line, the provenance, the summary's first line.

An experiment is a script, ``python experiments/<name>.py [--quick] [--out DIR]
[--no-progress]``, that computes, judges and writes ``data.h5``, ``figure.png`` and
``summary.md`` into ``DIR`` (default ``experiments/<name>/``). The scripts import this module
from their own folder (``tests/helpers.load_experiment`` puts the folder on the path)::

    import scaffold

    def main(argv=None):
        def compute(quick, log, ctx):         # ctx: Context (out folder, progress)
            result = ...                      # the experiment's numbers and verdicts
            return result, lambda path, prov: write(result, path, prov)
        return scaffold.main(__doc__, "my_experiment", argv, compute)
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import time
from dataclasses import dataclass

import jaxdamp
from jaxdamp.analysis.uncertainty import mean_se, pm, standard_error  # noqa: F401 - the one "±"

HERE = os.path.dirname(os.path.abspath(__file__))


def git_revision() -> str:
    """The checkout's short commit, or ``"unknown"`` outside a git work tree."""
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, cwd=HERE, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def provenance(name: str, quick: bool, elapsed: float) -> dict:
    """``command``, ``jaxdamp_version``, ``git``, ``machine`` and ``elapsed_s`` of a run."""
    return {"command": f"python experiments/{name}.py" + (" --quick" if quick else ""),
            "jaxdamp_version": jaxdamp.__version__, "git": git_revision(),
            "machine": f"{platform.machine()}, {os.cpu_count()} cores, Python "
                       f"{platform.python_version()}", "elapsed_s": elapsed}


def stamp(h5, prov: dict) -> None:
    """The provenance as root attributes of an HDF5 file (JSON for non-strings)."""
    h5.attrs.update({k: json.dumps(x) if not isinstance(x, str) else x for k, x in prov.items()})


def save_figure(fig, out: str, name: str = "figure.png", dpi: int = 120) -> str:
    """Lay out, write ``out/name`` and close a matplotlib figure; returns the path."""
    import matplotlib.pyplot as plt

    path = os.path.join(out, name)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


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


@dataclass(frozen=True)
class Context:
    """What ``compute`` may need besides ``quick``: the output folder ``out`` (for raw,
    resumable files under ``out/raw``) and whether to show progress bars."""

    out: str
    progress: bool

    def raw(self, name: str) -> str:
        """``out/raw/name``, the folder created: files kept for resuming, not committed."""
        os.makedirs(os.path.join(self.out, "raw"), exist_ok=True)
        return os.path.join(self.out, "raw", name)


def main(doc: str, name: str, argv, compute):
    """Parse ``--quick``, ``--out``, ``--no-progress``; ``compute(quick, log, ctx)``
    (``ctx``: :class:`Context`) returns ``(result, writer)``; ``writer(out_dir, provenance)``
    writes the files. Returns ``result``."""
    ap = argparse.ArgumentParser(description=doc,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="test-sized settings (minutes)")
    ap.add_argument("--out", default=os.path.join(HERE, name), help="output folder")
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    log = (lambda m: print(m, flush=True)) if not args.no_progress else (lambda m: None)
    t0 = time.perf_counter()
    result, writer = compute(args.quick, log, Context(args.out, not args.no_progress))
    os.makedirs(args.out, exist_ok=True)
    writer(args.out, provenance(name, args.quick, time.perf_counter() - t0))
    return result
