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
