"""The bridge link's timing and size defaults, apart from the link itself.

The command line shows them in its options' help; keeping them here lets it do
so without loading the link's sockets, TLS and threads (:mod:`mcl2pnml.runtime.link`),
which every command but ``run`` with a bridge would pay for at start-up.
"""
from __future__ import annotations

#: Seconds between heartbeats, from each end.
HEARTBEAT = 1.0
#: Seconds without any line from the other end before the link counts as lost.
LIVENESS = 5.0
#: Seconds a send may take (written to the kernel) before the link counts as lost.
SEND_TIMEOUT = 5.0
#: The longest line, in bytes (its newline excluded).
MAX_LINE = 64 * 1024
