"""Input and output: nets in the formats of other tools, behind one table.

Owns PNML (ISO/IEC 15909-2: writer, reader, grammar check), TINA's ``.net``,
LoLA's format and graphviz's DOT, each one module, and the format table
(:mod:`mcl2pnml.io.formats`) that names them, their suffixes, what each
can say, and how to read and write them. Serialising never lays out and
never draws: node positions, and a drawing's DOT text, come from the caller
(:mod:`mcl2pnml.view`).

May import: :mod:`mcl2pnml.core` only.
"""
