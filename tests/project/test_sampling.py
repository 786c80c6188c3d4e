"""The quick suite's selection (tests/support/sampling.py): what ``make test`` leaves to
``make test-slow`` is marked so, and a quick variant that is not one is refused."""
import pytest

from sampling import VARIANT, sample, variants


def test_a_variant_left_out_is_slow_and_marked_variant_and_a_long_one_slow_only():
    params = variants(["a", "b", "c"], ["a"], ids=["A", "B", "C"], slow=["c"])
    marks = {p.id: {m.name for m in p.marks} for p in params}
    assert marks == {"A": set(), "B": {m.name for m in VARIANT}, "C": {"slow"}}
    assert [p.values for p in params] == [("a",), ("b",), ("c",)]


def test_a_tuple_is_one_value_per_argument_name():
    (param,) = variants([("sauce", "Ends")], [("sauce", "Ends")])
    assert param.values == ("sauce", "Ends") and not param.marks


def test_a_quick_variant_that_is_not_a_variant_is_refused():
    with pytest.raises(ValueError, match="not variants"):
        variants(["a"], ["b"])
    with pytest.raises(ValueError, match="quick sample"):
        sample(10, 20)
