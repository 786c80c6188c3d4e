"""The core: Petri nets as plain immutable data, and what every layer shares.

Owns the net (places, transitions, arcs, the initial marking) and markings
kept apart from it; composition by place fusion (the paper's one operation,
sections 2.3 and 2.5); the indexed pre/post view of a net that analysis and
execution share; the typed records that travel in transition payloads
between the compiler, the executor and the writers; the one error type with
its file:line:col rendering; atomic files; the collector pause; the memory
budget of a command and the estimates it is held to.

May import: nothing of ours (the standard library and third-party packages
only). Every other layer imports it.
"""
