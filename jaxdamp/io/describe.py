"""``jaxdamp info``: a human-readable overview of any file jaxdamp writes, chosen by its
``format`` attribute (each kind's module describes its own layout)."""

from __future__ import annotations

import os

from jaxdamp.config import ConfigError


def describe(path: str) -> str:
    """Overview of the run, sweep (``frf``, ``efficiency``, replicated runs) or optimiser file
    ``path``; a :class:`ConfigError` naming the problem for a missing, non-HDF5, truncated or
    foreign file."""
    import h5py

    from jaxdamp.io import optimisation, runfile, sweepfile

    if not os.path.exists(path):
        raise ConfigError(f"{path}: no such file")
    if not h5py.is_hdf5(path):
        raise ConfigError(f"{path}: not an HDF5 file (jaxdamp writes run, sweep and optimiser "
                          "files in HDF5)")
    kinds = {"jaxdamp-run": runfile, "jaxdamp-sweep": sweepfile,
             "jaxdamp-optimize": optimisation}
    try:
        with h5py.File(path, "r") as h:
            fmt = str(h.attrs.get("format", ""))
            module = kinds.get(fmt.split("/")[0])
            if module is None:
                raise ConfigError(f"{path}: not a jaxdamp file (format attribute {fmt!r}; "
                                  f"expected one of {', '.join(k + '/…' for k in kinds)})")
            return "\n".join(module.describe_lines(h, path))
    except OSError as e:  # truncated or damaged
        raise ConfigError(f"{path}: cannot be read as HDF5 ({e})") from None
    except KeyError as e:
        raise ConfigError(f"{path}: a {fmt} file without its {e} (truncated or written by "
                          "another version?)") from None
