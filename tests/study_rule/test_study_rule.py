"""Tests of spreadmap.study_rule, the study's 5-statistic convergence rule: the statistics, the change
rule and its floors, the near-zero rule, the detectors, the batches' stop, the summary and the plots."""
import json

import numpy as np
import pandas as pd
import pytest
from figure_text import pdf_text
from scipy import stats

from spreadmap import study_rule as cv
from spreadmap.case.substrate import floor_label

TOL = cv.DEFAULT_TOLERANCE


def _table(values_mfr, values_pd=None, **extra):
    n = len(values_mfr)
    df = pd.DataFrame({"case_id": [f"c{i}" for i in range(n)], "sweep": "lds",
                       "index": np.arange(n), "mfr": values_mfr,
                       "pd": values_mfr if values_pd is None else values_pd,
                       "status": "ok", "flagged": False})
    for k, v in extra.items():
        df[k] = v
    return df


# ---------------------------------------------------------------------------------------------
# statistics and the change rule
# ---------------------------------------------------------------------------------------------
def test_partition_statistics_equal_numpy_and_scipy():
    x = np.random.default_rng(3).gamma(2.0, 0.1, 257)
    got = cv.partition_statistics(x)
    assert tuple(got) == cv.STATISTICS
    assert got["mean"] == pytest.approx(np.mean(x), rel=1e-14)
    assert got["std"] == pytest.approx(np.std(x, ddof=1), rel=1e-14)
    assert got["median"] == np.median(x)
    assert got["kurtosis"] == pytest.approx(stats.kurtosis(x, fisher=True, bias=True), rel=1e-12)
    assert got["skewness"] == pytest.approx(stats.skew(x, bias=True), rel=1e-12)
    # failed cases (NaN) are dropped
    with_nan = np.concatenate([x, [np.nan, np.nan]])
    assert cv.partition_statistics(with_nan) == got
    # undefined statistics are NaN, not an error
    one = cv.partition_statistics([0.4])
    assert one["mean"] == 0.4 and np.isnan(one["std"]) and np.isnan(one["skewness"])


def _changes(prev, curr, floors=None):
    """The rule as convergence_table applies it, one statistic at a time."""
    fl = cv.rule._floors(floors)
    out = {}
    for s in cv.STATISTICS:
        c, d, b = cv.rule._change_arrays(prev[s], curr[s], fl[s])
        out[s] = {"change": float(c), "denominator": float(d), "basis": str(b)}
    return out


def test_change_rule_floor():
    prev = {"mean": 0.5, "std": 0.1, "median": 0.5, "kurtosis": -0.02, "skewness": 0.010}
    curr = {"mean": 0.501, "std": 0.1, "median": 0.49, "kurtosis": -0.024, "skewness": 0.013}
    ch = _changes(prev, curr)
    assert ch["mean"]["change"] == pytest.approx(0.002)
    assert ch["mean"]["basis"] == "previous" and ch["mean"]["denominator"] == 0.5
    assert ch["median"]["change"] == pytest.approx(0.02)
    assert ch["std"]["change"] == 0.0
    # near zero: the floor (1.0) is the denominator -> an absolute change
    assert ch["skewness"]["basis"] == "floor" and ch["skewness"]["denominator"] == 1.0
    assert ch["skewness"]["change"] == pytest.approx(0.003)
    assert ch["kurtosis"]["change"] == pytest.approx(0.004)
    # the naive rule would call the same skewness step a 30 % change
    naive = _changes(prev, curr, {"skewness": 0.0, "kurtosis": 0.0})
    assert naive["skewness"]["change"] == pytest.approx(0.3)
    assert naive["skewness"]["basis"] == "previous"
    big = _changes({**prev, "skewness": 2.0}, {**curr, "skewness": 2.02})
    assert big["skewness"]["basis"] == "previous" and big["skewness"]["change"] == pytest.approx(0.01)
    nan = _changes({**prev, "std": np.nan}, curr)
    assert np.isnan(nan["std"]["change"])
    with pytest.raises(ValueError):
        _changes(prev, curr, {"variance": 1.0})


