"""The steady flag (stability.max_flow_trend_z): the flow's change between the window's halves in SEs
of its own within-window noise (spreadmap.metrics.noise.flow_trend_batch_z, the column
flow_trend_z_batch), on synthetic volume-behind series of known truth (no YADE): a steady Poisson
flow is flagged at the normal's rate, a falling and a rising flow are flagged with their reasons,
and the deprecated key max_flow_decline_z still works."""
import copy
import math
import warnings

import numpy as np
import pytest
import yaml
from conftest import ROOT
from scipy import stats

from spreadmap.config import validate
from spreadmap.metrics import batch_means_sd, case_metrics, flow_trend, flow_trend_batch_z
from spreadmap.metrics.case import MAX_FLOW_TREND_Z, flow_trend_bound
from spreadmap.metrics.noise import t_normal_score

D = 30e-6  # sphere diameter, m
BALL = math.pi / 6 * D ** 3
GAP, WIDTH = 2 * D, 4 * D
RULES = {"jam_mfr_max": 0.05, "short_feed_coverage_min": 0.5, "short_feed_thickness_min": 0.25}
SETTINGS = {"pd_clearance_d": 1.0, "pd_slices": 4, "counting_noise_c": 0.45, "within_batches": 8,
            "surface_grid_d": 0.01}
BOUNDS = {"max_overlap_ratio": 0.05, "max_escaped": 0, "min_heap_h2": 0.7}
NOMINAL = 2 * stats.norm.sf(3.0)  # a steady flow's share beyond +-3: 0.27 %


def poisson_series(rng, rate, x0=10.0, x1=20.0, step=0.5, offset=0.13, draws=1):
    """`draws` volume-behind series [time, x, volume] (x in d, volume in spheres) with a point every
    `step` of travel from x0 - 1 + offset to past x1, as the scene's monitor records them:
    spheres crossing as a Poisson process of `rate(x)` per d (a callable, or a number: steady),
    counted whole at each point. The offset puts the points off the batches' equal edges."""
    xs = np.arange(x0 - 1.0 + offset, x1 + step + 1e-9, step)
    mid = 0.5 * (xs[1:] + xs[:-1])
    mean = (rate(mid) if callable(rate) else np.full(len(mid), float(rate))) * np.diff(xs)
    counts = np.concatenate([np.zeros((draws, 1)), np.cumsum(rng.poisson(mean, size=(draws, len(mid))), axis=1)], axis=1)
    return [np.column_stack([xs, xs, c]) for c in counts]


def ramp(change, mean=1200.0):
    """A flow rising (change > 0) or falling linearly over the window 10-20 d, `mean` spheres per d:
    `change` x its mean from the window's start to its end (the halves' means differ by change / 2)."""
    return lambda x: mean * (1.0 + change * (x - 15.0) / 10.0)


# ------------------------------------------------------------------------ the statistic
def test_the_normal_score_of_a_t_against_closed_forms():
    """The normal score's tail equals the t's, by closed forms (not scipy's): P(T > t) is
    1/2 - atan(t)/pi at 1 dof (Cauchy) and (1 - t / sqrt(2 + t^2)) / 2 at 2 dof; the normal tail
    is erfc(z / sqrt 2) / 2. At many dof the score is t itself."""
    for t in (0.01, 0.7, 2.0, 3.0, 6.62, 12.0, 1e3):
        for dof, tail in ((1, 0.5 - math.atan(t) / math.pi), (2, 0.5 * (1.0 - t / math.sqrt(2.0 + t * t)))):
            z = t_normal_score(t, dof)
            assert 0.5 * math.erfc(z / math.sqrt(2.0)) == pytest.approx(tail, rel=1e-9)
            assert t_normal_score(-t, dof) == -z
        if t < 10:
            assert t_normal_score(t, 10**7) == pytest.approx(t, rel=1e-4)
    # the 3-sigma tail of t with 4 dof (8 batches) lies at t 6.62: a noise estimate of 4 dof is uncertain
    assert t_normal_score(6.62, 4) == pytest.approx(3.0, abs=0.01)
    assert t_normal_score(math.inf, 4) == math.inf and math.isnan(t_normal_score(math.nan, 4))


