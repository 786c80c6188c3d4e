"""PNML in and out: the writer, the tolerant-but-strict reader, the grammar check."""
from mcl2pnml.io.pnml.reader import parse_pnml, read_pnml
from mcl2pnml.io.pnml.writer import stream_pnml, to_pnml, write_pnml

__all__ = ["parse_pnml", "read_pnml", "stream_pnml", "to_pnml", "write_pnml"]
