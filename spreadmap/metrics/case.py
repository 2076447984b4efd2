"""Reduce one case's raw YADE output to the row of the results table: MFR and PD (the study's
axes, .flow), the layer's quality (.layer), the case's own noise estimate (.noise), the regime
(.regime) and the diagnostics, with the stability flags."""
from __future__ import annotations

import math

import numpy as np

from .. import targets
from ..case.scene import DENSEST_PACKING
from ..config import renamed_keys
from ..schema import checked, section_schema
from .flow import heap_h2, layer_density, mass_flow_ratio, measured_span, powder, sphere_volume, window_passed_volume
from .jams import JAM_COLUMNS, jam_measures
from .layer import layer_quality
from .noise import batch_means_sd, counting_sd, flow_trend, flow_trend_batch_z
from .regime import classify
from .sizes import size_measures

PHASES = ("settle", "relax", "move")  # the phases of the scene, in order (yade_scripts/spreading_case.py)

# columns added by the layer / precision work (issues 13, 14), after every older column
NEW_COLUMNS = ("n_passed", "mfr_sd", "pd_sd", "mfr_sd_within", "n_pd", "layer_fill", "coverage",
               "roughness_d", "thickness_ratio", "flow_trend", "flow_trend_z", "peak_overlap_free",
               "peak_overlap_wedged", "wedged", "layer_fill_sd", "coverage_sd", "roughness_d_sd",
               "thickness_ratio_sd",
               # the heap ahead of the blade at the window's start and end, in h^2 (issue 32)
               "heap_start_h2", "heap_end_h2",
               # the flow's change between the window's halves in SEs of its within-window noise, the
               # steady flag's statistic (noise.flow_trend_batch_z; flow_trend_z: counting-noise SEs)
               "flow_trend_z_batch")
# NEW_COLUMNS, SIZE_COLUMNS and JAM_COLUMNS (issue 66, .jams) keep the published tables' order; a target registered later in
# spreadmap.targets brings its columns after them (target_columns)
# the sizes: the feed's volume quantiles, the gap over D90 and the layer's segregation (issue 51, .sizes)
SIZE_COLUMNS = ("feed_d10_um", "feed_d50_um", "feed_d90_um", "h_over_d90", "layer_d50_ratio", "layer_d50_ratio_sd")
# metrics.layer_block_d's default (the schema's): block length (in d) of the layer measures' jackknife noise (.layer)
LAYER_BLOCK_D = checked("metrics")["layer_block_d"]
# metrics.jam_overlap_ratio and jam_min_travel_d's defaults (the schema's): what a jam event is (.jams)
JAM_OVERLAP, JAM_MIN_TRAVEL_D = checked("metrics")["jam_overlap_ratio"], checked("metrics")["jam_min_travel_d"]
SETTING_KEYS = ("pd_clearance_d", "pd_slices", "counting_noise_c", "within_batches", "surface_grid_d")
# stability.min_heap_h2's default (schemas/config.schema.yaml; docs/guide/01-model.md, "Metrics"):
# sound shipped cases end their window with 0.97 h^2 or more ahead of the blade (98 main-job
# cases, h/d 1.1-7.1), piles that ran down with ~0.2-0.5 h^2 (estimated)
MIN_HEAP_H2 = section_schema("stability")["properties"]["min_heap_h2"]["default"]
# stability.max_wedge_overlap_ratio's default (the schema's): a sphere the moving blade presses
# (the wedge, peak_overlap_wedged) is not a time-step matter and is not held to max_overlap_ratio,
# but no wedge of a sound step goes this deep: the largest of ~1,400 published cases is 0.174 R
# (docs/study/cases_converge.csv); a step too large goes further (0.92-0.95 x critical: 1.25-1.48 R, but the
# whole bed blew up with it; no step was seen unstable near the blade alone: tests/case/test_stability_yade.py)
MAX_WEDGE_OVERLAP = section_schema("stability")["properties"]["max_wedge_overlap_ratio"]["default"]
# stability.max_flow_trend_z's default (the schema's): a flow that fell or rose between the window's
# halves by more SEs of its within-window noise (flow_trend_z_batch) is not steady (docs/steady_window)
MAX_FLOW_TREND_Z = section_schema("stability")["properties"]["max_flow_trend_z"]["default"]


def _powder_snapshot(snapshot: dict) -> dict:
    pos, rad = powder(snapshot)
    return {**snapshot, "positions": pos, "radii": rad}


