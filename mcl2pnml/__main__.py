"""``python -m mcl2pnml`` is the ``mcl2pnml`` command."""
from mcl2pnml.cli import main

main()
