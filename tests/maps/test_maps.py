"""Maps (spreadmap.maps) drawn from a real GP surrogate of synthetic cases with a known truth."""
import numpy as np
import pandas as pd
import pytest
import synthetic_cases as syn
from figure_text import pdf_text
from scipy.stats import norm

from spreadmap import maps
from spreadmap.case.substrate import floor_label
from spreadmap.design import NAMES, bounds
from spreadmap.maps import grids, machine, powder_maps, regimes
from spreadmap.surrogate.models import GPModel
from spreadmap.surrogate.saved_model import SurrogateModel
from spreadmap.table import usable_cases

LOW, HIGH = bounds()
SUPPORT = {"max_distance": 1.5, "max_sd_ratio": 1.0}
ROUGH = floor_label({"scene": {"substrate": {"kind": "rough", "jitter": 0.5}}})


def surrogate(table) -> SurrogateModel:
    X = table[list(NAMES)].to_numpy(float)
    models = {t: GPModel().fit(X, table[t].to_numpy(float), table[f"{t}_sd"].to_numpy(float)) for t in ("mfr", "pd")}
    return SurrogateModel(("mfr", "pd"), models, X, LOW, HIGH)


@pytest.fixture(scope="module")
def cases():
    return syn.table(64, 0.07, seed=3)


@pytest.fixture(scope="module")
def model(cases):
    return surrogate(cases)


@pytest.fixture(scope="module")
def half_model():
    """Trained only on small particles (d <= 25 um): the large-d half of every map is beyond the data."""
    pts = syn.halton_points(256)
    return surrogate(syn.table(points=pts[pts[:, 1] <= 25][:64], rel=0.07))


class ClosedForm:
    """A stand-in surrogate in closed form: each target's mean a known function (syn.TRUTH for MFR
    and PD; coverage and layer thickness / h follow MFR), its model SD growing with friction, a
    constant noise SD, the distance to the data |d - 20 um| / 10 um case spacings, and each draw
    the mean plus the model SD times one standard normal shared by every point of the draw."""

    targets = ("mfr", "pd", "coverage", "thickness_ratio")
    NOISE = {"mfr": 0.015, "pd": 0.01, "coverage": 0.04, "thickness_ratio": 0.05}
    correction = None

    def mean(self, X, t):
        X = np.asarray(X, float)
        if t in syn.TRUTH:
            return syn.TRUTH[t](X)
        return 0.3 + 1.2 * syn.truth_mfr(X) if t == "coverage" else 0.2 + 2.0 * syn.truth_mfr(X)

    def model_sd(self, X, t):
        return (0.004 + 0.05 * (np.asarray(X, float)[:, 0] - 0.15)) * self.NOISE[t] / 0.015

    def predict_stats(self, X):
        return {t: (self.mean(X, t), self.model_sd(X, t), np.hypot(self.model_sd(X, t), self.NOISE[t]))
                for t in self.targets}

    def data_distance(self, X):
        return np.abs(np.asarray(X, float)[:, 1] - 20.0) / 10.0

    def draws(self, X, n, seed=0, targets=None):
        z = np.random.default_rng(seed).standard_normal((n, 1))
        return {t: self.mean(X, t)[None, :] + self.model_sd(X, t)[None, :] * z for t in (targets or self.targets)}


def files_ok(res):
    for p in res.paths.values():
        assert p.stat().st_size > 0, p
    return pd.read_csv(res.paths["csv"])


def names_the_floor(paths, floor=ROUGH):
    """The figure (its PDF) says which floor and which gap, and so does every row of its CSV."""
    shown = pdf_text(paths["pdf"])
    assert "(previous layer, jitter 0.5 R); gap h nominal, from its tops" in shown, shown[-400:]
    assert set(pd.read_csv(paths["csv"])["floor"]) == {floor}


