"""spreadlab.window_start on raw records of known flow: a steady flow reads 1 in every bin and
the same MFR in every later window; a flow that settles reads below 1 before it settles and the later
window reads the settled flow; a Poisson flow's trend z is standard normal."""
import math

import numpy as np
import pytest

from spreadlab import window_start as ws

D, GAP, WIDTH, PILE = 20e-6, 50e-6, 200e-6, 400e-6


def _raw(flow_of_travel, transient_d=3.0, window_d=8.0, step_d=0.05, noise=None):
    """A raw record whose volume-behind series passes flow_of_travel(s) [m^3/m] at s d beyond the pile."""
    s = np.arange(-2.0, transient_d + window_d + 1e-9, step_d)
    flows = np.array([flow_of_travel(si) for si in s])
    vol = np.concatenate([[0.0], np.cumsum(flows[1:] * step_d * D)])
    if noise is not None:
        vol = vol + noise(len(vol))
    x = PILE + s * D
    return {"behind_series": [[0.0, xi, vi] for xi, vi in zip(x, vol)],
            "geometry": {"pile_length": PILE, "gap": GAP, "width": WIDTH},
            "params": {"diameter": D},
            "window": {"x_start": PILE + transient_d * D, "x_end": PILE + (transient_d + window_d) * D}}


def test_a_steady_flow_reads_one_everywhere_and_its_mfr_in_every_window():
    q = 0.6 * GAP * WIDTH  # MFR 0.6
    raw = _raw(lambda s: q)
    prof = ws.flow_profile(raw, np.arange(0, 13, 1.0))
    assert prof[:11] == pytest.approx(np.ones(11), rel=1e-9)
    assert math.isnan(prof[11])  # 11-12 d: beyond the series' end
    for o in (3, 4, 5, 6):
        w = ws.later_window(raw, o)
        assert w["mfr_series"] == pytest.approx(0.6, rel=1e-9) and w["length_d"] == pytest.approx(11 - o)


def test_a_settling_flow_reads_low_before_it_settles_and_the_later_window_the_settled_flow():
    q = 0.5 * GAP * WIDTH
    raw = _raw(lambda s: q * (0.8 + 0.2 * min(s, 5.0) / 5.0))  # rises by 25 % until 5 d, then steady
    prof = ws.flow_profile(raw, np.arange(0, 11.01, 1.0))
    window_mean = (0.5 * (0.92 + 1.0) * 2 + 6 * 1.0) / 8  # 3-5 d: a ramp 0.92-1.0, then 1 (in q)
    assert prof[3] == pytest.approx((0.92 + 0.96) / 2 / window_mean, rel=1e-3)
    assert prof[8] == pytest.approx(1.0 / window_mean, rel=1e-3)
    assert ws.later_window(raw, 5)["mfr_series"] == pytest.approx(0.5, rel=1e-9)
    # (the series' flow holds over the interval before each point: the ramp ends 1/40 d late)
    assert ws.later_window(raw, 3)["mfr_series"] == pytest.approx(0.5 * window_mean, rel=1e-3)
    # a window shorter than 2 d is not read
    assert math.isnan(ws.later_window(raw, 9.5)["mfr_series"])


def test_the_trend_z_of_a_poisson_flow_is_standard_normal_and_a_rise_reads_positive():
    """Independent Poisson counts per series interval (the counting law), 300 cases: z has mean 0
    and SD 1 within their sampling error; the same counts with a 50 % step at the middle read z > 0
    in every case, > 2.5 on average (t with 4 dof: a noise estimate from 8 batches keeps z modest)."""
    rng = np.random.default_rng(4)
    sphere = math.pi * D ** 3 / 6
    per_interval = 4.0  # spheres passed per 0.05 d
    def poisson_flow(counts, step_share=0.0):
        # the flow over each 0.05 d interval of the series, a step of step_share at 7 d (the window's middle)
        return lambda s: (counts[min(int(round((s + 2.0) / 0.05)), len(counts) - 1)] * sphere / (0.05 * D)
                          * (1.0 + step_share * (s > 7.0)))

    zs, rising = [], []
    for _ in range(300):
        zs.append(ws.later_window(_raw(poisson_flow(rng.poisson(per_interval, 261))), 3)["trend_z"])
    zs = np.array(zs)
    assert abs(zs.mean()) < 3 * 1.1 / math.sqrt(300) and 0.85 < zs.std() < 1.15
    for _ in range(40):
        rising.append(ws.later_window(_raw(poisson_flow(rng.poisson(per_interval, 261), 0.5)), 3)["trend_z"])
    assert np.mean(rising) > 2.5 and min(rising) > 0


def test_the_window_profile_reads_a_ramp_within_the_window():
    """A flow rising linearly over the window by 20 % reads the ramp's means over its quarters."""
    q = 0.5 * GAP * WIDTH
    raw = _raw(lambda s: q * (1.0 + 0.2 * max(0.0, min(s - 3.0, 8.0)) / 8.0), step_d=0.01)
    prof = ws.window_profile(raw, 4)
    expected = np.array([1.025, 1.075, 1.125, 1.175]) / 1.1
    assert prof == pytest.approx(expected, rel=2e-3)
