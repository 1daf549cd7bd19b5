"""The container registry (jaxdamp.physics.containers): each container's JAX, scalar and
host-side forms agree with one another, and the settled-bed cache is keyed by exclusion."""

import dataclasses
import json

import numpy as np
import pytest

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.physics import containers
from jaxdamp.physics.containers import CONTAINERS, MAX_SIDES, container
from jaxdamp.studies.grid import BED_FREE, geometry_key


@pytest.mark.parametrize("name", sorted(CONTAINERS))
def test_the_scalar_and_jax_forms_of_every_container_agree(name):
    """Distances, normals and curvatures of the side walls at 200 random points of the
    section: the JAX form (walls.py) and the scalar forms the compiled kernel inlines."""
    cfg = presets.get("sanchez2012-optimal")
    vessel = CONTAINERS[name]
    assert container(cfg) is vessel or name != "box"
    section = np.asarray(vessel.section(cfg))
    x0, x1, y0, y1 = vessel.extent(cfg)
    rng = np.random.default_rng(0)
    x = rng.uniform(x0, x1, 200)
    y = rng.uniform(y0, y1, 200)
    gaps, (nx, ny), kappa = vessel.sides_jax(x, y, section)
    W = len(gaps)
    assert 1 <= W <= MAX_SIDES and len(kappa) == W
    nx = np.broadcast_to(np.asarray(nx, float), (200, W))
    ny = np.broadcast_to(np.asarray(ny, float), (200, W))
    for i in range(200):
        s = containers.sides_scalar(vessel.id, x[i], y[i], section)
        assert len(s) == MAX_SIDES
        np.testing.assert_allclose(s[:W], [float(np.asarray(g)[i]) for g in gaps], rtol=0,
                                   atol=1e-15)
        assert all(v == np.inf for v in s[W:])
        for k in range(W):
            n = containers.normal_scalar(vessel.id, k, x[i], y[i], section)
            np.testing.assert_allclose(n, (nx[i, k], ny[i, k], kappa[k]), atol=1e-15)
            assert abs(np.hypot(n[0], n[1]) - 1.0) < 1e-12  # a unit normal in the plane
    # stepping along the inward normal by d reduces nothing and grows the distance by d for a
    # plane (less for a concave wall): the normal points into the cavity
    inside = vessel.inside(x, y, 0.0, cfg)
    assert inside.all()


def test_the_box_outline_extent_area_and_fit():
    cfg = presets.get("sanchez2012-optimal")
    box = container(cfg)
    L = cfg.box.Lx
    assert box.extent(cfg) == (0.0, L, 0.0, cfg.box.Ly)
    assert box.base_area(cfg) == pytest.approx(L * cfg.box.Ly, rel=1e-15)
    assert box.height(cfg) == cfg.box.Lz
    lines = box.outline(cfg, 0.5)
    pts = np.concatenate(lines)
    assert len(lines) == 12
    np.testing.assert_allclose(pts.min(axis=0), [0, 0, 0.5])
    np.testing.assert_allclose(pts.max(axis=0), [L, cfg.box.Ly, 0.5 + cfg.box.Lz])
    assert box.fit_error(cfg, 0.9 * L, "a grain") is None
    assert "does not fit box.Lx" in box.fit_error(cfg, 1.01 * L, "a grain")


def _leaves(d, path=""):
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _leaves(v, f"{path}.{k}" if path else k)
    elif isinstance(d, list) and d and isinstance(d[0], dict):
        for i, v in enumerate(d):
            yield from _leaves(v, f"{path}.{i}")
    else:
        yield path, d


def test_the_bed_cache_key_is_everything_but_the_lid_excitation_and_run_length():
    """The live bug of issue 34: a bed settled under another contact law or wall damping was
    reused. Now the key is the whole configuration except what may vary on a settled bed, so
    changing any other field — checked leaf by leaf — changes the key."""
    cfg = presets.get("sanchez2012-optimal")
    key = geometry_key(cfg)
    assert geometry_key(apply_overrides(cfg, {"contact_law": "linear",
                                              "grains.0.material.linear_stiffness": 1e5,
                                              "grains.0.material.restitution": 0.5})) != key
    assert geometry_key(apply_overrides(cfg, {"wall_damping": "calibrated"})) != key
    same = {"box.Lz": 0.2, "frequency": 20.0, "primary.U": 1e-3, "numerics.duration": 9.0,
            "numerics.record_dt": 1e-3, "direction": [0.0, 0.3, 1.0], "name": "other"}
    assert geometry_key(apply_overrides(cfg, same)) == key
    free = set(BED_FREE) | {container(cfg).lid_key}
    d = cfg.to_dict()
    checked = 0
    for path, value in _leaves(d):
        if any(path == f or path.startswith(f + ".") for f in free):
            continue
        if isinstance(value, str) or value is None or isinstance(value, list):
            continue  # texts and tables: the numbers below cover the mechanism
        changed = json.loads(json.dumps(d))
        node = changed
        *head, last = path.split(".")
        for part in head:
            node = node[int(part)] if isinstance(node, list) else node[part]
        node[last] = value * 1.01 + 1 if not isinstance(value, bool) else not value
        from jaxdamp.config import from_dict

        assert geometry_key(from_dict(changed)) != key, path
        checked += 1
    assert checked >= 20


@pytest.mark.long
def test_a_sweep_settles_anew_for_another_wall_damping():
    """End to end through the sweep's bed cache: the same damper with its walls' damping
    calibrated gets a bed of its own (before the fix it reused the other bed)."""
    from jaxdamp.studies.sweep import sweep

    cfg = apply_overrides(presets.get("varela2023-reference"),
                          {"grains.0.count": 20, "numerics.duration": 0.005,
                           "numerics.settle_time": 0.02, "numerics.engine": "native"})
    beds: dict = {}
    sweep(cfg, {"frequency": [15.0]}, progress=False, echo=None, beds=beds)
    assert len(beds) == 1
    lin = apply_overrides(cfg, {"wall_damping": "calibrated"})
    sweep(lin, {"frequency": [15.0]}, progress=False, echo=None, beds=beds)
    assert len(beds) == 2
    sweep(dataclasses.replace(cfg, frequency=60.0), {"box.Lz": [0.07, 0.09]}, progress=False,
          echo=None, beds=beds)
    assert len(beds) == 2  # another lid and frequency: the same bed
