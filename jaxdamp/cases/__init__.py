"""Reference cases: the presets of the two sources and the binary-mixture class builders.

* :mod:`~jaxdamp.cases.presets` — named configurations (``jaxdamp presets``).
* :mod:`~jaxdamp.cases.mixtures` — classes a/b/c of the 2023 paper's binary mixtures.
"""
