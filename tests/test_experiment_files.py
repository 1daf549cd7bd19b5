"""The experiments as one library: every study is a module of the ``experiments`` package on
the one scaffold, and every stored result file carries the scaffold's provenance."""

import importlib
import pathlib

import h5py
import pytest

EXPERIMENTS = pathlib.Path(__file__).parent.parent / "experiments"
STUDIES = sorted(p.stem for p in EXPERIMENTS.glob("*.py") if p.stem not in ("__init__", "scaffold"))
PROVENANCE = ("command", "jaxdamp_version", "git", "machine", "elapsed_s")


@pytest.mark.parametrize("name", STUDIES)
def test_every_study_is_a_module_on_the_scaffold(name):
    """Importable as ``experiments.<name>`` (no path loading), with ``main(argv)`` through
    ``scaffold.main``: one command line, provenance, no parser of its own."""
    mod = importlib.import_module(f"experiments.{name}")
    assert callable(mod.main)
    text = (EXPERIMENTS / f"{name}.py").read_text()
    assert "scaffold.main(" in text and "ArgumentParser(" not in text


@pytest.mark.parametrize("path", sorted(EXPERIMENTS.glob("*/data.h5")),
                         ids=lambda p: p.parent.name)
def test_every_stored_result_carries_its_provenance(path):
    with h5py.File(path, "r") as h:
        missing = [k for k in PROVENANCE if k not in h.attrs]
    assert not missing, f"{path}: no {missing}"


def _sources():
    root = EXPERIMENTS.parent
    return sorted(EXPERIMENTS.glob("*.py")) + sorted((root / "jaxdamp").rglob("*.py"))


def test_one_standard_error_and_one_formatter():
    """No standard error typed inline (``std(ddof=1) / sqrt(n)``) and no ``±`` formatted by
    hand in an f-string, in the library or the studies: they go through
    :mod:`jaxdamp.analysis.uncertainty` (``standard_error``, ``mean_se``, ``pm``; the
    estimate over replicates is ``stats.across``)."""
    import re

    inline_se = re.compile(r"ddof\s*=\s*1\s*\)\s*/\s*(np\.|math\.)?sqrt")
    hand_pm = re.compile(r"\}\s*±\s*\{")  # "{mean} ± {se}" in an f-string
    found = []
    for p in _sources():
        if p.name == "uncertainty.py":
            continue
        for k, line in enumerate(p.read_text().splitlines(), 1):
            if inline_se.search(line) or hand_pm.search(line):
                found.append(f"{p.relative_to(EXPERIMENTS.parent)}:{k}: {line.strip()}")
    assert not found, "\n".join(found)
