"""Pair kernels, one module per pair family in the canonical order of shape codes
(constants.py), entry points ``collide_<a>_<b>``; kernels/narrowphase.py's pair table says
which answers each pair."""
