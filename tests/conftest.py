"""Test-session settings that must precede every import of the packages they configure."""

import os

# The fused device step (jaxdamp.engine.fused) runs in numba-cuda's CUDA simulator in the tests
# (a CPU-only machine; set NUMBA_ENABLE_CUDASIM=0 to run them on a GPU). numba.cuda reads this
# once, when first imported, so it is set before any test imports it.
os.environ.setdefault("NUMBA_ENABLE_CUDASIM", "1")