def test_every_map_names_its_floor(model, cases, tmp_path):
    """The maps drawn for the rough floor say so above their titles and in their CSVs; without a
    floor (a caller that does not know it) a map says nothing of one."""
    drawn = [maps.machine_map(model, tmp_path / "machine", n_h=3, n_v=3, support=SUPPORT, floor=ROUGH),
             maps.powder_band_map(model, tmp_path / "band", n_d=5, n_f=2, draws=20, support=SUPPORT, floor=ROUGH),
             maps.powder_cluster_map(model, tmp_path / "cluster", n_d=3, n_f=3, support=SUPPORT, floor=ROUGH),
             maps.parallel_coordinates(cases, tmp_path / "pc", floor=ROUGH)]
    for res in drawn:
        names_the_floor(res.paths)
    plain = maps.machine_map(model, tmp_path / "plain", n_h=3, n_v=3, support=SUPPORT)
    assert "floor" not in files_ok(plain).columns and "previous layer" not in pdf_text(plain.paths["pdf"])


def test_region_beyond_the_data_is_masked(half_model, tmp_path):
    res = maps.powder_band_map(half_model, tmp_path / "band", h_um=65, v_mm_s=10, n_d=21, n_f=3, support=SUPPORT)
    csv = files_ok(res)
    far = csv["d_um"] >= 35  # more than 10 um (a quarter of the range) beyond the last case
    assert not csv.loc[far, "supported"].any()
    assert csv.loc[csv["d_um"] <= 20, "supported"].mean() > 0.8
    assert "BEYOND THE DATA" in res.info["note"]
    # a map wholly beyond the data says so in its title (the machine map's d = 45 um)
    m = maps.machine_map(half_model, tmp_path / "machine", d_um=45, n_h=3, n_v=3, support=SUPPORT)
    assert m.info["n_unsupported"] == 9 and m.info["note"].startswith("9 of 9")
    assert m.info["title"].startswith("BEYOND THE DATA")


def test_support_is_distance_to_data_not_the_bounding_box():
    """Cases in two opposite corners: the centre of their bounding box is far from both."""
    rng = np.random.default_rng(0)
    u = np.vstack([rng.random((30, 4)) * 0.25, 0.75 + rng.random((30, 4)) * 0.25])
    m = surrogate(syn.table(points=LOW + u * (HIGH - LOW), rel=0.03))
    centre = pd.DataFrame([(LOW + HIGH) / 2], columns=list(NAMES))
    corner = pd.DataFrame([LOW + 0.12 * (HIGH - LOW)], columns=list(NAMES))
    assert not grids.evaluate(m, centre, ["mfr"], SUPPORT)["supported"].item()
    assert grids.evaluate(m, corner, ["mfr"], SUPPORT)["supported"].item()


def test_machine_map_follows_the_truth_within_its_uncertainty(model, tmp_path):
    res = maps.machine_map(model, tmp_path / "m", f=0.3, d_um=20.0, n_h=4, n_v=3, support=SUPPORT)
    csv = files_ok(res)
    assert len(csv) == 12 and len(csv[["h_um", "v_mm_s"]].drop_duplicates()) == 12
    X = csv[list(NAMES)].to_numpy()
    for t in ("mfr", "pd"):
        z = (csv[t] - syn.TRUTH[t](X)) / csv[f"{t}_model_sd"]
        assert np.mean(np.abs(z) < 3) >= 0.9, z.round(2).tolist()
        assert (csv[f"{t}_run_sd"] > csv[f"{t}_model_sd"]).all()


def test_powder_maps_resolve_the_friction_effect(model, tmp_path):
    """The truth lowers MFR by 15 % of its value from f = 0.15 to 0.45: the map's interval excludes 0
    where the data are dense, and holds the true change."""
    res = maps.powder_band_map(model, tmp_path / "band", h_um=65, v_mm_s=10, n_d=9, n_f=3, support=SUPPORT)
    eff = res.info["effect"]
    X0 = np.column_stack([np.full(9, 0.15), eff["d_um"], np.full(9, 65.0), np.full(9, 10.0)])
    X1 = X0.copy()
    X1[:, 0] = 0.45
    true = syn.truth_mfr(X1) - syn.truth_mfr(X0)
    inside = (eff["mfr_change_low"] <= true) & (true <= eff["mfr_change_high"])
    assert inside.mean() >= 0.75
    assert (eff["mfr_change_high"] < 0).sum() >= 3
    clusters = maps.powder_cluster_map(model, tmp_path / "clusters", h_um=60, v_mm_s=10, d_values=[15, 30, 45], n_f=4)
    assert len(files_ok(clusters)) == 12