def target_columns(first=()) -> tuple[str, ...]:
    """The columns of the targets registered in ``spreadmap.targets`` that neither `first` (the
    row's leading columns, e.g. mfr and pd) nor NEW_COLUMNS and SIZE_COLUMNS hold: a case's row
    ends with them (none for the targets of the published tables)."""
    held = set(first) | set(NEW_COLUMNS) | set(SIZE_COLUMNS) | set(JAM_COLUMNS)
    return tuple(c for c in targets.columns() if c not in held)


def check_settings(settings: dict) -> None:
    missing = [k for k in SETTING_KEYS if k not in settings]
    if missing:
        raise KeyError(f"config section 'metrics' lacks {missing} (needed: {list(SETTING_KEYS)})")


def measure(raw: dict, settings: dict) -> dict:
    """MFR, PD and its slice CV, the layer measures and the noise estimates of a finished case."""
    check_settings(settings)
    p = raw["params"]
    d, gap, width = p["diameter"], p["gap"], p["width"]
    s1 = _powder_snapshot(raw["snapshots"]["window_start"])
    s2 = _powder_snapshot(raw["snapshots"]["window_end"])
    # spheres are counted at their mean volume: one size, the sphere's; a size distribution, the
    # mean by number of the pile as the blade starts
    if p.get("psd_sizes"):
        _, feed_radii = powder(raw["snapshots"]["blade_start"])
        v_sphere = float(np.mean(4.0 / 3.0 * math.pi * feed_radii ** 3))
    else:
        v_sphere = sphere_volume(d)
    x0, x1 = measured_span(s1, s2, settings["pd_clearance_d"] * d, p["blade_thickness"], diameter=d)
    out = {"mfr": mass_flow_ratio(s1, s2, gap, width)}
    slices = layer_density(s2["positions"], s2["radii"], x0, x1, width, gap, settings["pd_slices"])
    out["pd"] = float(np.mean(slices))  # equal slices: the mean is the whole box's fraction
    out["pd_cv"] = float(np.std(slices) / out["pd"]) if out["pd"] > 0 else math.inf
    c = settings["counting_noise_c"]
    out["n_passed"] = window_passed_volume(s1, s2) / v_sphere
    out["n_pd"] = out["pd"] * (x1 - x0) * width * gap / v_sphere
    travel = s2["blade_rear_x"] - s1["blade_rear_x"]
    out["mfr_sd"] = counting_sd(out["n_passed"], v_sphere / (gap * width * travel), c)
    out["pd_sd"] = counting_sd(out["n_pd"], v_sphere / ((x1 - x0) * width * gap), c)
    out["mfr_sd_within"] = batch_means_sd(raw.get("behind_series", []), s1["blade_rear_x"], s2["blade_rear_x"],
                                          gap, width, settings["within_batches"])[0]
    # is the flow steady over the window? (second half - first) / mean, in counting-noise SEs
    # (flow_trend_z, kept for comparison: the real noise is larger) and in SEs of the flow's own
    # within-window noise (flow_trend_z_batch: the steady flag's statistic)
    out["flow_trend"] = flow_trend(raw.get("behind_series", []), s1["blade_rear_x"], s2["blade_rear_x"], gap, width)
    se = 2.0 * c / math.sqrt(out["n_passed"]) if out["n_passed"] > 0 else math.nan
    out["flow_trend_z"] = out["flow_trend"] / se if se and math.isfinite(se) else math.nan
    out["flow_trend_z_batch"] = flow_trend_batch_z(raw.get("behind_series", []), s1["blade_rear_x"], s2["blade_rear_x"],
                                                   settings["within_batches"])[0]
    layer = layer_quality(s2["positions"], s2["radii"], x0, x1, width, settings["surface_grid_d"] * d,
                          block=settings.get("layer_block_d", LAYER_BLOCK_D) * d)
    out["layer_fill"], out["layer_fill_sd"] = layer["layer_fill"], layer["layer_fill_sd"]
    out["coverage"], out["coverage_sd"] = layer["coverage"], layer["coverage_sd"]
    out["roughness_d"], out["roughness_d_sd"] = layer["roughness"] / d, layer["roughness_sd"] / d
    out["thickness_ratio"], out["thickness_ratio_sd"] = layer["thickness"] / gap, layer["thickness_sd"] / gap
    # what is left ahead of the blade to feed the flow: a pile that ran down before the window, or
    # is nearly gone at its end, shows here even when the flow has no trend within the window
    out["heap_start_h2"], out["heap_end_h2"] = heap_h2(s1, gap, width), heap_h2(s2, gap, width)
    if "blade_start" in raw["snapshots"]:
        out.update(size_measures(raw["snapshots"]["blade_start"], s2, x0, x1, gap))
    # jam events: a sphere the moving blade pins and drags (records before the jam record: NaN)
    out.update(jam_measures(raw, settings.get("jam_overlap_ratio", JAM_OVERLAP),
                            settings.get("jam_min_travel_d", JAM_MIN_TRAVEL_D)))
    return out


