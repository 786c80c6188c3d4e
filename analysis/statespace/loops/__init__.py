"""The explorers' inner loops: in C (``_native.c``, built at install) and their fallbacks."""
