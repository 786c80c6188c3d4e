"""How many random cases a sampled test draws: a quick sample in ``make test``, the
whole one in ``make test-slow``.

A test that draws its cases (Hypothesis's examples, generated missions, mutants)
makes the same checks on each: the quick sample keeps every check and draws fewer
cases, so that the suite fits its budget on two cores. ``make test-slow`` sets
``MCL2PNML_TEST_THOROUGH=1`` and draws the whole one, besides running the tests
marked ``slow``.
"""
from __future__ import annotations

import os

#: The environment variable that asks for the whole samples.
ENV = "MCL2PNML_TEST_THOROUGH"
THOROUGH = os.environ.get(ENV) == "1"


def sample(whole: int, quick: int) -> int:
    """``whole`` cases when the run is thorough, ``quick`` otherwise."""
    if not 0 < quick <= whole:
        raise ValueError(f"a quick sample of {quick} out of {whole}")
    return whole if THOROUGH else quick