# ---------------------------------------------------------------------------------------------
# partition detector
# ---------------------------------------------------------------------------------------------
def test_convergence_table_known_partition():
    rng = np.random.default_rng(7)
    a = rng.normal(0.30, 0.05, 100)
    b = rng.normal(0.50, 0.05, 100)
    # prefix 200 = a+b; prefixes 400 and 800 repeat it, so every statistic (up to the ddof=1
    # factor of std, 0.13 % from 200 to 400) stops changing at 400
    values = np.tile(np.concatenate([a, b]), 4)
    conv = cv.convergence_table(_table(values), partitions=[100, 200, 400, 800])
    assert list(conv["partition"]) == [100, 200, 400, 800]
    assert list(conv["converged"]) == [False, False, True, True]
    assert cv.first_converged(conv) == 400
    assert conv.loc[1, "mfr_mean_change"] > 0.3
    assert conv.loc[2, "max_change"] < 0.002
    # the same verdict from the growing-N detector run on the table itself
    res = cv.first_stable_n(conv, TOL)
    assert res["first_holds"] == 400 and res["stable_from"] == 400
    assert conv.loc[2, "pd_skewness_basis"] in ("floor", "previous")
    for t in ("mfr", "pd"):
        for s in cv.STATISTICS:
            assert {f"{t}_{s}", f"{t}_{s}_change", f"{t}_{s}_denominator"} <= set(conv.columns)


def _near_zero_skew_sequence(p=400, a=0.0033, c=0.5, sigma=0.05, blocks=8):
    """Blocks Z+, Z-, Z+, ... with Z- the mirror image of Z+ about c.

    Every prefix of k blocks has the same mean (c), the same m2 and m4 (so the same std up to
    ddof and the same kurtosis, itself near zero), a median within a*sigma of c, and skewness
    s/k for odd k and 0 for even k, with s the (small) skewness of Z+: it hovers around 0.
    """
    q = stats.norm.ppf((np.arange(p) + 0.5) / p)
    zp = c + sigma * (q + a * (q**2 - np.mean(q**2)))
    zm = 2 * c - zp
    return np.concatenate([zp if k % 2 == 0 else zm for k in range(blocks)]), stats.skew(zp)


def test_near_zero_skewness_rule_converges_where_naive_never_does():
    p = 400
    values, s = _near_zero_skew_sequence(p)
    # preconditions of the construction: changes s (2p), s/3 (3p, 4p) fail, s/5 (5p on) hold
    assert s / 3 > 1.1 * TOL and s / 5 < 0.9 * TOL
    parts = [p * k for k in range(1, 9)]
    conv = cv.convergence_table(_table(values), partitions=parts)
    assert abs(conv["mfr_skewness"]).max() < 0.03  # skewness really is near zero throughout
    assert abs(conv["mfr_kurtosis"]).max() < 0.1  # and so is the excess kurtosis
    assert conv["mfr_skewness"].iloc[1::2].abs().max() < 1e-10  # exactly 0 on even prefixes
    assert cv.first_converged(conv) == 5 * p
    assert list(conv["converged"]) == [False] * 4 + [True] * 4
    assert set(conv.loc[1:, "mfr_skewness_basis"]) == {"floor"}
    # the naive relative rule: never (every other step is a 100 % change, or one from ~0)
    naive = cv.convergence_table(_table(values), partitions=parts,
                                 floors={"skewness": 0.0, "kurtosis": 0.0})
    assert cv.first_converged(naive) is None
    assert naive.loc[1:, "mfr_skewness_change"].min() >= 1.0 - 1e-9


def test_drifting_distribution_never_converges():
    rng = np.random.default_rng(11)
    n = 2000
    values = 0.2 + 0.5 * np.arange(n) / n + rng.normal(0, 0.02, n)
    conv = cv.convergence_table(_table(values))  # default partitions: every 100 cases
    assert list(conv["partition"]) == list(range(100, 2001, 100))
    assert not conv["converged"].any()
    assert cv.first_converged(conv) is None
    out = cv.summary({"lds": conv})
    assert out["sweeps"]["lds"]["status"] == "not converged within the cases run"
    assert out["sweeps"]["lds"]["cases_run"] == 2000