def overlap_by_cause(raw: dict, peak: float, bound: float) -> dict:
    """The peak overlap split by cause (the scene's attribute_overlap): `free` (impacts, the pile's
    weight: the time step's and the stiffness's doing, which the stability bound is for) and
    `wedged` (a sphere pinned between the moving blade and what lies below it: the blade is driven
    whatever the force, so the overlap grows until the sphere squeezes out, at any time step; a
    particle dragged by the blade, reported as `wedged` and not flagged). Raw records from before
    the split have only the whole peak, which then counts as free."""
    if "peak_overlap_free" not in raw:
        return {"peak_overlap_free": peak, "peak_overlap_wedged": math.nan, "wedged": False}
    wedged = raw["peak_overlap_wedged"]
    return {"peak_overlap_free": raw["peak_overlap_free"], "peak_overlap_wedged": wedged, "wedged": wedged > bound}


# Near its peak a Hertz impact's overlap falls as cos(omega t) to second order, omega t_c = sqrt(5/4) x 2.943:
# delta'' = -(5/4) v0^2 / delta_max at the peak and t_c = 2.943 delta_max / v0 (Johnson, Contact Mechanics,
# 1985, sec. 11.4); 4.7 % faster than a half-sine's pi.
HERTZ_PEAK_OMEGA_TC = math.sqrt(1.25) * 2.943


def overlap_sampling_factor(params: dict) -> float:
    """How much an overlap peak can exceed what a record read every ``overlap_every`` steps saw.

    One sample lies within k / 2 steps of an impact's peak (k = ``overlap_every``), where the overlap
    is at least cos(omega k dt / 2) of the peak (``HERTZ_PEAK_OMEGA_TC`` / t_c, t_c the shortest
    contact the scene expects, ``contact_time``; a longer contact falls slower). The stability check
    multiplies the recorded peak by that: ~1.4 at the shipped stride (k = 4 at `default`, two reads
    a contact; 1.05-1.09 at k = 2, four reads, before 2026-12-07), 1 where
    every step is read (k = 1, and records from before the stride). Checked against YADE's own
    impacts (tests/case/test_overlap_resolution_yade.py: within 0.5 % of the per-step record at
    8 steps per contact, where the integration itself departs from Hertz's curve).
    """
    every = int(params.get("overlap_every", 1) or 1)
    contact = params.get("contact_time")
    if every <= 1 or not contact:
        return 1.0
    angle = HERTZ_PEAK_OMEGA_TC * 0.5 * every * float(params["time_step"]) / float(contact)
    return 1.0 / math.cos(min(angle, 0.45 * math.pi))


def wedge_cause(params: dict) -> str:
    """Why a wedge went deeper than the bound: with spheres of one size, or a size distribution
    whose largest sphere passes the gap, no wedge of a sound step goes that deep; when the feed's
    largest spheres are wider than the gap (a coarse tail, `psd_sizes` [m] against `gap` [m]) it is
    a jam: such a sphere cannot pass, and the blade, driven at its speed, squeezes it."""
    sizes = params.get("psd_sizes") or []
    gap = params.get("gap")
    if sizes and gap and sizes[-1] > gap:
        return (f"a jam of the coarse tail (the feed's largest spheres {sizes[-1] * 1e6:.0f} um against a gap of "
                f"{gap * 1e6:.0f} um: they cannot pass), not a step too long")
    return "beyond any wedge of a sound step"


