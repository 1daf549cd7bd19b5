"""The experiments as one library: every study is a module of the ``experiments`` package on
the one scaffold, and every stored result file carries the scaffold's provenance."""

import importlib
import pathlib

import h5py
import pytest

EXPERIMENTS = pathlib.Path(__file__).parent.parent / "experiments"
STUDIES = sorted(p.stem for p in EXPERIMENTS.glob("*.py") if p.stem != "__init__")


@pytest.mark.parametrize("name", STUDIES)
def test_every_study_is_a_module_on_the_scaffold(name):
    """Importable as ``experiments.<name>`` (no path loading), with ``main(argv)`` through
    :func:`jaxdamp.studies.scaffold.entry`: one command line, provenance, no parser of its own."""
    mod = importlib.import_module(f"experiments.{name}")
    assert callable(mod.main)
    text = (EXPERIMENTS / f"{name}.py").read_text()
    assert "scaffold.entry(__file__, __doc__, compute" in text and "ArgumentParser(" not in text


@pytest.mark.parametrize("path", sorted(EXPERIMENTS.glob("*/data.h5")),
                         ids=lambda p: p.parent.name)
def test_every_stored_result_is_a_study_file_with_its_provenance(path):
    """One layout (:mod:`jaxdamp.io.study`): the format, the provenance, and ``jaxdamp info``
    describes it."""
    from jaxdamp.io.describe import describe
    from jaxdamp.io.study import FORMAT, PROVENANCE

    with h5py.File(path, "r") as h:
        missing = [k for k in PROVENANCE + ("format", "units", "created") if k not in h.attrs]
        assert h.attrs.get("format") == FORMAT
    assert not missing, f"{path}: no {missing}"
    assert "(study results)" in describe(str(path))


#: Stored figures whose data their runs never kept (whole trajectories): the report draws them
#: when the data file holds those data (every run from 2026-12-05 on stores them), so they come
#: back with the next full run; until then the committed PNG is the one the run drew.
NOT_IN_STORED_DATA = {"binary_mixtures": {"snapshots.png"}, "decay_vs_sine": {"figure.png"},
                      "gap_scan": {"fig3_9.png"}, "grain_number": {"fig3_3_3_4.png"},
                      "random_vs_sine": {"figure.png"}, "two_mode_structure": {"figure.png"}}


#: Every stored result: ``experiments/<study>/data.h5`` and a study's other runs in folders of
#: its own (``experiments/<study>/<run>/data.h5``: another time step, another law).
STORED = sorted(p.parent.relative_to(EXPERIMENTS).as_posix()
                for p in list(EXPERIMENTS.glob("*/data.h5")) + list(EXPERIMENTS.glob("*/*/data.h5"))
                if p.relative_to(EXPERIMENTS).parts[0] in STUDIES)


@pytest.mark.parametrize("run", STORED)
def test_stored_data_reproduce_their_summaries(run, tmp_path):
    """``--from-data`` computes nothing: from the stored ``data.h5`` alone (a study's main
    result or another run of it) it writes the stored ``summary.md`` byte for byte and every
    stored figure (but those of :data:`NOT_IN_STORED_DATA`), and leaves the data file as it
    was."""
    import shutil

    name = run.split("/")[0]
    stored = EXPERIMENTS / run
    shutil.copy(stored / "data.h5", tmp_path / "data.h5")
    before = (tmp_path / "data.h5").read_bytes()
    importlib.import_module(f"experiments.{name}").main(
        ["--from-data", "--out", str(tmp_path), "--no-progress"])
    assert (tmp_path / "summary.md").read_text() == (stored / "summary.md").read_text()
    assert ({p.name for p in tmp_path.glob("*.png")}
            == {p.name for p in stored.glob("*.png")} - NOT_IN_STORED_DATA.get(name, set()))
    assert (tmp_path / "data.h5").read_bytes() == before


def test_from_data_without_a_result_file_is_a_clear_error(tmp_path, capsys):
    from experiments import stiffness

    with pytest.raises(SystemExit) as e:
        stiffness.main(["--from-data", "--out", str(tmp_path / "nowhere")])
    assert e.value.code == 2 and "--from-data: no result file" in capsys.readouterr().err


def test_a_study_file_is_written_and_described(tmp_path):
    from jaxdamp.io.common import put
    from jaxdamp.io.describe import describe
    from jaxdamp.io.study import create

    prov = dict(command="python experiments/x.py --quick", jaxdamp_version="0", git="abc",
                machine="here", elapsed_s=90.0)
    with create(tmp_path / "data.h5", prov, settings={"R": 2}) as h:
        put(h, "amplitude", [0.01, 0.02], "m")
        h.create_group("beds")
    text = describe(str(tmp_path / "data.h5"))
    assert "jaxdamp-study/1" in text and "x.py --quick" in text and "1.5 min wall" in text
    assert "amplitude: (2,) [m]" in text and "settings" in text and "beds/" in text
    with pytest.raises(ValueError, match="git"):
        create(tmp_path / "bad.h5", {k: v for k, v in prov.items() if k != "git"})


def test_a_study_file_reads_back_whole(tmp_path):
    """:func:`jaxdamp.io.study.load`: datasets as arrays or numbers, attributes decoded as
    written, each dataset's attributes in ``meta``; a file of another format is refused."""
    import numpy as np

    from jaxdamp.io.common import put
    from jaxdamp.io.study import create, load

    prov = dict(command="c", jaxdamp_version="0", git="abc", machine="here", elapsed_s=90.0)
    with create(tmp_path / "data.h5", prov, settings={"R": 2, "f": [1.5]}, label="a b") as h:
        put(h, "amplitude", [0.01, 0.02], "m", dims="frequency")
        g = h.create_group("beds")
        g.attrs["n"] = 3
        put(g, "count", 7, "1")
        g.create_dataset("names", data=np.array([b"x", b"yz"]))
        g.create_dataset("labels", data=["p", "qr"], dtype=h5py.string_dtype())
    d = load(tmp_path / "data.h5")
    assert d.attrs["settings"] == {"R": 2, "f": [1.5]} and d.attrs["label"] == "a b"
    assert d.attrs["elapsed_s"] == 90.0 and d.attrs["git"] == "abc"
    np.testing.assert_array_equal(d["amplitude"], [0.01, 0.02])
    assert d.meta["amplitude"] == {"units": "m", "dims": "frequency"}
    assert d["beds"].attrs["n"] == 3 and d["beds"]["count"] == 7
    assert list(d["beds"]["names"]) == ["x", "yz"]
    assert list(d["beds"]["labels"]) == ["p", "qr"]
    with h5py.File(tmp_path / "other.h5", "w") as h:
        h.attrs["format"] = "jaxdamp-sweep/2"
    with pytest.raises(ValueError, match="not a study file"):
        load(tmp_path / "other.h5")


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
