"""spreadmap.surrogate.validation.by_band: out-of-fold errors against their intervals by band of h/d,
on predictions whose errors and SDs are set by hand (the expected numbers written out)."""
import numpy as np
import pandas as pd
import pytest

from spreadmap.surrogate.validation import by_band


def test_bands_report_error_noise_and_the_intervals_fit():
    # band [0, 2): 4 cases, errors +-0.01, interval SD 0.02 -> z^2 0.25, all inside;
    # band >= 2: 2 cases x 2 repeats, errors +-0.03, interval SD 0.01 -> z^2 9, none inside
    oof = pd.DataFrame({
        "case_id": ["a", "b", "c", "d", "e", "e", "f", "f"],
        "y": [0.51, 0.49, 0.51, 0.49, 0.53, 0.47, 0.53, 0.47],
        "mean": [0.5] * 8,
        "run_sd": [0.02] * 4 + [0.01] * 4,
        "model_sd": [0.005] * 4 + [0.008] * 4,
        "case_sd": [0.015] * 4 + [0.006] * 4})
    h_over_d = pd.Series({"a": 1.2, "b": 1.9, "c": 0.5, "d": 1.0, "e": 2.0, "f": 6.0})
    bands = by_band(oof, h_over_d, edges=(0.0, 2.0, np.inf)).set_index("h_over_d")
    assert list(bands.index) == ["0-2", ">= 2"]  # h/d 2.0 falls in the upper band
    assert bands.loc["0-2", "cases"] == 4 and bands.loc[">= 2", "cases"] == 2
    np.testing.assert_allclose(bands["rmse"], [0.01, 0.03])
    np.testing.assert_allclose(bands["mean_z2"], [0.25, 9.0])
    np.testing.assert_allclose(bands["inside"], [1.0, 0.0])
    np.testing.assert_allclose(bands["interval_sd"], [0.02, 0.01])
    np.testing.assert_allclose(bands["model_sd"], [0.005, 0.008])
    np.testing.assert_allclose(bands["case_sd"], [0.015, 0.006])


def test_right_intervals_read_one_and_a_missing_h_over_d_is_refused():
    rng = np.random.default_rng(3)
    n = 20000
    sd = rng.uniform(0.005, 0.02, n)
    oof = pd.DataFrame({"case_id": np.arange(n).astype(str), "mean": 0.4, "run_sd": sd, "model_sd": sd / 2,
                        "case_sd": sd})
    oof["y"] = oof["mean"] + rng.normal(0, sd)
    h_over_d = pd.Series(rng.uniform(1.0, 6.0, n), index=oof["case_id"])
    bands = by_band(oof, h_over_d)
    assert len(bands) == 4
    assert np.all(np.abs(bands["mean_z2"] - 1.0) < 0.06)  # ~4000 draws of z^2 (SD sqrt(2)) a band
    assert np.all(np.abs(bands["inside"] - 0.95) < 0.015)
    with pytest.raises(ValueError, match="no h/d"):
        by_band(oof, h_over_d.iloc[1:])