def flow_fall_reason(trend: float, trend_z: float, heap_end_h2: float, heap_min: float | None) -> str:
    """The flag of a flow that fell over the window, with its cause as far as the heap ahead of the
    blade tells (the text after the last ': ' is the cause the summaries count): a heap that still
    holds `heap_min` h^2 or more at the window's end did not run down, so the fall is the flow's
    own (unsteady: a heap that builds or slides, a floor the flow has not settled on); a smaller
    heap, or none measured, is a pile that ran down."""
    fell = f"flow fell by {-trend:.0%} over the window ({trend_z:.1f} SE of its within-window noise)"
    if heap_min is not None and math.isfinite(heap_end_h2) and heap_end_h2 >= heap_min:
        return f"{fell} with {heap_end_h2:.2f} h^2 still ahead of the blade: the flow is unsteady, the pile did not run down"
    return f"{fell}: the pile ran down"


def flow_rise_reason(trend: float, trend_z: float) -> str:
    """The flag of a flow that rose over the window (the text after the last ': ' is the cause the
    summaries count): the window opened before the flow had settled (a flow still rising towards
    its steady value reads an MFR below it)."""
    return (f"flow rose by {trend:.0%} over the window ({trend_z:.1f} SE of its within-window noise): "
            f"the flow was still rising in the window: not steady")


def flow_trend_bound(stability: dict) -> float | None:
    """The steady flag's bound on |flow_trend_z_batch| from a `stability` section: its
    ``max_flow_trend_z``; where a section that was not validated gives only the deprecated
    ``max_flow_decline_z``, that (with a FutureWarning, ``spreadmap.config.renamed_keys``: the new
    key takes precedence where both are given); where it gives neither, the schema's default.
    None: the flag is off."""
    section = renamed_keys({"stability": dict(stability)})["stability"]
    return section.get("max_flow_trend_z", MAX_FLOW_TREND_Z)


def _applied_bond_number(raw: dict) -> float:
    """The Bond number the scene applied (``adhesion.bond_number`` of the raw record, read off the
    contacts at the end of the settling); NaN when the record has none (a record from before
    adhesion, or a case that ended before settling)."""
    value = (raw.get("adhesion") or {}).get("bond_number")
    return math.nan if value is None else float(value)


