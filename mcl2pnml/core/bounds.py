"""The largest numbers mcl2pnml reads, and how a reader checks a number's text against them.

A number is bounded where it is read, so that every later stage sees only
values it can hold, and a number too large is one message at its place in
the file, not a failure deep inside (Python refuses to turn an integer of
more than 4,300 digits into text or back, and an unbounded one would pass
through the analysis's 64-bit counters):

* markings and arc weights (PNML, TINA, LoLA): at most :data:`MAX_TOKENS`,
  2^63 - 1, what the analysis's counters hold (``mcl2pnml.analysis.statespace.counters``
  counts tokens in signed 64-bit integers);
* time-outs (MCL) and time bounds (TINA): finite, at most
  :data:`MAX_SECONDS` seconds of virtual time (about 31.7 years), far
  beyond any mission and still exact as a float to the microsecond that
  the TINA writer counts in;
* the vehicle's assumed timing (an acknowledgement, a gap between reports): at most
  :data:`MAX_ACK_WITHIN` and :data:`MAX_REPORT_GAP` seconds;
* any other number in MCL: an integer of at most :data:`MAX_INTEGER` in
  size, or a finite decimal (a double).

And the missions and properties a command reads: a mission of at most
:data:`MAX_MISSION_SIZE` bytes and a side file of properties of at most
:data:`MAX_PROPERTIES_SIZE`, each checked before it is read, and at most
:data:`MAX_PROPERTY_ATOMS` atoms in all, counted once they are parsed; a
certificate of at most :data:`MAX_CERTIFICATE_SIZE`.

And the work a command does unless told otherwise, each bound written here once for
every command, library call and option that shares it: the markings an exploration
builds (:data:`MAX_STATES`), the states a check of properties or a zone graph builds
(:data:`MAX_CHECK_STATES`), the longest run (:data:`MAX_RUN_TIME`).
"""
from __future__ import annotations

#: The largest marking of a place and weight of an arc.
MAX_TOKENS = 2 ** 63 - 1
#: How the messages write it.
MAX_TOKENS_TEXT = "2^63-1 (9,223,372,036,854,775,807)"
#: The longest time-out and time bound, in seconds.
MAX_SECONDS = 1_000_000_000
#: The longest a vehicle may take to acknowledge a request, in seconds: ten minutes, both
#: as the timed analysis assumes it (``analyze --ack-within``) and as the autopilot bridge
#: waits for it (the mapping's ``ack_within``). A vehicle slower than that has a broken
#: link; and the timed analysis's cost grows with the window (docs/time.md).
MAX_ACK_WITHIN = 600
#: The longest gap between a primitive's reports the timed analysis assumes, in seconds
#: (``analyze --report-gap``): a day, far beyond any controller's reporting period.
MAX_REPORT_GAP = 24 * 3600
#: The largest integer literal of MCL, in size (a decimal may be larger, up to a double's).
MAX_INTEGER = 2 ** 63 - 1
#: The largest MCL mission read, unless raised (``--max-mission-size``): a mission a person
#: writes is a few KB (the examples' largest is 2 KB) and a generated survey of 100,000
#: calls 2.3 MiB; reading and checking cost about 2 s and 65 MB a MiB, in proportion
#: (bench/mission_scale.py), so that a mission at the limit is checked in under a minute
#: within about 1 GB, and a file of gigabytes, which would exhaust the memory, is refused
#: before a byte of it is read.
MAX_MISSION_SIZE = 16 << 20
#: The largest side file of properties read, unless raised (``--max-properties-size``):
#: the examples' are a few KB; reading and parsing cost about 2 s and 50 MB a MiB.
MAX_PROPERTIES_SIZE = 4 << 20
#: The most atoms (``true`` and ``false`` count) the properties of one command may
#: have in all, unless raised (``--max-atoms``): each atom is evaluated in each
#: marking of the product the checker explores, so that the limit keeps a command's
#: time and memory in proportion to what a person writes.
MAX_PROPERTY_ATOMS = 10_000
#: The largest certificate read, unless raised (``--max-certificate-size``): a 10,000-call
#: survey's is 3.3 MB; read as JSON, a file takes about fifteen times its size in memory.
MAX_CERTIFICATE_SIZE = 16 << 20

#: The most markings an exploration builds, unless told (``analyze --max-states``, ``query
#: --max-states``, :func:`mcl2pnml.analysis.statespace.explore.explore`).
MAX_STATES = 5_000_000
#: The most states a check of properties (a product of the net with an observer) or a
#: zone graph (the timed verdicts) builds, unless told.
MAX_CHECK_STATES = 1_000_000
#: The most instants the exact odds explore (``odds --max-states``) before they are
#: refused as too large (:mod:`mcl2pnml.odds`).
MAX_CHAIN_STATES = 200_000
#: The longest run, in seconds (virtual, or the wall clock's), unless told
#: (``run --max-time``, and each run of a campaign): a day.
MAX_RUN_TIME = 24 * 3600.0


def natural_at_most(digits: str, limit: int) -> int | None:
    """The value of a text of decimal digits, or None if it is more than ``limit``.

    The length is judged first: a text of 5,000 digits is never turned into
    an integer (Python refuses to beyond 4,300 digits, and it costs time).
    """
    significant = digits.lstrip("0")
    if len(significant) > len(str(limit)):
        return None
    value = int(significant or "0")
    return value if value <= limit else None