def test_the_plain_sd_of_the_batches_can_never_reach_3():
    """Why the SE is not 2 x mfr_sd_within: the batches' plain SD holds the trend itself, so
    flow_trend / (2 mfr_sd_within / mean) is at most sqrt(b - 1) = 2.65 with 8 batches, however
    large the fall (here a flow halved at the window's middle, 4,500 spheres); the batch z of the
    flag reads it (t 20 or so: z beyond 3.5; with 4 dof the score grows slowly with t)."""
    rng = np.random.default_rng(11)
    fell = poisson_series(rng, lambda x: np.where(x < 15.0, 600.0, 300.0), offset=0.0)[0]
    trend = flow_trend(fell, 10.0, 20.0, 1.0, 1.0)
    sd, b = batch_means_sd(fell, 10.0, 20.0, 1.0, 1.0, 8)
    mean = (fell[-1, 2] - fell[0, 2]) / (fell[-1, 1] - fell[0, 1])
    assert b == 8 and trend == pytest.approx(-2 / 3, abs=0.05)
    assert -math.sqrt(7) <= trend / (2 * sd / mean) < -2.6
    assert flow_trend_batch_z(fell, 10.0, 20.0, 8)[0] < -3.5


def test_a_steady_poisson_flow_reads_standard_normal():
    """2,000 steady windows (150 spheres each, the default preset's; 20 monitor intervals, off the
    batches' edges): the batch z has mean 0 and SD 1 (within 4 SE of each)."""
    rng = np.random.default_rng(7)
    z = np.array([flow_trend_batch_z(s, 10.0, 20.0, 8)[0] for s in poisson_series(rng, 15.0, draws=2000)])
    assert abs(z.mean()) < 4 / math.sqrt(len(z)) and abs(z.std() - 1.0) < 4 * 0.71 / math.sqrt(len(z))


@pytest.mark.slow
def test_a_steady_poisson_flow_is_flagged_at_the_nominal_rate():
    """20,000 steady windows (150 spheres each), points on and off the batches' edges: the share
    beyond +-3 has the normal's 0.27 % inside its 99 % binomial (Clopper-Pearson) interval, each
    side about half of it (~5 s)."""
    rng = np.random.default_rng(2029)
    z = np.array([flow_trend_batch_z(s, 10.0, 20.0, 8)[0]
                  for offset in (0.0, 0.13) for s in poisson_series(rng, 15.0, offset=offset, draws=10_000)])
    flagged = int(np.sum(np.abs(z) > 3.0))
    ci = stats.binomtest(flagged, len(z)).proportion_ci(0.99)
    assert ci.low < NOMINAL < ci.high, (flagged, len(z), ci)
    for side in (z > 3.0, z < -3.0):
        assert stats.binomtest(int(side.sum()), len(z), NOMINAL / 2).pvalue > 0.01


@pytest.mark.parametrize("change", [-0.6, 0.6])
def test_a_ramp_is_caught_where_the_halves_scatter_is_blind_to_it(change):
    """A flow falling or rising linearly by 60 % over the window (12,000 spheres: t ~ 16): over 100
    windows the batch z passes the bound in nearly all, with the ramp's sign. (The scatter about
    each half's own mean would hold the ramp within the halves: a noiseless ramp reads 2.8 there.
    With 3,000 spheres, t ~ 8, 80 % of them: docs/steady_window, the flag's power.)"""
    rng = np.random.default_rng(5)
    z = np.array([flow_trend_batch_z(s, 10.0, 20.0, 8)[0] for s in poisson_series(rng, ramp(change), draws=100)])
    assert np.mean(np.sign(change) * z > MAX_FLOW_TREND_Z) > 0.95


