"""Configuration: presets, overrides, TOML, and clear errors for bad input before any compute."""

import pytest

from jaxdamp import cli
from jaxdamp.cases import presets
from jaxdamp.config import ConfigError, apply_overrides, from_dict, load_toml
from jaxdamp.validation import validate


@pytest.mark.parametrize("name", list(presets.PRESETS))
def test_presets_are_valid(name):
    cfg = validate(presets.get(name))
    assert from_dict(cfg.to_dict()) == cfg


def test_overrides_and_toml(tmp_path):
    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          ["box.Lz=0.07", "grains.0.count=100", "primary.C=26.3", "name=mine"])
    assert (cfg.box.Lz, cfg.grains[0].count, cfg.primary.C, cfg.name) == (0.07, 100, 26.3, "mine")
    f = tmp_path / "d.toml"
    f.write_text("frequency = 12.5\n[box]\nLz = 0.09\n")
    cfg2 = load_toml(str(f), presets.get("sanchez2012-optimal"))
    assert cfg2.frequency == 12.5 and cfg2.box.Lz == 0.09 and cfg2.box.Lx == 0.03675


def _err(over, match, preset="sanchez2012-optimal"):
    with pytest.raises(ConfigError, match=match):
        validate(apply_overrides(presets.get(preset), over))


def test_grains_that_do_not_fit_the_box():
    _err(["grains.0.radius=0.02"], r"grains\.0\.radius.*does not fit box\.Lx")
    _err(["box.Lz=0.02"], r"box\.Lz = 0\.02.*cannot fit")


@pytest.mark.parametrize(
    "over, match",
    [
        (["grains.0.radius=-0.001"], r"grains\.0\.radius = -0\.001: must be .* > 0"),
        (["grains.0.radius=0"], r"grains\.0\.radius = 0"),
        (["grains.0.material.density=0"], r"grains\.0\.material\.density = 0"),
        (["grains.0.material.E=0"], r"grains\.0\.material\.E = 0"),
        (["grains.0.material.E=-1e9"], r"grains\.0\.material\.E"),
        (["grains.0.count=-3"], r"grains\.0\.count = -3"),
        (["primary.M=-2"], r"primary\.M = -2"),
        (["primary.K=-1"], r"primary\.K = -1"),
        (["frequency=0"], r"frequency = 0"),
        (["frequency=-5"], r"frequency = -5"),
        (["grains.0.material.nu=0.6"], r"grains\.0\.material\.nu"),
        (["grains.0.material.restitution=0.8"], r"either gamma_n .* or restitution"),
        (["numerics.analysis_window=0"], r"numerics\.analysis_window"),
        (["system='orbit'"], r"system = 'orbit'"),
        (["numerics.precision='float16'"], r"numerics\.precision = 'float16': expected"),
        (["numerics.precision='float32'", "numerics.engine='native'"],
         r"numerics\.precision = 'float32' runs on the JAX engine only"),
    ],
)
def test_invalid_values_name_the_parameter(over, match):
    _err(over, match)


def test_float32_precision_runs_on_the_jax_engine():
    """``numerics.precision = 'float32'`` reaches the model, and ``auto`` resolves to the JAX
    engine for it (the native kernel is float64 only)."""
    from jaxdamp.engine.choice import resolve_engine
    from jaxdamp.physics.model import build

    cfg = apply_overrides(presets.get("sanchez2012-optimal"), ["numerics.precision='float32'"])
    assert build(validate(cfg))[0].precision == "float32"
    assert resolve_engine("auto", "float32") == "jax"
    with pytest.raises(ValueError, match=r"numerics\.precision = 'float32' runs on the JAX "
                                         "engine only"):
        resolve_engine("native", "float32")


def test_time_step_above_collision_limit():
    """dt above t_c/50 is refused with the numbers (thesis modulus, R = 3 mm, 1 m/s)."""
    with pytest.raises(ConfigError, match=r"numerics\.dt = 1e-05 s is too large.*t_c = 1\.8\d*e-05 s"):
        validate(apply_overrides(presets.get("sanchez2012-optimal"),
                                 ["numerics.stiffness_scale=1", "numerics.dt=1e-5"]))


def test_unknown_preset_and_malformed_set():
    with pytest.raises(ConfigError, match="preset 'nope' is unknown; known presets: sanchez2012"):
        presets.get("nope")
    base = presets.get("sanchez2012-optimal")
    with pytest.raises(ConfigError, match="expected key=value"):
        apply_overrides(base, ["box.Lz"])
    with pytest.raises(ConfigError, match="unknown key 'Lw'"):
        apply_overrides(base, ["box.Lw=0.1"])
    with pytest.raises(ConfigError, match="out of range"):
        apply_overrides(base, ["grains.3.count=1"])
    with pytest.raises(ConfigError, match="unknown key"):
        apply_overrides(base, ["bogus=1"])


def test_cli_reports_errors_before_compute(capsys):
    assert cli.main(["run", "--preset", "nope"]) == 2
    assert "preset 'nope' is unknown" in capsys.readouterr().err
    assert cli.main(["run", "--preset", "sanchez2012-optimal", "--frequency", "0"]) == 2
    assert "--frequency: 0: must be > 0" in capsys.readouterr().err
    assert cli.main(["run", "--preset", "sanchez2012-optimal", "--set", "box.Lz"]) == 2
    assert "expected key=value" in capsys.readouterr().err


def test_stored_configuration_matches_across_added_defaults():
    """A file written before a field with a default was added (its JSON lacks the field) still
    holds the same configuration, so sweeps resume and raw files are reused; a different
    value, or an unreadable text, does not match."""
    import json

    from jaxdamp.config import is_stored

    cfg = presets.get("sanchez2012-optimal")
    old = json.loads(cfg.to_json())
    del old["primary"]["z0"], old["primary"]["v0"]
    assert is_stored(json.dumps(old), cfg)
    assert not is_stored(json.dumps(old), apply_overrides(cfg, {"primary.z0": 0.01}))
    assert not is_stored("not json", cfg) and not is_stored(None, cfg)
