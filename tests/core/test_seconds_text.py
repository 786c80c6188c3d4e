"""Every printer of a time writes it exactly (core.timing.seconds_text): a decimal where
there is one, never rounded nor with an exponent; ``p/q`` where there is none."""
from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import given, strategies as st

from mcl2pnml.core.timing import Assumptions, seconds_text


@pytest.mark.parametrize("seconds, text", [
    (Fraction(200001, 2), "100000.5"), (Fraction(10 ** 9), "1000000000"),
    (Fraction(1, 1000), "0.001"), (Fraction(0), "0"), (Fraction(-1, 2), "-0.5"),
    (Fraction(999999999999999, 10 ** 6), "999999999.999999"), (Fraction(1, 8), "0.125"),
    (Fraction(1, 3), "1/3"), (Fraction(-7, 6), "-7/6"), (12, "12"),
])
def test_a_time_is_written_exactly(seconds, text):
    assert seconds_text(seconds) == text


@given(st.integers(-10 ** 20, 10 ** 20), st.integers(0, 30), st.integers(0, 30))
def test_a_decimal_time_reads_back_as_itself(numerator, twos, fives):
    seconds = Fraction(numerator, 2 ** twos * 5 ** fives)
    text = seconds_text(seconds)
    assert Fraction(text) == seconds and "e" not in text and "/" not in text
    assert not text.endswith(".") and not ("." in text and text.endswith("0"))


@given(st.fractions())
def test_any_time_reads_back_as_itself(seconds):
    assert Fraction(seconds_text(seconds)) == seconds


def test_the_assumptions_are_written_exactly():
    words = Assumptions(ack_within=Fraction(1000001, 2), report_gap=Fraction(10 ** 9)).words()
    assert words.startswith("acknowledgements within 500000.5 s; a primitive's reports at "
                            "least 1000000000 s apart")