RULES = {"jam_mfr_max": 0.05, "short_feed_coverage_min": 0.5, "short_feed_thickness_min": 0.25}


def test_regime_probability_is_the_predictive_normal():
    frame = pd.DataFrame({"mfr": [0.05, 0.30, 0.30, 0.30], "mfr_run_sd": [0.02] * 4,
                          "coverage": [0.9, 0.5, 0.9, 0.9], "coverage_run_sd": [0.05] * 4,
                          "thickness_ratio": [0.6, 0.6, 0.6, 0.25], "thickness_ratio_run_sd": [0.05] * 4})
    p = grids.regime_probabilities(frame, RULES)
    assert p["p_jamming"].tolist() == pytest.approx([0.5, norm.cdf(-12.5), norm.cdf(-12.5), norm.cdf(-12.5)])
    ok_cov, ok_thick = 1 - norm.cdf(-8.0), 1 - norm.cdf(-7.0)   # (0.5 - 0.9) / 0.05, (0.25 - 0.6) / 0.05
    assert p["p_short_feed"].iloc[1] == pytest.approx(1 - 0.5 * ok_thick, rel=1e-9)  # coverage at its threshold
    assert p["p_short_feed"].iloc[3] == pytest.approx(1 - 0.5 * ok_cov, rel=1e-6)
    assert p["p_normal"].iloc[2] == pytest.approx(ok_cov * ok_thick, rel=1e-9)
    np.testing.assert_allclose(p[["p_normal", "p_jamming", "p_short_feed"]].sum(axis=1), 1.0)


def test_regime_overlay_counts_planted_regimes(tmp_path):
    """Regimes planted by hand on the cases (the 5 lowest MFR jam; of the others, the 7 with the
    least coverage are short feed): the DEM counts are the planted ones, and a surrogate of the
    three targets the rule reads puts nearly every case in its planted regime."""
    df = syn.table(60, 0.03, seed=4)
    rng = np.random.default_rng(5)
    df["coverage"] = np.clip(1.6 * df["pd"], 0, 1) + rng.normal(0, 0.01, len(df))
    df["coverage_sd"] = 0.01
    df["thickness_ratio"], df["thickness_ratio_sd"] = 0.6 + rng.normal(0, 0.01, len(df)), 0.01
    df["regime"] = "normal"
    jammed = df["mfr"].nsmallest(5).index
    df.loc[jammed, "regime"] = "jamming"
    thin = df.drop(jammed)["coverage"].nsmallest(8).index
    df.loc[thin[:7], "regime"] = "short_feed"
    df.loc[0, ["regime", "status"]] = ["", "failed"]
    rules = {"jam_mfr_max": float(df["mfr"].nsmallest(6).iloc[4:6].mean()),
             "short_feed_coverage_min": float(df.loc[thin[6:8], "coverage"].mean()), "short_feed_thickness_min": 0.2}
    ok = df[df["status"] == "ok"]
    X = ok[list(NAMES)].to_numpy(float)
    targets = ("mfr", "coverage", "thickness_ratio")
    models = {t: GPModel().fit(X, ok[t].to_numpy(float), ok[f"{t}_sd"].to_numpy(float)) for t in targets}
    m = SurrogateModel(targets, models, X, LOW, HIGH)
    res = maps.regime_overlay(df, m, tmp_path / "reg", rules, n_d=12, n_h=8, support=SUPPORT, floor=ROUGH)
    counts = res.info["counts"]
    planted = ok["regime"].value_counts()
    assert counts["dem"].to_dict() == {r: int(planted.get(r, 0)) for r in maps.REGIMES}
    assert res.info["excluded"] == 1
    assert counts["both"].sum() >= 0.85 * counts["dem"].sum()
    files_ok(res)
    names_the_floor(res.paths)
    assert res.info["x"] == "h_over_d" and res.info["coarse_ratio"] is None  # one size: by h/d


