"""Input and output: nets in the formats of other tools, behind one table.

Owns PNML (ISO/IEC 15909-2: writer, reader, grammar check), TINA's ``.net``,
LoLA's format and graphviz's DOT, each one module, and the format table
(:mod:`mcl2pnml.io.formats`) that names them, their suffixes, what each
can say, and how to load and save them. Serialising never lays out: node
positions come from the caller.

May import: :mod:`mcl2pnml.core` only.
"""
