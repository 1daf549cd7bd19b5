"""What each runtime dependency costs: installed size and import time (issue 15 item 4).

    python benchmarks/install_size.py                 # jaxdamp's runtime requirements
    python benchmarks/install_size.py --with-jax-md   # as before jax-md was replaced

Walks the installed metadata from jaxdamp's runtime requirements (``pyproject.toml``) and
prints, per direct requirement, the packages that only it brings in (its exclusive closure)
with their installed size, then the import time of the modules jaxdamp uses from it, each in a
fresh interpreter (``python -X importtime`` is not needed: one wall-clock ``import`` each).
Run it in the environment CI builds (``pip install -e ".[dev]"``).
"""

from __future__ import annotations

import importlib.metadata as md
import os
import platform
import re
import subprocess
import sys
import time

#: jaxdamp's runtime requirements and the module jaxdamp imports from each.
#: (jax-md, a dependency until 2026-12-02, is listed when installed: ``--with-jax-md``.)
USED = {"jax": "jax", "optax": "optax", "numpy": "numpy",
        "scipy": "scipy.optimize", "h5py": "h5py", "matplotlib": "matplotlib.pyplot",
        "tqdm": "tqdm", "numba": "numba"}


def _norm(name: str) -> str:
    return name.lower().replace("_", "-")


def requires(name: str) -> list[str]:
    """Direct, unconditional requirements of an installed distribution."""
    try:
        dist = md.distribution(name)
    except md.PackageNotFoundError:
        return []
    out = []
    for r in dist.requires or []:
        if "extra ==" in r:
            continue
        out.append(_norm(re.split(r"[ ;<>=!~\[(]", r)[0]))
    return out


def closure(roots) -> set[str]:
    seen, stack = set(), [_norm(r) for r in roots]
    while stack:
        n = stack.pop()
        if n not in seen:
            seen.add(n)
            stack += requires(n)
    return seen


def size(name: str) -> int:
    """Installed bytes of a distribution's recorded files."""
    try:
        dist = md.distribution(name)
    except md.PackageNotFoundError:
        return 0
    total = 0
    for f in dist.files or []:
        try:
            total += os.path.getsize(dist.locate_file(f))
        except OSError:
            pass
    return total


def import_time(module: str) -> float:
    code = f"import time; t = time.perf_counter(); import {module}; print(time.perf_counter() - t)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout.strip())


def main():
    if "--with-jax-md" in sys.argv:
        USED["jax-md"] = "jax_md.partition"
    roots = list(USED)
    everything = closure(roots)
    total = sum(size(n) for n in everything)
    print(f"# {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"{time.strftime('%Y-%m-%d')}")
    print(f"runtime closure: {len(everything)} distributions, {total / 1e6:.0f} MB installed")
    print("| requirement | exclusive distributions | exclusive MB | share | import of | s |")
    print("| --- | --- | --- | --- | --- | --- |")
    for r in roots:
        others = closure([x for x in roots if x != r])
        own = closure([r]) - others
        mb = sum(size(n) for n in own) / 1e6
        t = import_time(USED[r])
        print(f"| {r} | {len(own)} | {mb:.0f} | {mb * 1e6 / total:.0%} | `{USED[r]}` | {t:.2f} |")
    if "jax-md" in USED:
        extra = sorted(closure(["jax-md"]) - closure([x for x in roots if x != "jax-md"]))
        print("\njax-md alone brings:", " ".join(extra))


if __name__ == "__main__":
    main()
