"""Result files of the studies (``experiments/<name>/data.h5``; ``docs/output.md``).

``jaxdamp-study/1``: the root attributes every jaxdamp file has (:func:`jaxdamp.io.common.stamp`:
``format``, ``jaxdamp_version``, ``created``, ``units``), the provenance of the run that wrote
it (:data:`PROVENANCE`: the command, the checkout's revision, the machine, the wall time) and
the study's own attributes (settings, verdicts: JSON unless a string or a number); below the
root, each study's groups and datasets, every dataset with a ``units`` attribute. Written by
:func:`create` (through :func:`jaxdamp.studies.scaffold.data_file`); ``jaxdamp info`` describes it
(:func:`describe_lines`).
"""

from __future__ import annotations

import json

from jaxdamp.io.common import stamp

FORMAT = "jaxdamp-study/1"
#: The provenance attributes of every study file.
PROVENANCE = ("command", "jaxdamp_version", "git", "machine", "elapsed_s")


def create(path: str, provenance: dict, **attrs):
    """``path`` opened for writing (an ``h5py.File``; use it in ``with``), stamped with
    :data:`FORMAT`, the ``provenance`` (:data:`PROVENANCE`) and ``attrs``."""
    import h5py

    missing = [k for k in PROVENANCE if k not in provenance]
    if missing:
        raise ValueError(f"provenance without {', '.join(missing)}")
    h5 = h5py.File(path, "w")
    stamp(h5, FORMAT, **dict(provenance, **attrs))
    return h5


def describe_lines(h, path: str) -> list[str]:
    """Human-readable overview of an open study file (``jaxdamp info``): what ran, where and
    how long; the study's own attributes; the top-level groups and datasets."""
    a = h.attrs
    elapsed = a.get("elapsed_s")
    try:
        took = f"{float(json.loads(elapsed) if isinstance(elapsed, str) else elapsed) / 60:.1f} min"
    except (TypeError, ValueError):
        took = "?"
    lines = [f"{path}: {a.get('format', '?')} (study results), jaxdamp "
             f"{a.get('jaxdamp_version', '?')}",
             f"  command: {a.get('command', '?')}",
             f"  revision {a.get('git', '?')}; {a.get('machine', '?')}; {took} wall"]
    own = sorted(k for k in a if k not in PROVENANCE + ("format", "created", "units"))
    if own:
        lines.append("  attributes: " + ", ".join(own))
    for name in sorted(h):
        obj = h[name]
        if hasattr(obj, "shape"):
            unit = obj.attrs.get("units", "")
            lines.append(f"  {name}: {obj.shape}" + (f" [{unit}]" if unit else ""))
        else:
            lines.append(f"  {name}/: {len(obj)} entries")
    return lines
