"""Maps drawn from an analytic predictor and a synthetic table of cases (no YADE)."""
import numpy as np
import pandas as pd
import pytest

from spreadmap import maps
from spreadmap.design import NAMES, bounds

LOW, HIGH = bounds()


def predict(points):
    """Smooth analytic stand-in for the surrogate: MFR grows with h/d, falls with f and v."""
    p = np.asarray(points, float)
    f, d, h, v = p.T
    mfr = 0.65 * (1 - np.exp(-(h / d - 1))) * (1 - 0.4 * (f - 0.15) / 0.3) * (1 - 0.02 * (v - 5))
    pd_ = (0.40 + 0.25 * np.sqrt(np.clip(mfr, 0, None)) - 0.05 * (f - 0.15) / 0.3
           - 0.004 * (v - 5) + 0.001 * (h - 55))
    return np.column_stack([mfr, pd_])


def assert_files(result):
    assert set(result.paths) == {"png", "pdf", "csv"}
    for path in result.paths.values():
        assert path.exists() and path.stat().st_size > 0, path
    return pd.read_csv(result.paths["csv"])


def test_save_figure(tmp_path):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    paths = maps.save_figure(fig, tmp_path / "sub" / "fig", pd.DataFrame({"x": [0, 1]}))
    assert [p.name for p in paths.values()] == ["fig.png", "fig.pdf", "fig.csv"]
    assert all(p.stat().st_size > 0 for p in paths.values())
    assert pd.read_csv(paths["csv"])["x"].tolist() == [0, 1]


def test_machine_map_grid(tmp_path):
    res = maps.machine_map(predict, tmp_path / "machine", f=0.3, d_um=20.0, n_h=4, n_v=3)
    csv = assert_files(res)
    assert len(csv) == 4 * 3
    assert list(csv.columns) == [*NAMES, "mfr", "pd"]
    np.testing.assert_allclose(np.unique(csv["h_um"]), np.linspace(55, 75, 4))
    np.testing.assert_allclose(np.unique(csv["v_mm_s"]), np.linspace(5, 15, 3))
    assert (csv["f"] == 0.3).all() and (csv["d_um"] == 20.0).all()
    # every (h, v) pair once, and the values are the predictor's
    assert len(csv[["h_um", "v_mm_s"]].drop_duplicates()) == 12
    np.testing.assert_allclose(csv[["mfr", "pd"]].to_numpy(),
                               predict(csv[list(NAMES)].to_numpy()))


def test_machine_map_defaults_and_explicit_values(tmp_path):
    res = maps.machine_map(predict, tmp_path / "m2", h_values=[55, 60, 75],
                           v_values=[5, 6.1, 10, 12, 15])
    csv = assert_files(res)
    assert len(csv) == 15
    assert (csv["f"] == 0.45).all() and (csv["d_um"] == 45.0).all()  # SPEC defaults
    np.testing.assert_allclose(np.unique(csv["h_um"]), [55, 60, 75])
    np.testing.assert_allclose(np.unique(csv["v_mm_s"]), [5, 6.1, 10, 12, 15])


def test_machine_map_many_lines(tmp_path):
    res = maps.machine_map(predict, tmp_path / "m3", n_h=11, n_v=9)  # labels thinned
    assert len(assert_files(res)) == 99


def test_powder_band_map(tmp_path):
    res = maps.powder_band_map(predict, tmp_path / "band", n_d=9, n_f=3)
    csv = assert_files(res)
    assert len(csv) == 9 * 3
    assert (csv["h_um"] == 57.0).all() and (csv["v_mm_s"] == 6.1).all()
    np.testing.assert_allclose(np.unique(csv["f"]), [0.15, 0.30, 0.45])
    np.testing.assert_allclose(np.unique(csv["d_um"]), np.linspace(10, 50, 9))


def test_powder_cluster_map(tmp_path):
    res = maps.powder_cluster_map(predict, tmp_path / "clusters", h_um=60.0, v_mm_s=10.0,
                                  d_values=[15, 30, 45], n_f=4)
    csv = assert_files(res)
    assert len(csv) == 12
    assert (csv["h_um"] == 60.0).all() and (csv["v_mm_s"] == 10.0).all()
    np.testing.assert_allclose(np.unique(csv["d_um"]), [15, 30, 45])
    np.testing.assert_allclose(np.unique(csv["f"]), np.linspace(0.15, 0.45, 4))


