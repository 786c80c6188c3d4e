"""The version of mcl2pnml, which every file it writes names (PNML, TINA, LoLA)."""

__version__ = "0.1.0"
