"""PNML in and out: the writer, the tolerant-but-strict reader, the grammar check."""
from mcl2pnml.io.pnml.reader import load_pnml, parse_pnml
from mcl2pnml.io.pnml.writer import save_pnml, to_pnml_bytes, write_pnml

__all__ = ["load_pnml", "parse_pnml", "save_pnml", "to_pnml_bytes", "write_pnml"]