def test_unusable_cases_are_left_out_but_counted_in_n():
    values = np.random.default_rng(1).normal(0.5, 0.05, 300)
    tab = _table(values)
    tab.loc[[5, 17], "status"] = "failed"
    tab.loc[[5, 17], ["mfr", "pd"]] = np.nan
    tab.loc[40, "flagged"] = True
    tab.loc[40, "mfr"] = 1e6  # a blown-up value that must not reach the statistics
    conv = cv.convergence_table(tab, partitions=[100, 300])
    assert list(conv["n_usable"]) == [97, 297]
    keep = np.ones(300, bool)
    keep[[5, 17, 40]] = False
    assert conv.loc[1, "mfr_mean"] == pytest.approx(values[keep].mean())
    # shuffled rows: order comes from the index column
    conv2 = cv.convergence_table(tab.sample(frac=1.0, random_state=0), partitions=[100, 300])
    pd.testing.assert_frame_equal(conv, conv2)
    with pytest.raises(ValueError):
        cv.convergence_table(tab.assign(sweep=["lds", "lattice"] * 150))


def test_group_mode_for_lattices():
    rows = []
    for k in (2, 3, 4):
        axis = np.linspace(0, 1, k)
        g = np.stack(np.meshgrid(*([axis] * 4), indexing="ij"), -1).reshape(-1, 4)
        y = 0.3 + 0.1 * g.sum(axis=1)
        rows.append(pd.DataFrame({"k": k, "index": np.arange(len(y)), "mfr": y, "pd": y}))
    tab = pd.concat(rows[::-1], ignore_index=True)  # order of rows does not matter
    conv = cv.convergence_table(tab, partition_col="k")
    assert list(conv["partition"]) == [16, 81, 256]
    assert list(conv["group"]) == [2, 3, 4]
    # symmetric lattices of a linear function: the mean is exactly 0.5 every time
    assert conv["mfr_mean"].to_numpy() == pytest.approx([0.5] * 3)


# ---------------------------------------------------------------------------------------------
# case-by-case
# ---------------------------------------------------------------------------------------------
def test_running_statistics_equal_per_n_recomputation():
    rng = np.random.default_rng(5)
    y = np.column_stack([rng.gamma(3.0, 0.1, 2000), rng.beta(5, 3, 2000) * 0.74])
    run = cv.running_statistics(y, start=3)
    assert list(run.index) == list(range(3, 2001))
    assert list(run.columns) == [f"{t}_{s}" for t in ("mfr", "pd") for s in cv.STATISTICS]
    for n in list(range(3, 40)) + list(range(40, 2001, 97)) + [2000]:
        for j, t in enumerate(("mfr", "pd")):
            ref = cv.partition_statistics(y[:n, j])
            for s in cv.STATISTICS:
                assert run.loc[n, f"{t}_{s}"] == pytest.approx(ref[s], rel=1e-9, abs=1e-12), (n, t, s)
    with pytest.raises(ValueError):
        cv.running_statistics(np.array([0.1, np.nan, 0.3]))


def test_first_stable_n_on_constructed_frame():
    n = np.arange(10, 41)
    r = np.full(n.size, 0.1)  # intended relative change of the mean at each n
    r[n == 13] = 0.001  # holds once...
    r[n >= 20] = 0.001  # ...and for good from 20
    mean = np.cumprod(1.0 + np.where(n == 10, 0.0, r))
    skew = 0.001 * (-1.0) ** n  # hovers around 0: absolute steps of 0.002 < 0.005 * floor
    frame = pd.DataFrame({"y_mean": mean, "y_skewness": skew}, index=pd.Index(n, name="n"))
    res = cv.first_stable_n(frame, TOL)
    assert res["first_holds"] == 13
    assert res["stable_from"] == 20
    assert res["checks_in_final_run"] == 21 and res["n_last"] == 40
    assert cv.first_stable_n(frame, TOL, window=21)["stable_from"] == 20
    assert cv.first_stable_n(frame, TOL, window=22)["stable_from"] is None
    naive = cv.first_stable_n(frame, TOL, floors={"skewness": 0.0})
    assert naive["first_holds"] is None and naive["stable_from"] is None
    # the same frame given with a partition column instead of an index
    res2 = cv.first_stable_n(frame.reset_index().rename(columns={"n": "partition"}), TOL)
    assert res2["stable_from"] == 20