def test_regime_overlay_places_a_size_distribution_by_h_over_d90(tmp_path):
    """Cases of a size distribution (size_span > 0) are placed by h/D90 of their feed, and the
    figure's CSV carries it; D90 / D50 is the median of the feeds' (1.5 here, one case 1.9); a table
    whose size_span is 0 (spheres of one size, as the scene records them) stays on h/d."""
    df = syn.table(30, 0.03, seed=6)
    for t in ("coverage", "thickness_ratio"):
        df[t], df[f"{t}_sd"] = 0.9, 0.01
    df["regime"] = "normal"
    df["size_span"] = 1.0
    df["feed_d50_um"] = df["d_um"]
    df["feed_d90_um"] = 1.5 * df["d_um"]
    df.loc[3, "feed_d90_um"] = 1.9 * df.loc[3, "d_um"]
    df["h_over_d90"] = df["h_um"] / df["feed_d90_um"]
    ok = df[df["status"] == "ok"]
    X = ok[list(NAMES)].to_numpy(float)
    targets = ("mfr", "coverage", "thickness_ratio")
    m = SurrogateModel(targets, {t: GPModel().fit(X, ok[t].to_numpy(float), ok[f"{t}_sd"].to_numpy(float))
                                 for t in targets}, X, LOW, HIGH)
    res = maps.regime_overlay(df, m, tmp_path / "psd", RULES, n_d=6, n_h=4, support=SUPPORT, floor=ROUGH)
    assert res.info["x"] == "h_over_d90" and res.info["coarse_ratio"] == pytest.approx(1.5)
    written = pd.read_csv(res.paths["csv"])
    np.testing.assert_allclose(written["h_over_d90"], ok["h_um"].to_numpy() / ok["feed_d90_um"].to_numpy())
    one = df.assign(size_span=0.0, feed_d90_um=df["d_um"], h_over_d90=df["h_um"] / df["d_um"])
    res1 = maps.regime_overlay(one, m, tmp_path / "one", RULES, n_d=6, n_h=4, support=SUPPORT, floor=ROUGH)
    assert res1.info["x"] == "h_over_d" and res1.info["coarse_ratio"] is None
    assert regimes.coarse_ratio(df.drop(columns=["feed_d90_um"])) is None


def test_regime_overlay_needs_the_targets_of_the_rule(model, cases, tmp_path):
    with pytest.raises(ValueError, match="coverage"):
        maps.regime_overlay(cases, model, tmp_path / "reg", RULES, support=SUPPORT)


def test_machine_y_is_the_layer_measure_with_most_beyond_mfr():
    rng = np.random.default_rng(1)
    df = syn.table(40, 0.07)
    df["layer_fill"] = 0.9 * df["mfr"] + rng.normal(0, 0.005, 40)      # MFR again
    df["coverage"] = rng.uniform(0.6, 1.0, 40)                             # something else
    y, scores = maps.choose_machine_y(df, ["mfr", "pd", "layer_fill", "coverage"])
    assert y == "coverage" and list(scores["target"]) == ["layer_fill", "coverage", "pd"]
    # the reported correlation with MFR is scipy's Pearson r, recomputed here with numpy
    r = scores.set_index("target")["r_with_mfr"]
    assert r["layer_fill"] == pytest.approx(np.corrcoef(df["mfr"], df["layer_fill"])[0, 1], abs=1e-12)
    assert r["layer_fill"] > 0.9 and abs(r["coverage"]) < 0.4
    low, high = scores.set_index("target").loc["coverage", ["r_low", "r_high"]]
    assert low < r["coverage"] < high
    assert maps.choose_machine_y(df, ["mfr", "pd"])[0] == "pd"


