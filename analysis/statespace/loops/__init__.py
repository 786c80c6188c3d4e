"""The explorers' inner loops behind one typed interface (``interface.py``): in C
(``c.py`` over ``_native.c``, built at install) and their plain-Python reference
(``python.py``); ``backends.py`` says which runs here."""