def test_first_stable_n_agrees_with_brute_force_on_real_data():
    from scipy.stats import qmc
    n_run = 600
    u = qmc.Halton(d=1, scramble=True, seed=2).random(n_run)[:, 0]
    y = 0.3 + 0.1 * u  # a uniform output; stability is reached around n = 400 here
    run = cv.running_statistics(y, start=10)
    res = cv.first_stable_n(run, TOL)
    n0 = res["stable_from"]
    assert n0 is not None and 10 < n0 < n_run
    per_n = {n: cv.partition_statistics(y[:n]) for n in range(10, n_run + 1)}

    def holds(n):
        ch = _changes(per_n[n - 1], per_n[n])
        return all(v["change"] < TOL for v in ch.values())

    assert not holds(n0 - 1)
    assert all(holds(n) for n in range(n0, n_run + 1))
    assert res["first_holds"] == next(n for n in range(11, n_run + 1) if holds(n))


# ---------------------------------------------------------------------------------------------
# stop rule
# ---------------------------------------------------------------------------------------------
def test_batches_stop_early_when_converged():
    block = np.random.default_rng(4).normal(0.5, 0.05, 200)
    calls = []

    def evaluate(n):
        calls.append(n)
        return np.column_stack([np.resize(block, n), np.resize(block[::-1], n)])

    res = cv.batches_until_converged(evaluate, batch_size=200, k_consecutive=3, budget=5000)
    # n = 200, 400, 600, 800: prefixes of whole blocks share their statistics, the criterion holds
    # at 400, 600 and 800 -> three in a row at 800
    assert res["reason"] == "converged"
    assert res["stopped_at"] == 800 and res["converged_n"] == 400
    assert calls == [200, 400, 600, 800]
    assert [h["streak"] for h in res["history"]] == [0, 1, 2, 3]
    json.dumps(res)  # JSON-friendly


def test_batches_stop_at_budget_when_never_converging():
    res = cv.batches_until_converged(lambda n: np.arange(1.0, n + 1.0), batch_size=100,
                                     k_consecutive=2, budget=950, start=100)
    assert res["reason"] == "budget"
    assert res["stopped_at"] == 950 and res["converged_n"] is None
    assert [h["n"] for h in res["history"]] == list(range(100, 1000, 100)) + [950]
    assert not any(h["holds"] for h in res["history"])
    out = cv.summary({"lds": res})
    assert out["sweeps"]["lds"]["status"] == cv.NOT_CONVERGED


def test_summary_ratio_and_json():
    out = cv.summary({"lds": (1000, 2000), "lattice": (10000, 10000)})
    json.dumps(out)
    assert out["ratio_lattice_to_lds"]["kind"] == "ratio"
    assert out["ratio_lattice_to_lds"]["value"] == pytest.approx(10.0)
    out = cv.summary({"lds": (1000, 2000), "lattice": (None, 6561)})
    assert out["sweeps"]["lattice"]["status"] == "not converged within the cases run"
    assert out["ratio_lattice_to_lds"] == {
        "value": pytest.approx(6.561), "kind": "lower bound",
        "text": out["ratio_lattice_to_lds"]["text"]}
    out = cv.summary({"lds": {"stable_from": None, "n_last": 500}, "lattice": (81, 81)})
    assert out["ratio_lattice_to_lds"]["kind"] == "undefined"
    assert out["ratio_lattice_to_lds"]["value"] is None
    json.dumps(out)