def test_parallel_coordinates_marks_best(cases, tmp_path):
    c = cases.copy()
    c.loc[3, ["mfr", "pd"]] = [0.05, 0.73]          # densest, but it hardly flows
    c.loc[7, ["mfr", "pd", "flagged"]] = [0.6, 0.74, True]  # denser still, but flagged
    c.loc[11, ["mfr", "pd"]] = [0.45, 0.72]
    c.loc[12, ["status", "mfr", "pd"]] = ["failed", np.nan, np.nan]
    res = maps.parallel_coordinates(c, tmp_path / "pc", mfr_min=0.3)
    csv = files_ok(res)
    assert res.info["best"]["case_id"] == "lds-00011"
    assert len(csv) == len(c) - 2 and csv["best"].sum() == 1
    assert maps.best_case(usable_cases(c, ["mfr", "pd"]))["case_id"] == "lds-00003"


def test_the_noise_cross_goes_to_the_corner_the_map_leaves_empty():
    """A band from the upper left to the lower right (the study's machine map) leaves the lower
    left free; its mirror leaves the upper left free."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from spreadmap.maps.machine import emptiest_corner

    fig, ax = plt.subplots()
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    t = np.linspace(0.05, 0.95, 40)
    assert emptiest_corner(ax, t, 1 - t) == (0.08, 0.1)
    assert emptiest_corner(ax, t, t) == (0.08, 0.9)
    assert emptiest_corner(ax, np.full(40, 0.1), t) == (0.5, 0.9)  # a column at the left edge: the right side
    plt.close(fig)


def test_powder_band_numbers_are_the_closed_form():
    """powder_band_grid's table on a closed-form model, against the same numbers computed here: the
    (f, d) grid with f varying slowest, each target's mean, model SD, noise SD and their ratio, the
    support (distance <= 1.5 and model SD <= noise SD for MFR and PD), and per d the change from the
    lowest to the highest f, whose joint draws differ by (change of the model SD) x z: a 95 %
    interval change + (sd_high - sd_low) x (-1.96, 1.96) and P(increase) Phi(change / |sd change|)."""
    cf = ClosedForm()
    d, fv = np.array([12.0, 20.0, 31.0, 44.0]), np.array([0.15, 0.25, 0.45])
    table = powder_maps.powder_band_grid(cf, "pd", h_um=65, v_mm_s=10, d_values=d, f_values=fv, support=SUPPORT,
                                    draws=20000)
    assert table[["f", "d_um"]].to_numpy().tolist() == [[f, x] for f in fv for x in d]
    assert (table["h_um"] == 65).all() and (table["v_mm_s"] == 10).all()
    X = table[list(NAMES)].to_numpy()
    ok = np.abs(X[:, 1] - 20) / 10 <= 1.5
    for t in ("mfr", "pd"):
        msd = (0.004 + 0.05 * (X[:, 0] - 0.15)) * cf.NOISE[t] / 0.015
        np.testing.assert_allclose(table[t], syn.TRUTH[t](X), rtol=1e-12)
        np.testing.assert_allclose(table[f"{t}_model_sd"], msd, rtol=1e-12)
        np.testing.assert_allclose(table[f"{t}_noise_sd"], cf.NOISE[t], rtol=1e-9)
        np.testing.assert_allclose(table[f"{t}_sd_ratio"], msd / cf.NOISE[t], rtol=1e-9)
        ok &= msd <= cf.NOISE[t]
    assert table["supported"].tolist() == ok.tolist()
    assert 0 < ok.sum() < len(ok)  # the check sees both sides: far in d, and a model SD above the noise at f = 0.45
    for t in ("mfr", "pd"):
        low, high = (np.column_stack([np.full(4, f), d, np.full(4, 65.0), np.full(4, 10.0)]) for f in (0.15, 0.45))
        change = syn.TRUTH[t](high) - syn.TRUTH[t](low)
        sd_change = 0.05 * 0.30 * cf.NOISE[t] / 0.015
        per_d = table.groupby("d_um").first()  # every f of a d carries its d's change
        np.testing.assert_allclose(per_d[f"{t}_change"], change, rtol=1e-12)
        np.testing.assert_allclose(per_d[f"{t}_change_low"], change - 1.96 * sd_change, atol=0.05 * sd_change)
        np.testing.assert_allclose(per_d[f"{t}_change_high"], change + 1.96 * sd_change, atol=0.05 * sd_change)
        np.testing.assert_allclose(per_d[f"{t}_p_increase"], norm.cdf(change / sd_change), atol=0.01)


def test_powder_cluster_numbers_are_the_closed_form():
    cf = ClosedForm()
    grid = powder_maps.powder_cluster_grid(cf, "coverage", h_um=60, v_mm_s=8, d_values=[15, 45], f_values=[0.2, 0.3, 0.4],
                                      support=SUPPORT)
    X = grid[list(NAMES)].to_numpy()
    assert X.tolist() == [[f, d, 60.0, 8.0] for f in (0.2, 0.3, 0.4) for d in (15.0, 45.0)]
    np.testing.assert_allclose(grid["mfr"], syn.truth_mfr(X), rtol=1e-12)
    np.testing.assert_allclose(grid["coverage"], 0.3 + 1.2 * syn.truth_mfr(X), rtol=1e-12)
    np.testing.assert_allclose(grid["coverage_run_sd"], np.hypot(cf.model_sd(X, "coverage"), 0.04), rtol=1e-12)
    np.testing.assert_allclose(grid["data_distance"], np.abs(X[:, 1] - 20) / 10)
    assert "pd" not in grid  # the targets drawn: MFR and y


RULES_CF = {"jam_mfr_max": 0.15, "short_feed_coverage_min": 0.55, "short_feed_thickness_min": 0.6}


def test_machine_numbers_are_the_closed_form():
    """machine_grid on a closed-form model: the (h, v) grid at (f, d), h varying slowest, MFR and y
    the model's known functions, their run SDs the model SD and noise in quadrature, the support
    the distance to the data; the map drawn from it saves the same numbers."""
    cf = ClosedForm()
    grid = machine.machine_grid(cf, "thickness_ratio", f=0.25, d_um=35.0, h_values=[70, 60], n_v=3, support=SUPPORT)
    X = grid[list(NAMES)].to_numpy()
    assert X.tolist() == [[0.25, 35.0, h, v] for h in (60.0, 70.0) for v in (5.0, 10.0, 15.0)]
    np.testing.assert_allclose(grid["mfr"], syn.truth_mfr(X), rtol=1e-12)
    np.testing.assert_allclose(grid["thickness_ratio"], 0.2 + 2.0 * syn.truth_mfr(X), rtol=1e-12)
    np.testing.assert_allclose(grid["mfr_run_sd"], np.hypot(cf.model_sd(X, "mfr"), 0.015), rtol=1e-12)
    np.testing.assert_allclose(grid["data_distance"], 1.5)
    assert "pd" not in grid


def test_regime_numbers_are_the_closed_form():
    """regime_tables on a closed-form model: each regime's probability from the predictive normal of
    MFR, coverage and thickness / h (mean, run SD), computed here with scipy, at the cases' own
    settings (the case without a regime left out) and over the (d, h) plane, d varying slowest."""
    cf = ClosedForm()
    pts = syn.halton_points(9, seed=5)
    cases = pd.DataFrame(pts, columns=list(NAMES)).assign(case_id=[f"c{i}" for i in range(9)], mfr=0.3, pd=0.5,
                                                          regime=["normal", "jamming", "short_feed"] * 3)
    cases.loc[4, "regime"] = ""
    table, plane = regimes.regime_tables(cases, cf, RULES_CF, f=0.3, v_mm_s=10, n_d=7, n_h=5, support=SUPPORT)

    def probabilities(X):
        def below(t, threshold):
            return norm.cdf((threshold - cf.mean(X, t)) / np.hypot(cf.model_sd(X, t), cf.NOISE[t]))
        jam = below("mfr", 0.15)
        fine = (1 - below("coverage", 0.55)) * (1 - below("thickness_ratio", 0.6))
        return np.column_stack([(1 - jam) * fine, jam, (1 - jam) * (1 - fine)])

    assert list(table["case_id"]) == [f"c{i}" for i in range(9) if i != 4]
    X = table[list(NAMES)].to_numpy()
    P = probabilities(X)
    np.testing.assert_allclose(table[["p_normal", "p_jamming", "p_short_feed"]], P, rtol=1e-9, atol=1e-15)
    assert list(table["regime_pred"]) == [maps.REGIMES[k] for k in P.argmax(axis=1)]
    np.testing.assert_allclose(table["h_over_d"], X[:, 2] / X[:, 1])
    d, h = np.linspace(10, 50, 7), np.linspace(55, 75, 5)
    assert plane[["d_um", "h_um"]].to_numpy().tolist() == [[a, b] for a in d for b in h]
    Q = probabilities(plane[list(NAMES)].to_numpy())
    np.testing.assert_allclose(plane[["p_normal", "p_jamming", "p_short_feed"]], Q, rtol=1e-9, atol=1e-15)
    assert len(set(Q.argmax(axis=1))) == 3  # the plane holds every regime


def test_maps_redraw_from_their_csv(tmp_path):
    """Each map drawn again from its CSV (and the regime map's plane CSV) read back from disk is the
    same figure, saved with the same CSV, byte for byte."""
    cf = ClosedForm()
    first, again = tmp_path / "first", tmp_path / "again"
    band = maps.powder_band_map(cf, first / "band", h_um=65, v_mm_s=10, n_d=7, n_f=3, draws=50, support=SUPPORT,
                                floor=ROUGH)
    cluster = maps.powder_cluster_map(cf, first / "cluster", y="coverage", n_d=3, n_f=4, support=SUPPORT, floor=ROUGH)
    mach = maps.machine_map(cf, first / "machine", f=0.3, d_um=20, n_h=3, n_v=4, support=SUPPORT, floor=ROUGH)
    cases = pd.DataFrame(syn.halton_points(12, seed=2), columns=list(NAMES)).assign(
        mfr=0.3, pd=0.5, regime=["normal", "jamming", "short_feed", ""] * 3)
    reg = maps.regime_overlay(cases, cf, first / "regime", RULES_CF, n_d=9, n_h=6, support=SUPPORT, floor=ROUGH)
    assert reg.paths["plane"] == first / "regime_plane.csv"
    assert set(pd.read_csv(reg.paths["plane"])["floor"]) == {ROUGH}

    grid = pd.read_csv(mach.paths["csv"])
    redrawn = [(band, powder_maps.draw_powder_band_map(pd.read_csv(band.paths["csv"]), again / "band", "pd", SUPPORT, ROUGH)),
               (cluster, powder_maps.draw_powder_cluster_map(pd.read_csv(cluster.paths["csv"]), again / "cluster", "coverage",
                                                        SUPPORT, ROUGH)),
               (mach, machine.draw_machine_map(grid, again / "machine", "pd", SUPPORT, floor=ROUGH)),
               (reg, regimes.draw_regime_overlay(pd.read_csv(reg.paths["csv"]), pd.read_csv(reg.paths["plane"]),
                                                 again / "regime", 3, SUPPORT, ROUGH))]
    for old, new in redrawn:
        for ext in ("png", "csv"):
            assert new.paths[ext].read_bytes() == old.paths[ext].read_bytes(), old.paths[ext]
    assert redrawn[3][1].info["counts"].equals(reg.info["counts"]) and reg.info["excluded"] == 3
