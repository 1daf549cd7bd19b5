"""Test-session settings that must precede every import of the packages they configure."""

import os

# The fused device step (jaxdamp.engine.fused) runs in numba-cuda's CUDA simulator in the tests
# (a CPU-only machine; set NUMBA_ENABLE_CUDASIM=0 to run them on a GPU). numba.cuda reads this
# once, when first imported, so it is set before any test imports it.
os.environ.setdefault("NUMBA_ENABLE_CUDASIM", "1")

# JAX's persistent compilation cache, shared by the xdist workers and by CI's two pytest steps
# (and by the command lines the tests start): a program compiled once in any of them is read
# back instead of compiled again (README: the CLI tests ran 96-99 s with it, 120-137 s
# without). Keyed by JAX on the program, its options and the jax/jaxlib version, so a stale entry
# is never used; kept in the git-ignored .pytest_cache; JAX_COMPILATION_CACHE_DIR="" turns it
# off.
os.environ.setdefault("JAX_COMPILATION_CACHE_DIR",
                      os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                   ".pytest_cache", "jax-compile"))
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.3")
# A program read back from that cache makes XLA:CPU log an ERROR line per entry on this AMD host
# ("Loading XLA:CPU AOT result. Target machine feature +prefer-no-gather is not supported":
# tuning flags it compiled with, absent from the host's feature list — the same machine), on
# the stderr of the command lines the tests start, whose every line the tests check (a
# Ctrl-C's and a full disk's one-line messages failed on it with a warm cache). XLA's own
# logging off in the tests (TF_CPP_MIN_LOG_LEVEL=3: errors too); jaxdamp's messages are its own.
os.environ.setdefault("TF_CPP_MIN_LOG_LEVEL", "3")
