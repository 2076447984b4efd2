"""Reduce one case's raw YADE output to the results table's row.

flow    MFR (volume across the blade's rear plane, exact caps), PD (the study's box fraction) and
        the heap ahead of the blade (heap_h2: what is left to feed the flow, in h^2)
layer   layer quality: packing within the layer's own thickness, coverage, roughness, thickness
noise   the case's own noise estimate (counting statistics; batch means within the case)
regime  the regime rule (scalars or arrays: DEM cases and surrogate predictions alike)
sizes   the feed's volume quantiles (D10, D50, D90), gap / D90 and the layer's segregation
jams    jam events: a sphere the moving blade pins and drags (events per mm, wedged size / h)
case    case_metrics: all of it plus the diagnostics and the stability flags
geometry  exact sphere / axis-aligned-box intersection volumes (the layer's packing density)
window_start  where the flow settles along the blade's travel, and windows opened later (a run's
        raw records, not a case's row: tools/window_start.py, docs/steady_window)
"""
from .case import MAX_WEDGE_OVERLAP, MIN_HEAP_H2, NEW_COLUMNS, PHASES, SETTING_KEYS, SIZE_COLUMNS, case_metrics, measure
from .flow import (
    heap_h2,
    heap_volume,
    layer_density,
    mass_flow_ratio,
    measured_span,
    passed_volume,
    powder,
    sphere_volume,
    window_passed_volume,
)
from .jams import JAM_COLUMNS, jam_events, jam_measures
from .layer import layer_quality, upper_envelope
from .noise import batch_means_sd, counting_sd, flow_trend, flow_trend_batch_z
from .regime import REGIMES, RULE_KEYS, classify, regime_probabilities

__all__ = ["JAM_COLUMNS", "MAX_WEDGE_OVERLAP", "MIN_HEAP_H2", "NEW_COLUMNS", "PHASES", "REGIMES", "RULE_KEYS",
           "SETTING_KEYS", "SIZE_COLUMNS", "batch_means_sd", "case_metrics", "classify", "counting_sd", "flow_trend",
           "flow_trend_batch_z", "heap_h2", "heap_volume", "jam_events", "jam_measures", "layer_density",
           "layer_quality", "mass_flow_ratio", "measure", "measured_span", "passed_volume", "powder",
           "regime_probabilities", "sphere_volume", "upper_envelope", "window_passed_volume"]
