"""The one usable-case rule and the one partition (spreadmap.table), and their readers taking
the same rows."""
import numpy as np
import pandas as pd
import pytest
import synthetic_cases as syn

from spreadmap.design import NAMES
from spreadmap.loop.model import table_data
from spreadmap.study_rule import rule, rule_plots
from spreadmap.surrogate.training_rows import select
from spreadmap.table import partition, usable, usable_cases


def cases() -> pd.DataFrame:
    """Six cases: 0 clean, 1 flagged, 2 failed, 3 with PD empty, 4 with MFR text, 5 clean."""
    t = syn.table(6, 0.05, seed=1)
    t["mfr"] = t["mfr"].astype(object)
    t.loc[1, "flagged"] = True
    t.loc[2, "status"] = "failed"
    t.loc[3, "pd"] = np.nan
    t.loc[4, "mfr"] = "n/a"
    return t


def test_usable_is_finished_not_flagged_and_finite_in_the_columns_asked():
    t = cases()
    assert list(np.flatnonzero(usable(t))) == [0, 3, 4, 5]
    assert list(np.flatnonzero(usable(t, ["pd"]))) == [0, 4, 5]
    assert list(usable_cases(t, ["mfr", "pd"]).index) == [0, 5]  # text counts as not finite
    with pytest.raises(ValueError, match=r"lacks column\(s\) \['coverage'\]"):
        usable(t, ["mfr", "coverage"])


def test_every_reader_takes_the_rules_rows():
    """The surrogate's training rows and the loop's map model take exactly the rule's rows."""
    t = cases()
    assert list(select(t, ["mfr", "pd"]).frame["case_id"]) == list(usable_cases(t, [*NAMES, "mfr", "pd"])["case_id"])
    X, y, _ = table_data(t, "pd")
    np.testing.assert_array_equal(y, usable_cases(t, ["pd"])["pd"].to_numpy(float))


def test_partition_is_the_first_n_positions_of_one_sweep_in_order():
    t = syn.table(8, 0.05).sample(frac=1.0, random_state=3)  # rows shuffled
    other = syn.table(3, 0.05).assign(sweep="points")
    both = pd.concat([t, other])
    p = partition(both, 5)
    assert list(p["index"]) == [0, 1, 2, 3, 4] and set(p["sweep"]) == {"lds"}
    assert len(partition(both, 5, sweep=None)) == 5 + 3  # every sweep's positions below 5


def test_the_study_rule_refuses_a_sequence_with_a_missing_position():
    t = syn.table(40, 0.05)
    rule.convergence_table(t, partitions=[20, 40])  # whole: fine
    with pytest.raises(ValueError, match=r"\[\(20, 19\), \(39, 38\)\].*not 0 \.\. N-1"):
        rule.convergence_table(t.drop(index=7), partitions=[20, 39])  # position 7 has no row
    values = rule_plots.partition_values(t, "lds", partitions=[10])
    assert len(values) == 2 * 10 and set(values["partition"]) == {10}