# ---------------------------------------------------------------------------------------------
# figures
# ---------------------------------------------------------------------------------------------
def _sweeps():
    from scipy.stats import qmc
    u = qmc.Halton(d=4, scramble=True, seed=0).random(400)
    lds = pd.DataFrame({"index": np.arange(400), "sweep": "lds",
                        "mfr": 0.2 + 0.3 * u[:, 0] * u[:, 1], "pd": 0.5 + 0.1 * u[:, 2],
                        "status": "ok", "flagged": False})
    lat_rows = []
    for k in (2, 3, 4):
        axis = np.linspace(0, 1, k)
        g = np.stack(np.meshgrid(*([axis] * 4), indexing="ij"), -1).reshape(-1, 4)
        lat_rows.append(pd.DataFrame({"k": k, "index": np.arange(len(g)), "sweep": "lattice",
                                      "mfr": 0.2 + 0.3 * g[:, 0] * g[:, 1],
                                      "pd": 0.5 + 0.1 * g[:, 2], "status": "ok",
                                      "flagged": False}))
    return lds, pd.concat(lat_rows, ignore_index=True)


def test_plots_write_png_pdf_csv(tmp_path):
    from spreadmap.study_rule import rule_plots as cp
    lds, lat = _sweeps()
    long_df = pd.concat([cp.partition_values(lds, "lds", partitions=[50, 100, 200, 400]),
                         cp.partition_values(lat, "lattice", partition_col="k")],
                        ignore_index=True)
    assert set(long_df.loc[long_df["sweep"] == "lattice", "partition"]) == {16, 81, 256}
    floor = floor_label({"scene": {"substrate": {"kind": "rough", "jitter": 0.5}}})
    written = [cp.plot_distributions(long_df, tmp_path / "dist", floor=floor)]
    conv = {"lds": cv.convergence_table(lds, partitions=[50, 100, 200, 400]),
            "lattice": cv.convergence_table(lat, partition_col="k")}
    written.append(cp.plot_statistics(conv, tmp_path / "sub" / "stats"))
    run = cv.running_statistics(lds[["mfr", "pd"]].to_numpy(), start=10)
    written.append(cp.plot_statistics({"lds case by case": run, "lattice": conv["lattice"]},
                                      tmp_path / "stats_running"))
    for paths in written:
        for ext in ("png", "pdf", "csv"):
            assert paths[ext].exists() and paths[ext].stat().st_size > 0, paths[ext]
    assert "(previous layer, jitter 0.5 R)" in pdf_text(written[0]["pdf"])  # given its floor, a figure names it
    assert set(pd.read_csv(written[0]["csv"])["floor"]) == {floor} and "floor" not in pd.read_csv(written[1]["csv"])
    stats_csv = pd.read_csv(tmp_path / "sub" / "stats.csv")
    assert {"sweep", "n", "target", "statistic", "value", "band_low", "band_high"} <= set(
        stats_csv.columns)
    final = stats_csv[(stats_csv["sweep"] == "lds") & (stats_csv["target"] == "mfr")
                      & (stats_csv["statistic"] == "mean")]
    assert final["band_high"].iloc[0] - final["band_low"].iloc[0] == pytest.approx(
        2 * TOL * conv["lds"]["mfr_mean"].iloc[-1])


def test_statistic_panels_are_scaled_to_the_partitions_not_the_first_few_cases():
    """A case-by-case curve's first cases swing widely; the y range covers the partitions, the bands
    and the case-by-case values from the smallest partition on, and nothing before it."""
    from spreadmap.study_rule import rule_plots as cp
    panel = pd.DataFrame({"n": [2, 3, 16, 50, 16, 81], "value": [5.0, -4.0, 0.44, 0.45, 0.43, 0.46],
                          "band_low": 0.447, "band_high": 0.453})
    low, high = cp.statistic_limits(panel, n_from=16, pad=0.1)
    assert (low, high) == pytest.approx((0.43 - 0.003, 0.46 + 0.003))
    assert cp._scaled_from({"run": pd.DataFrame({"x": [1.0]}, index=[2]),
                            "lattice": pd.DataFrame({"partition": [81, 256]}),
                            "lds": pd.DataFrame({"partition": [16, 32]})}) == 16
    assert cp._scaled_from({"run": pd.DataFrame({"x": [1.0]}, index=[2])}) == 1
    assert cp.statistic_limits(panel.assign(value=np.nan, band_low=np.nan, band_high=np.nan), 16) is None
