"""Reduce one case's raw YADE output to MFR, PD, the regime and the diagnostics.

MFR: volume (mass / density) of the spheres that passed behind the blade's rear face during the
     measurement window, over the largest volume that could have passed: gap h x bed width W x
     blade travel in the window. Spheres are counted by centre as they cross the plane; the
     window is long against one diameter.
PD:  solid fraction of the deposited layer at the end of the window in the box spanning the
     window's travel (at least the blade thickness) x the full bed width x the gap height,
     spheres counted by their exact intersection volume with the box.
"""
from __future__ import annotations

import math

import numpy as np

from .geometry import sphere_box_volume
from .scene import DENSEST_PACKING

PHASES = ("settle", "relax", "move")  # the phases of the scene, in order (yade_scripts/spreading_case.py)

REGIMES = ("normal", "jamming", "short_feed")


def passed_volume(snapshot: dict) -> float:
    """Volume passed behind the blade at a snapshot: spheres whose centre is behind (x below) the
    blade's rear face, plus those removed earlier after rolling off the back of the floor."""
    positions, radii = np.asarray(snapshot["positions"], float), np.asarray(snapshot["radii"], float)
    behind = positions[:, 0] < snapshot["blade_rear_x"]
    return float(np.sum(4.0 / 3.0 * math.pi * radii[behind] ** 3)) + snapshot.get("removed_behind_volume", 0.0)


def mass_flow_ratio(start: dict, end: dict, gap: float, width: float) -> float:
    """MFR between two snapshots (dicts with positions, radii, blade_rear_x)."""
    travel = end["blade_rear_x"] - start["blade_rear_x"]
    if travel <= 0:
        raise ValueError("the blade did not advance during the measurement window")
    return (passed_volume(end) - passed_volume(start)) / (gap * width * travel)


def layer_density(positions, radii, x0: float, x1: float, width: float, gap: float, slices: int = 1) -> np.ndarray:
    """Solid fraction in `slices` equal boxes along x between x0 and x1 (y in [0, W], z in [0, h])."""
    positions, radii = np.asarray(positions, float), np.asarray(radii, float)
    edges = np.linspace(x0, x1, slices + 1)
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        near = (positions[:, 0] > a - radii) & (positions[:, 0] < b + radii) & (positions[:, 2] < gap + radii)
        vol = sphere_box_volume(positions[near], radii[near], (a, 0.0, 0.0), (b, width, gap)).sum()
        out.append(vol / ((b - a) * width * gap))
    return np.array(out)


def classify(mfr: float, pd: float, pd_cv: float, rules: dict) -> str:
    if mfr < rules["jam_mfr_max"]:
        return "jamming"
    if pd < rules["short_feed_pd_min"] or pd_cv > rules["short_feed_cv_max"]:
        return "short_feed"
    return "normal"


def case_metrics(raw: dict, regime_rules: dict, stability: dict) -> dict:
    """Everything the results table needs from one raw record (ok, blown or failed)."""
    p = raw["params"]
    out = {
        "case_id": p["case_id"], "preset": p.get("preset", ""),
        **p["point"],
        "seed": p["seed"], "status": raw["status"], "reason": raw.get("reason", ""),
        "mfr": math.nan, "pd": math.nan, "pd_cv": math.nan, "regime": "",
        "n_particles": raw.get("n_particles", p.get("n_particles")),
        "time_step": raw.get("time_step", p["time_step"]),
        "critical_time_step": raw.get("critical_time_step", p["critical_time_step"]),
        "time_step_ratio": raw.get("time_step_ratio", p["time_step"] / p["critical_time_step"]),
        "density_scale": p["density_scale"],
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
    flags = []
    if raw["status"] == "ok":
        s1, s2 = raw["snapshots"]["window_start"], raw["snapshots"]["window_end"]
        out["mfr"] = mass_flow_ratio(s1, s2, p["gap"], p["width"])
        slices = layer_density(s2["positions"], s2["radii"], s1["blade_rear_x"], s2["blade_rear_x"],
                               p["width"], p["gap"], regime_rules["pd_slices"])
        out["pd"] = float(np.mean(slices))  # equal slices: the mean is the whole box's fraction
        out["pd_cv"] = float(np.std(slices) / out["pd"]) if out["pd"] > 0 else math.inf
        out["regime"] = classify(out["mfr"], out["pd"], out["pd_cv"], regime_rules)
        for name in ("mfr", "pd"):
            if not 0.0 <= out[name] <= DENSEST_PACKING:
                flags.append(f"{name} = {out[name]:.4f} outside [0, {DENSEST_PACKING:.4f}]")
    else:
        flags.append(f"{raw['status']}: {raw.get('reason', '')}".strip())
    if out["time_step_ratio"] > 1.0:
        flags.append(f"time step {out['time_step_ratio']:.2f} x critical")
    if out["peak_overlap_ratio"] > stability["max_overlap_ratio"]:
        flags.append(f"peak overlap {out['peak_overlap_ratio']:.3g} R > {stability['max_overlap_ratio']} R")
    if out["escaped_particles"] > stability["max_escaped"]:
        flags.append(f"{out['escaped_particles']} spheres escaped the box")
    out["flagged"] = bool(flags)
    out["flag_reason"] = "; ".join(flags)
    return out
