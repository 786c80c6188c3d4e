"""``python -m mcl2pnml`` is the ``mcl2pnml`` command."""
from .cli import main

main()