def make_cases(n=60, seed=0):
    rng = np.random.default_rng(seed)
    pts = LOW + rng.random((n, 4)) * (HIGH - LOW)
    y = predict(pts) + rng.normal(0, 0.01, (n, 2))
    cases = pd.DataFrame(pts, columns=list(NAMES))
    cases.insert(0, "case_id", [f"lds_{i:04d}" for i in range(n)])
    cases["status"] = "ok"
    cases["flagged"] = False
    cases["mfr"], cases["pd"] = y[:, 0], y[:, 1]
    cases["regime"] = maps.classify_regime(y[:, 0], y[:, 1], 0.15, 0.5)
    return cases


def test_parallel_coordinates_marks_best(tmp_path):
    cases = make_cases()
    # the densest case overall flows too little; a flagged case is denser still;
    # the best admissible case is planted explicitly
    cases.loc[3, ["mfr", "pd"]] = [0.05, 0.73]
    cases.loc[7, ["mfr", "pd", "flagged"]] = [0.6, 0.74, True]
    cases.loc[11, ["mfr", "pd"]] = [0.45, 0.72]
    cases.loc[12, ["status", "mfr", "pd"]] = ["failed", np.nan, np.nan]
    res = maps.parallel_coordinates(cases, tmp_path / "pc", mfr_min=0.3)
    csv = assert_files(res)
    assert res.best["case_id"] == "lds_0011"
    assert len(csv) == len(cases) - 2  # flagged and failed cases are not drawn
    assert csv["best"].sum() == 1
    assert csv.loc[csv["best"], "case_id"].item() == "lds_0011"
    for col in ("mfr_norm", "pd_norm", *[f"{n}_norm" for n in NAMES]):
        assert csv[col].between(0, 1).all()
    # without the MFR threshold the densest usable case wins; a score can override both
    assert maps.best_case(maps.usable_cases(cases))["case_id"] == "lds_0003"
    res2 = maps.parallel_coordinates(cases, tmp_path / "pc2",
                                     score=lambda df: df["mfr"] + df["pd"])
    assert res2.best["case_id"] == "lds_0011"


def test_regime_overlay_counts(tmp_path):
    cases = make_cases(80, seed=1)
    cases.loc[0, "regime"] = ""  # a failed run has no regime
    cases.loc[0, ["status", "mfr", "pd"]] = ["failed", np.nan, np.nan]
    cases.loc[1:5, "regime"] = "jamming"  # DEM disagrees with the thresholds for a few
    res = maps.regime_overlay(cases, predict, tmp_path / "regimes", jam_mfr_max=0.15,
                              short_feed_pd_min=0.5)
    csv = assert_files(res)
    expected = cases["regime"].value_counts()
    for r in maps.REGIMES:
        assert res.counts.loc[r, "dem"] == expected.get(r, 0)
    assert res.counts["dem"].sum() == len(cases) - 1
    assert res.info["excluded"] == 1
    assert len(csv) == len(cases) - 1
    # surrogate regimes follow the rules on the predictor's values
    pred = predict(cases.loc[1:, list(NAMES)].to_numpy())
    rule = maps.classify_regime(pred[:, 0], pred[:, 1], 0.15, 0.5)
    for r in maps.REGIMES:
        assert res.counts.loc[r, "surrogate"] == int((rule == r).sum())
    assert res.info["agree"] == int(csv["agree"].sum())
    assert (csv["regime"] == csv["regime_pred"]).sum() == res.counts["both"].sum()


def test_classify_regime_rules():
    got = maps.classify_regime([0.01, 0.01, 0.3, 0.3], [0.3, 0.6, 0.3, 0.6], 0.05, 0.5)
    assert list(got) == ["jamming", "jamming", "short_feed", "normal"]


def test_bad_predictor_shape(tmp_path):
    with pytest.raises(ValueError, match="shape"):
        maps.machine_map(lambda p: p[:, :1], tmp_path / "x", n_h=2, n_v=2)
