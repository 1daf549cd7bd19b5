"""``jaxdamp info``: a human-readable overview of any file jaxdamp writes, chosen by its
``format`` attribute (each kind's module describes its own layout); :func:`file_family` and
:func:`what_file` name a file's kind for the other commands' messages."""

from __future__ import annotations

import importlib
import os

from jaxdamp.config import ConfigError

#: Every kind of file jaxdamp writes, by its ``format`` attribute's part before the ``/``: what
#: the file is called (with the commands that write it) and the :mod:`jaxdamp.io` module that
#: describes it.
FAMILIES = {
    "jaxdamp-run": ("a run file (jaxdamp run --out)", "runfile"),
    "jaxdamp-sweep": ("a sweep file (jaxdamp frf, decay, random or efficiency --out, or run "
                      "--replicates --out)", "sweepfile"),
    "jaxdamp-optimize": ("an optimiser log (jaxdamp optimize --out)", "optimisation"),
    "jaxdamp-study": ("a study's results (python experiments/<name>.py)", "study"),
}


def file_family(h) -> str | None:
    """The family (a key of :data:`FAMILIES`) of the open HDF5 file ``h``, ``None`` for a file
    jaxdamp did not write."""
    family = str(h.attrs.get("format", "")).split("/")[0]
    return family if family in FAMILIES else None


def what_file(h) -> str:
    """``"an optimiser log (jaxdamp optimize --out), format 'jaxdamp-optimize/2'"``: what the
    open HDF5 file ``h`` is, for messages."""
    fmt = str(h.attrs.get("format", ""))
    family = file_family(h)
    if family is None:
        return (f"not a jaxdamp file (format attribute {fmt!r}; expected one of "
                f"{', '.join(k + '/…' for k in FAMILIES)})")
    return f"{FAMILIES[family][0]}, format {fmt!r}"


def describe(path: str) -> str:
    """Overview of the run, sweep (``frf``, ``efficiency``, replicated runs), optimiser or
    study file ``path``; a :class:`ConfigError` naming the problem for a missing, non-HDF5,
    truncated or foreign file."""
    import h5py

    if not os.path.exists(path):
        raise ConfigError(f"{path}: no such file")
    if not h5py.is_hdf5(path):
        raise ConfigError(f"{path}: not an HDF5 file (jaxdamp writes run, sweep and optimiser "
                          "files in HDF5)")
    fmt = ""
    try:
        with h5py.File(path, "r") as h:
            fmt = str(h.attrs.get("format", ""))
            family = file_family(h)
            if family is None:
                raise ConfigError(f"{path}: {what_file(h)}")
            module = importlib.import_module(f"jaxdamp.io.{FAMILIES[family][1]}")
            return "\n".join(module.describe_lines(h, path))
    except OSError as e:  # truncated or damaged
        raise ConfigError(f"{path}: cannot be read as HDF5 ({e})") from None
    except KeyError as e:
        raise ConfigError(f"{path}: a {fmt} file without its {e} (truncated or written by "
                          "another version?)") from None
