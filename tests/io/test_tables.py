"""Table cells for people (capmap.io.tables.fmt_value): counts as integers, errors in scientific
notation with 3 digits, other numbers to 4 significant digits, numbers read back as text alike; each
formatted value parses back to the number within its stated precision."""

from __future__ import annotations

import numpy as np
import pytest

from capmap.io.tables import fmt_value


@pytest.mark.parametrize("raw, shown", [
    ("1.624677775646788e-08", "1.62e-08"), ("0.005000000000000046", "0.005"), ("100000000000.0", "1e+11"),
    ("70460.0", "70460"), (70460.0, "70460"), (np.int64(7), "7"), (1234.5678, "1234.6"), (0.0123456, "0.01235"),
    ("True", "True"), ("right_s1", "right_s1"), ("-", "-"), (float("nan"), ""), (None, ""), (True, "True"),
])
def test_cells(raw, shown):
    assert fmt_value(raw) == shown


def test_formatted_numbers_parse_back_within_their_precision():
    rng = np.random.default_rng(0)
    x = np.concatenate([10.0 ** rng.uniform(-12, 12, 2000) * rng.choice([-1, 1], 2000),
                        np.round(rng.uniform(0, 1e8, 200))])
    for v in x:
        back = float(fmt_value(float(v)))
        if float(v).is_integer() and abs(v) < 1e9:
            assert back == v
        else:  # 3 significant digits at worst (scientific), 4 otherwise; one decimal from 100 is finer
            assert abs(back - v) <= 5e-3 * abs(v)
        assert float(fmt_value(str(v))) == back  # the same number as text reads the same
