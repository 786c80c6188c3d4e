"""What the quick suite keeps of a test's cases: a quick sample of the random cases in
``make test``, the whole one in ``make test-slow``; and of a check made on every example,
the examples that reach every line and branch of ours that the others reach (``variants``).

A test that draws its cases (Hypothesis's examples, generated missions, mutants)
makes the same checks on each: the quick sample keeps every check and draws fewer
cases, so that the suite fits its budget on two cores. ``make test-slow`` sets
``MCL2PNML_TEST_THOROUGH=1`` and draws the whole one, besides running the tests
marked ``slow``.
"""
from __future__ import annotations

import os

import pytest

#: The marks of a variant left to ``make test-slow``: one more input to a check that the
#: quick suite makes on others, reaching no line or branch of ours that they do not.
VARIANT = (pytest.mark.slow, pytest.mark.variant)
#: The environment variable that asks for the whole samples.
ENV = "MCL2PNML_TEST_THOROUGH"
THOROUGH = os.environ.get(ENV) == "1"


def sample(whole: int, quick: int) -> int:
    """``whole`` cases when the run is thorough, ``quick`` otherwise."""
    if not 0 < quick <= whole:
        raise ValueError(f"a quick sample of {quick} out of {whole}")
    return whole if THOROUGH else quick


def variants(values, quick, ids=None, slow=()) -> list:
    """``values`` as the parameters of a test (a tuple: one value per argument name), those
    not in ``quick`` marked ``slow``, for ``make test-slow``: the variants kept in ``make
    test`` are chosen to reach every line and branch of ours that the whole set reaches
    (``python tests/support/coverage_check.py`` measures it). Those in ``slow`` are marked
    ``slow`` only: too long for the quick suite, whatever they reach."""
    values = list(values)
    kept, long = set(quick), set(slow)
    unknown = (kept | long) - set(values)
    if unknown:
        raise ValueError(f"quick variants that are not variants: {sorted(map(str, unknown))}")
    names = ids if ids is not None else [None] * len(values)
    # a tuple is one value per argument name: parametrize("name,prop", ...)
    return [pytest.param(*(v if isinstance(v, tuple) else (v,)), id=name,
                         marks=() if v in kept else pytest.mark.slow if v in long else VARIANT)
            for v, name in zip(values, names)]