def test_too_few_monitor_points_give_no_z():
    """Fewer than 12 intervals in the window (6 batches of 2): NaN, and 6 batches where there are 12."""
    rng = np.random.default_rng(1)
    assert math.isnan(flow_trend_batch_z(poisson_series(rng, 15.0, step=1.0)[0], 10.0, 20.0, 8)[0])  # 10 intervals
    assert flow_trend_batch_z(poisson_series(rng, 15.0, step=10 / 12, offset=0.0)[0], 10.0, 20.0, 8)[1] == 6
    assert flow_trend_batch_z(poisson_series(rng, 15.0)[0], 10.0, 20.0, 8)[1] == 8
    assert math.isnan(flow_trend_batch_z(poisson_series(rng, 15.0)[0], 10.0, 30.0, 8)[0])  # the series ends first


# ------------------------------------------------------------------------ through case_metrics
def record(series, heap_end_spheres=36):
    """A blade at 10 d then 20 d (gap 2 d, bed 4 d wide) over a simple cubic monolayer, a block of
    whole spheres ahead of it (72 at the start, `heap_end_spheres` at the end: 36 is 1.21 h^2,
    12 is 0.41 h^2), and the volume-behind `series` (x in d, volume in spheres)."""
    layer = [(x + 0.5, y + 0.5, 0.5) for x in range(20) for y in range(4)]

    def heap(rear_d, n):
        return [(rear_d + 0.5 + i // 12, 0.5 + (i % 12) % 4, 0.5 + (i % 12) // 4) for i in range(n)]

    def snap(positions, rear_d):
        return {"positions": (np.array(positions) * D).tolist(), "radii": [0.5 * D] * len(positions),
                "blade_rear_x": rear_d * D, "removed_behind_volume": 0.0}

    params = {"case_id": "steady", "preset": "default", "point": {"f": 0.3, "d_um": 30.0, "h_um": 60.0, "v_mm_s": 10.0},
              "seed": 1, "diameter": D, "gap": GAP, "width": WIDTH, "blade_thickness": 2 * D, "time_step": 1e-7,
              "critical_time_step": 4e-7, "density_scale": 1000.0, "n_particles": 200}
    return {"status": "ok", "params": params, "peak_overlap_ratio": 0.01, "escaped_particles": 0,
            "behind_series": np.column_stack([series[:, 0] * D, series[:, 1] * D, series[:, 2] * BALL]).tolist(),
            "snapshots": {"window_start": snap([p for p in layer if p[0] < 10] + heap(10.0, 72), 10.0),
                          "window_end": snap(layer + heap(20.0, heap_end_spheres), 20.0)}}


@pytest.mark.parametrize("heap_end_spheres,cause", [
    (36, " with {:.2f} h^2 still ahead of the blade: the flow is unsteady, the pile did not run down"),
    (12, ": the pile ran down"),
])
def test_a_falling_flow_is_flagged_with_what_the_heap_tells(heap_end_spheres, cause):
    rng = np.random.default_rng(3)
    m = case_metrics(record(poisson_series(rng, ramp(-0.6))[0], heap_end_spheres), RULES, BOUNDS, SETTINGS)
    assert m["flow_trend_z_batch"] < -MAX_FLOW_TREND_Z and m["flow_trend"] == pytest.approx(-0.3, abs=0.06)
    first = m["flag_reason"].split("; ")[0]
    assert m["flagged"] and first == (f"flow fell by {-m['flow_trend']:.0%} over the window "
                                      f"({m['flow_trend_z_batch']:.1f} SE of its within-window noise)"
                                      + cause.format(m["heap_end_h2"]))
    assert "rising" not in m["flag_reason"]


def test_a_rising_flow_is_flagged_not_steady():
    """Before, a rising flow was never flagged."""
    rng = np.random.default_rng(3)
    m = case_metrics(record(poisson_series(rng, ramp(0.6))[0]), RULES, BOUNDS, SETTINGS)
    assert m["flow_trend_z_batch"] > MAX_FLOW_TREND_Z and m["flow_trend"] == pytest.approx(0.3, abs=0.06)
    assert m["flagged"] and m["flag_reason"] == (
        f"flow rose by {m['flow_trend']:.0%} over the window ({m['flow_trend_z_batch']:.1f} SE of its within-window "
        f"noise): the flow was still rising in the window: not steady")
    # the cause the summaries count (the text after the last ': ')
    assert m["flag_reason"].rsplit(": ", 1)[1] == "not steady"
    # a looser bound, and null: not flagged
    assert not case_metrics(record(poisson_series(rng, ramp(0.6))[0]), RULES,
                            {**BOUNDS, "max_flow_trend_z": 1e3}, SETTINGS)["flagged"]
    assert not case_metrics(record(poisson_series(rng, ramp(0.6))[0]), RULES,
                            {**BOUNDS, "max_flow_trend_z": None}, SETTINGS)["flagged"]


def test_a_steady_flow_is_not_flagged_and_keeps_its_counting_z():
    rng = np.random.default_rng(4)
    m = case_metrics(record(poisson_series(rng, 300.0)[0]), RULES, BOUNDS, SETTINGS)
    assert abs(m["flow_trend_z_batch"]) < MAX_FLOW_TREND_Z and not m["flagged"], m["flag_reason"]
    assert math.isfinite(m["flow_trend_z"])  # the counting-noise z is still reported beside it


# ------------------------------------------------------------------------ the config's key
def test_the_deprecated_key_is_read_as_the_new_one_which_takes_precedence():
    """stability.max_flow_decline_z (before): read as max_flow_trend_z with a warning naming both;
    given beside max_flow_trend_z, ignored with a warning (the new key wins); the shipped config
    says max_flow_trend_z; handed to case_metrics unvalidated, the old key still bounds the flag."""
    raw = yaml.safe_load((ROOT / "config.yaml").read_text())
    assert "max_flow_decline_z" not in raw["stability"] and raw["stability"]["max_flow_trend_z"] == 3.0
    old = copy.deepcopy(raw)
    del old["stability"]["max_flow_trend_z"]
    old["stability"]["max_flow_decline_z"] = 2.5
    with pytest.warns(FutureWarning, match=r"'stability\.max_flow_decline_z' is deprecated, read as "
                                           r"'stability\.max_flow_trend_z' = 2\.5 .*rename it"):
        cfg = validate(old)
    assert cfg["stability"]["max_flow_trend_z"] == 2.5 and "max_flow_decline_z" not in cfg["stability"]
    both = copy.deepcopy(raw)
    both["stability"].update(max_flow_trend_z=4.0, max_flow_decline_z=2.5)
    with pytest.warns(FutureWarning, match=r"'stability\.max_flow_decline_z' is deprecated and ignored: "
                                           r"'stability\.max_flow_trend_z' is given and takes precedence"):
        cfg = validate(both)
    assert cfg["stability"]["max_flow_trend_z"] == 4.0 and "max_flow_decline_z" not in cfg["stability"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert validate(copy.deepcopy(raw))["stability"]["max_flow_trend_z"] == 3.0  # no warning for the new key
        assert flow_trend_bound({}) == MAX_FLOW_TREND_Z == 3.0
    with pytest.warns(FutureWarning):
        assert flow_trend_bound({"max_flow_decline_z": None}) is None
    rng = np.random.default_rng(3)
    with pytest.warns(FutureWarning):
        off = case_metrics(record(poisson_series(rng, ramp(-0.6))[0]), RULES, {**BOUNDS, "max_flow_decline_z": None}, SETTINGS)
    assert off["flow_trend_z_batch"] < -3 and not off["flagged"]
