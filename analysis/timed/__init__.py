"""Time: the zone graph of a time Petri net and the verdicts it proves."""
