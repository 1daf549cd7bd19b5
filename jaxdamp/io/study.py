"""Result files of the studies (``experiments/<name>/data.h5``; ``docs/output.md``).

``jaxdamp-study/1``: the root attributes every jaxdamp file has (:func:`jaxdamp.io.common.stamp`:
``format``, ``jaxdamp_version``, ``created``, ``units``), the provenance of the run that wrote
it (:data:`PROVENANCE`: the command, the checkout's revision, the machine, the wall time) and
the study's own attributes (settings, verdicts: JSON unless a string or a number); below the
root, each study's groups and datasets, every dataset with a ``units`` attribute. Written by
:func:`create` (through :func:`jaxdamp.studies.scaffold.data_file`); ``jaxdamp info`` describes it
(:func:`describe_lines`); :func:`load` reads one back whole, for a study's report.
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


class Group(dict):
    """A group of a study file read into memory (:func:`load`): its members by name (datasets
    as NumPy arrays, a scalar dataset as a Python number, subgroups as :class:`Group`), its
    attributes in ``attrs`` (JSON decoded where :func:`~jaxdamp.io.common.stamp` encoded them)
    and each dataset's attributes (``units``, ``dims``) in ``meta[name]``."""

    def __init__(self, members=(), attrs=None, meta=None):
        super().__init__(members)
        self.attrs = dict(attrs or {})
        self.meta = dict(meta or {})


def _decode(value):
    import numpy as np

    if isinstance(value, bytes):
        value = value.decode()
    if isinstance(value, str) and value[:1] in "[{":
        try:
            return json.loads(value)
        except ValueError:
            return value
    if isinstance(value, np.generic):
        return value.item()
    return value


def _read(group) -> Group:
    import h5py

    out = Group(attrs={k: _decode(v) for k, v in group.attrs.items()})
    for name, obj in group.items():
        if hasattr(obj, "shape"):
            value = obj.asstr()[()] if h5py.check_string_dtype(obj.dtype) else obj[()]
            out[name] = _decode(value) if obj.shape == () else value
            out.meta[name] = {k: _decode(v) for k, v in obj.attrs.items()}
        else:
            out[name] = _read(obj)
    return out


def load(path: str) -> Group:
    """The study file ``path`` read whole into a :class:`Group` (study files are small): what a
    study's report draws its figures and summary from, at the end of a run or from a stored
    file (``--from-data``). Its ``attrs`` hold the provenance (:data:`PROVENANCE`)."""
    import h5py

    with h5py.File(path, "r") as h:
        if h.attrs.get("format") != FORMAT:
            raise ValueError(f"{path} is not a study file (format {FORMAT!r})")
        return _read(h)


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
