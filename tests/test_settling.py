"""Settling stops at ``numerics.settle_time`` counted in whole chunks of a nominal 20 ms: a
chunk's steps (``round(5 ms / dt)`` per sample) may end a little short of 20 ms, which must not
cost one more chunk (it did: ``settle_time = 0.02`` settled for 0.04 s)."""

import pytest

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.engine.packing import SETTLE_PIECE, settle
from jaxdamp.physics.model import build


@pytest.mark.parametrize("limit, chunks", [(0.02, 1), (0.03, 2), (0.04, 2)])
def test_settling_stops_at_its_time_limit_in_whole_chunks(limit, chunks):
    """The thesis bed, never slow enough to count as settled (``settle_speed`` 1e-9 m/s):
    its settling ends after ``ceil(settle_time / 20 ms)`` chunks, each within a step per
    sample of 20 ms, and the bed is marked not settled."""
    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          {"numerics.settle_time": limit, "numerics.settle_speed": 1e-9})
    model, params = build(cfg)
    bed = settle(cfg, model, params)
    dt = float(params.dt)
    assert not bed.settled
    assert abs(bed.time - chunks * SETTLE_PIECE) <= 4 * chunks * dt, (bed.time, dt)