def case_metrics(raw: dict, regime_rules: dict, stability: dict, settings: dict) -> dict:
    """Everything the results table needs from one raw record (ok, blown or failed).

    Parameters
    ----------
    raw : dict
        The case's raw YADE record (``spreadmap.records.read_raw``).
    regime_rules : dict
        The config's `regime` section (the regime rule's thresholds).
    stability : dict
        The config's `stability` section: ``max_overlap_ratio`` [R] and ``max_escaped`` (spheres);
        optional ``max_wedge_overlap_ratio`` [R], ``max_flow_trend_z`` (standard errors of the
        flow's within-window noise, either way; the deprecated ``max_flow_decline_z`` is read as it,
        ``flow_trend_bound``) and ``min_heap_h2`` [h^2], each None to switch its flag off.
    settings : dict
        The config's `metrics` section (``SETTING_KEYS``).

    Returns
    -------
    dict
        The case's row of the results table: identity, parameters, ``status``, ``mfr`` and ``pd``
        (dimensionless; NaN unless the case finished), ``regime``, ``flagged`` and
        ``flag_reason``, the run's diagnostics (time step, overlaps, energy, escaped spheres, CPU
        and wall time [s]), the floor, and the noise and layer columns (``NEW_COLUMNS``).

    Raises
    ------
    KeyError
        If `settings` lacks a key of ``SETTING_KEYS`` (or the record a key it must have).
    """
    check_settings(settings)
    p = raw["params"]
    out = {
        "case_id": p["case_id"], "preset": p.get("preset", ""),
        **p["point"],
        "seed": p["seed"], "status": raw["status"], "reason": raw.get("reason", ""),
        # the floor (the scene's defaults where a record predates them: flat, jitter 0.5); the
        # jitter of a rough substrate only
        "substrate": p.get("substrate", "flat"),
        "substrate_jitter": p.get("substrate_jitter", 0.5) if p.get("substrate") == "rough" else math.nan,
        "mfr": math.nan, "pd": math.nan, "pd_cv": math.nan, "regime": "",
        "n_particles": raw.get("n_particles", p.get("n_particles")),
        "time_step": raw.get("time_step", p["time_step"]),
        "critical_time_step": raw.get("critical_time_step", p["critical_time_step"]),
        "time_step_ratio": raw.get("time_step_ratio", p["time_step"] / p["critical_time_step"]),
        "density_scale": p["density_scale"],
        # DMT adhesion: the real surface energy [J/m^2] (0 in records from before it) and the Bond
        # number the scene applied (a sphere pair's pull-off over its weight, read off its contacts)
        "surface_energy": p.get("surface_energy", 0.0),
        "bond_number": _applied_bond_number(raw),
        # the size distribution's span (D90 - D10) / D50 (0: one size; records from before it)
        "size_span": p.get("size_span", 0.0),
        "steps": raw.get("steps", math.nan), "simulated_time": raw.get("simulated_time", math.nan),
        "wall_time": raw.get("wall_time", math.nan),
        "cpu_time": raw.get("cpu_time", math.nan),
        "peak_overlap_ratio": raw.get("peak_overlap_ratio", math.nan),
        # where it happened: the fall into the pile, the pile at rest, the spreading
        **{f"peak_overlap_{phase}": raw.get("peak_overlap_by_phase", {}).get(phase, math.nan) for phase in PHASES},
        "final_kinetic_energy": raw.get("final_kinetic_energy", math.nan),
        "final_ke_per_mgd": (raw["final_kinetic_energy"] / raw["kinetic_energy_scale"]
                             if "kinetic_energy_scale" in raw else math.nan),
        "escaped_particles": raw.get("escaped_particles", math.nan),
        "rolled_off_particles": raw.get("rolled_off_particles", math.nan),
        "max_speed": raw.get("max_speed_seen", math.nan),
        # the settle / relax phases ended on their time cap, kinetic energy not yet decayed (the
        # free rolling of spheres without rolling resistance keeps it up): reported, not flagged
        "settled_by_time": raw.get("settled_by_time"),
        "relaxed_by_time": raw.get("relaxed_by_time"),
        "yade_version": raw.get("yade_version", ""),
    }
    own = NEW_COLUMNS + SIZE_COLUMNS + JAM_COLUMNS + target_columns(out)
    new = {k: math.nan for k in own}
    new.update(overlap_by_cause(raw, out["peak_overlap_ratio"], stability["max_overlap_ratio"]))
    flags = []
    if raw["status"] == "ok":
        measured = measure(raw, settings)
        out.update({k: measured[k] for k in ("mfr", "pd", "pd_cv")})
        new.update({k: measured[k] for k in own if k in measured})
        out["regime"] = classify(out["mfr"], new["coverage"], new["thickness_ratio"], regime_rules)
        for name in targets.names("base"):
            if not 0.0 <= out[name] <= DENSEST_PACKING:
                flags.append(f"{name} = {out[name]:.4f} outside [0, {DENSEST_PACKING:.4f}]")
    else:
        flags.append(f"{raw['status']}: {raw.get('reason', '')}".strip())
    if out["time_step_ratio"] > 1.0:
        flags.append(f"time step {out['time_step_ratio']:.2f} x critical")
    sampling = overlap_sampling_factor(p)  # the peak between the record's samples (1: read every step)
    if new["peak_overlap_free"] * sampling > stability["max_overlap_ratio"]:
        flags.append(f"peak overlap {new['peak_overlap_free']:.3g} R" + (
            f" (x{sampling:.3f}: read every {p['overlap_every']} steps)" if sampling > 1.0 else "")
            + f" > {stability['max_overlap_ratio']} R")
    wedge_max = stability.get("max_wedge_overlap_ratio", MAX_WEDGE_OVERLAP)
    if wedge_max is not None and new["peak_overlap_wedged"] * sampling > wedge_max:  # nan (no split) compares False
        flags.append(f"peak overlap {new['peak_overlap_wedged']:.3g} R at spheres the blade presses > {wedge_max} R: "
                     + wedge_cause(p))
    z_max = flow_trend_bound(stability)
    heap_min = stability.get("min_heap_h2", MIN_HEAP_H2)
    z = new["flow_trend_z_batch"]
    if z_max is not None and z < -z_max:  # nan (no series, too few batches) compares False
        flags.append(flow_fall_reason(new["flow_trend"], z, new["heap_end_h2"], heap_min))
    if z_max is not None and z > z_max:
        flags.append(flow_rise_reason(new["flow_trend"], z))
    if heap_min is not None and new["heap_end_h2"] < heap_min:  # nan (a failed case) compares False
        flags.append(f"the heap ahead of the blade fell to {new['heap_end_h2']:.2f} h^2 (< {heap_min:g} h^2): "
                     f"the pile ran down")
    if out["escaped_particles"] > stability["max_escaped"]:
        flags.append(f"{out['escaped_particles']} spheres escaped the box")
    out["flagged"] = bool(flags)
    out["flag_reason"] = "; ".join(flags)
    out.update(new)
    return out
