"""The regime of a case from quantities that are not the counting noise of a few spheres:
MFR over the whole window, and the layer's coverage of the floor and mean thickness over the whole
measured layer (not PD's variation between short slices, which at large d counts ~5 spheres a
slice and labelled cases at random).

    jamming     MFR < jam_mfr_max                                (powder rides with the blade)
    short feed  coverage < short_feed_coverage_min
                or thickness_ratio < short_feed_thickness_min     (little or patchy deposit)
    normal      otherwise

One rule for DEM cases and for surrogate predictions: `classify` takes scalars or arrays.
"""
from __future__ import annotations

import numpy as np

REGIMES = ("normal", "jamming", "short_feed")
RULE_KEYS = ("jam_mfr_max", "short_feed_coverage_min", "short_feed_thickness_min")


def classify(mfr, coverage, thickness_ratio, rules: dict):
    """Regime label(s) of MFR, coverage and thickness_ratio (scalars or arrays broadcast together).
    Returns a str for scalar input, else an object array of str; "" where an input is NaN.
    rules: the config's `regime` mapping (keys RULE_KEYS; other keys are ignored)."""
    missing = [k for k in RULE_KEYS if k not in rules]
    if missing:
        raise KeyError(f"config section 'regime' lacks {missing} (needed: {list(RULE_KEYS)})")
    m, c, t = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (mfr, coverage, thickness_ratio)))
    label = np.select(
        [np.isnan(m) | np.isnan(c) | np.isnan(t),
         m < rules["jam_mfr_max"],
         (c < rules["short_feed_coverage_min"]) | (t < rules["short_feed_thickness_min"])],
        ["", "jamming", "short_feed"], default="normal").astype(object)
    return str(label[()]) if label.ndim == 0 else label


def regime_probabilities(mfr, mfr_sd, coverage, coverage_sd, thickness_ratio, thickness_sd, rules: dict) -> dict:
    """P(normal), P(jamming), P(short feed) of `classify` when MFR, coverage and thickness_ratio
    are uncertain (a surrogate's predictive mean and SD of a new run), each normal and independent
    of the others; arrays broadcast. A zero SD gives the plain rule. Coverage and thickness of one
    run err together (both grow with the deposit); independence then overstates P(short feed)
    by at most min(P(coverage low), P(thickness low)), which is zero when one condition is
    certain. Returns {"normal": ..., "jamming": ..., "short_feed": ...}."""
    from scipy.stats import norm

    missing = [k for k in RULE_KEYS if k not in rules]
    if missing:
        raise KeyError(f"config section 'regime' lacks {missing} (needed: {list(RULE_KEYS)})")

    def below(mean, sd, threshold):
        mean, sd = np.broadcast_arrays(np.asarray(mean, float), np.asarray(sd, float))
        with np.errstate(divide="ignore", invalid="ignore"):
            p = norm.cdf((threshold - mean) / sd)
        return np.where(sd > 0, p, (mean < threshold).astype(float))

    p_jam = below(mfr, mfr_sd, rules["jam_mfr_max"])
    p_ok = ((1 - below(coverage, coverage_sd, rules["short_feed_coverage_min"]))
            * (1 - below(thickness_ratio, thickness_sd, rules["short_feed_thickness_min"])))
    return {"normal": (1 - p_jam) * p_ok, "jamming": p_jam, "short_feed": (1 - p_jam) * (1 - p_ok)}
