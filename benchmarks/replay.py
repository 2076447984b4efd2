"""The loop's replay (spreadlab.experiments.replay): the real step code against a truth fitted on the
published cases, with their noise law and the planned-cost law; prints and writes what the stop rule
is worth, per design.

    .venv/bin/python benchmarks/replay.py --out docs/replay --seeds 20 --jobs 2
    .venv/bin/python benchmarks/replay.py --out /tmp/r --seeds 2 --max-cases 64 --designs active_per_cpu

Writes: cost_law.json (the law fitted on the published cases), paths.csv (one row per replay and
step: cases, modelled CPU, the rule's estimate and the true map error per target), stops.csv and
honesty.csv (at each tolerance of --tolerances), replay.png, meta.json. Re-running with the same
arguments reuses paths.csv rows already computed (by design and seed).
"""
from __future__ import annotations

import argparse
import copy
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

from spreadlab.experiments import replay
from spreadmap.config import load
from spreadmap.files import atomic_path, write_text_atomically
from spreadmap.loop.cost import fit_law
from spreadmap.noise_law.apply import case_noise

ROOT = Path(__file__).resolve().parents[1]

PUBLISHED = ["cases_converge.csv", "cases_lds.csv", "cases_lattice.csv", "cases_heldout.csv", "cases_heldout2.csv"]
_WORLD = None


def published_tables(study: Path) -> list[pd.DataFrame]:
    return [pd.read_csv(study / name) for name in PUBLISHED if (study / name).exists()]


def _init(world_path):
    global _WORLD
    import joblib

    _WORLD = joblib.load(world_path)


def _one(args):
    design, seed, max_cases, max_cpu_h = args
    t0 = time.process_time()
    path = replay.replay_one(_WORLD, design, seed, max_cases=max_cases, max_cpu_h=max_cpu_h)
    return path.assign(replay_cpu_s=time.process_time() - t0)


def summary_markdown(paths: pd.DataFrame, hon: pd.DataFrame, margin: float, law: dict) -> str:
    """The replay's tables as markdown (written by this script; docs/replay/README.md reads them)."""
    lines = ["# The loop's replay: numbers", "",
             f"Written by `benchmarks/replay.py`. {paths.groupby(['design', 'seed']).ngroups} replays; "
             f"margin {margin:g} calibrated on the first seeds, judged on the others (meta.json says which); "
             f"cost law CPU s = exp({law['ln_a']:.3f}) N^{law['b_particles']:.3f} S^{law['b_steps']:.3f} "
             f"(N spheres, S steps planned; {law['cases']} published cases, residual SD {law['residual_sd']:.2f} in ln).",
             "", "## Stops per tolerance (MFR and PD): honest = the true map error (RMS, worst grid) within the "
             "tolerance at the stop; 95 % Clopper-Pearson interval", "",
             "| rule | tolerance | design | stops / replays | honest [95 % CI] | cases at stop, median (p90) | "
             "modelled CPU h at stop, median (p90) |", "|---|---|---|---|---|---|---|"]
    for r in hon.sort_values(["rule", "tolerance", "design"]).itertuples():
        honest = (f"{r.honest_share:.2f} [{r.honest_low:.2f}, {r.honest_high:.2f}]" if r.stops else "-")
        cases = f"{r.cases_median:.0f} ({r.cases_p90:.0f})" if r.stops else "-"
        cpu = f"{r.cpu_h_median:.2f} ({r.cpu_h_p90:.2f})" if r.stops else "-"
        lines.append(f"| {r.rule} | {r.tolerance:g} | {r.design} | {r.stops} / {r.replays} | {honest} | {cases} | {cpu} |")
    p = paths.assign(worst=paths[["mfr_true", "pd_true"]].max(axis=1))
    g = p.groupby(["design", "n"]).agg(cpu=("cpu_h_modelled", "median"), med=("worst", "median"),
                                        q90=("worst", lambda x: x.quantile(0.9)),
                                        mfr=("mfr_true", "median"), pd_=("pd_true", "median"),
                                        est=("mfr_estimate", "median")).reset_index()
    lines += ["", "## The true map error per design and size (worst of MFR and PD, worst grid; over the seeds)", "",
              "| design | cases | modelled CPU h (median) | true error median | true error p90 | MFR median | PD median "
              "| MFR estimate median |",
              "|---|---|---|---|---|---|---|---|"]
    for r in g.itertuples():
        lines.append(f"| {r.design} | {r.n} | {r.cpu:.2f} | {r.med:.4f} | {r.q90:.4f} | {r.mfr:.4f} | {r.pd_:.4f} "
                     f"| {r.est:.4f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--study", type=Path, default=ROOT / "docs" / "study")
    ap.add_argument("--fidelity", type=Path, default=ROOT / "docs" / "fidelity" / "cases_presets.csv")
    ap.add_argument("--cases", type=Path, nargs="*", default=None,
                    help="the truth's tables instead of --study's published ones (e.g. an adhesive main job's "
                         "cases.csv); their `default` cases are fitted")
    ap.add_argument("--law-cases", type=Path, nargs="*", default=None,
                    help="the cost law's tables (one intercept each) instead of --study's and --fidelity's")
    ap.add_argument("--law-scene", choices=["full_pile", "shipped"], default="full_pile",
                    help="the scene the law's tables ran: full_pile (the published study's, before the fed "
                         "heap) or shipped (the config's as it is, e.g. a main job run since the fed heap)")
    ap.add_argument("--config", type=Path, default=ROOT / "config.yaml")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0,
                    help="replay seeds first-seed .. first-seed + seeds - 1 (fresh seeds for a judgement)")
    ap.add_argument("--max-cases", type=int, default=160)
    ap.add_argument("--max-cpu-h", type=float, default=None)
    ap.add_argument("--designs", nargs="*", default=[d["name"] for d in replay.DESIGNS])
    ap.add_argument("--tolerances", nargs="*", type=float, default=[0.010, 0.012, 0.015, 0.02, 0.025])
    ap.add_argument("--calibrate-on", nargs="*", type=float, default=[0.015, 0.02],
                    help="tolerances the margin is calibrated at (those the shipped budget can reach)")
    ap.add_argument("--calibration-seeds", type=int, default=None,
                    help="the margin is calibrated on seeds 0 to this - 1 and judged on the rest (default: the first "
                         "half); more seeds with the same value judge the same margin on more held-out replays")
    ap.add_argument("--min-stop-cases", type=int, default=None,
                    help="the fewest cases a stop may have (default: the config's converge.min_stop_cases)")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    import joblib

    a.out.mkdir(parents=True, exist_ok=True)
    config = load(a.config)
    tables = [pd.read_csv(f) for f in a.cases] if a.cases else published_tables(a.study)
    if a.law_cases:
        law_tables = [pd.read_csv(f) for f in a.law_cases]
    else:
        law_tables = tables + ([pd.read_csv(a.fidelity)] if a.fidelity.exists() else [])
    # the law relates the work a case planned to its CPU: the published cases ran the full pile
    # (before scene.fed_heap shipped), so their planned work is that scene's; the fitted law then
    # prices the shipped scene's planned work (docs/case_cost: it predicts the fed cost)
    published_scene = copy.deepcopy(config)
    if a.law_scene == "full_pile":
        published_scene["scene"]["fed_heap"] = False
    law = fit_law(law_tables, published_scene)
    write_text_atomically(a.out / "cost_law.json", json.dumps(law, indent=1) + "\n")
    print(f"cost law on {law['cases']} published cases: CPU s = exp({law['ln_a']:.3f}) N^{law['b_particles']:.3f} "
          f"S^{law['b_steps']:.3f}, residual SD {law['residual_sd']:.3f} (ln, within sessions)")
    world_path = a.out / "world.joblib"
    if not world_path.exists():
        published = pd.concat(tables, ignore_index=True).drop_duplicates("case_id")
        published = published[published["preset"].astype(str) == "default"]
        # each case's noise as the workflow weighs it: MFR's and PD's from the fitted noise law
        # (config noise_model, docs/noise), the layer measures' from the bands
        published = case_noise(published, config.get("noise_model"), config["noise_calibration"],
                               config["metrics"]["counting_noise_c"])
        t0 = time.time()
        world = replay.build_world(published, config, law)
        print(f"truth fitted in {time.time() - t0:.0f} s: {world.notes[0]}")
        with atomic_path(world_path) as tmp:
            joblib.dump(world, tmp)
    paths_file = a.out / "paths.csv"
    done = pd.read_csv(paths_file) if paths_file.exists() else pd.DataFrame(columns=["design", "seed"])
    have = set(zip(done["design"], done["seed"]))
    designs = [d for d in replay.DESIGNS if d["name"] in a.designs]
    seeds = range(a.first_seed, a.first_seed + a.seeds)
    todo = [(d, s, a.max_cases, a.max_cpu_h) for d in designs for s in seeds if (d["name"], s) not in have]
    print(f"{len(todo)} replays to run ({len(have)} reused), {a.jobs} processes")
    t0 = time.time()
    parts = [done] if len(done) else []
    with ProcessPoolExecutor(a.jobs, initializer=_init, initargs=(str(world_path),)) as pool:
        for i, path in enumerate(pool.map(_one, todo), 1):
            parts.append(path)
            r = path.iloc[-1]
            print(f"[{i}/{len(todo)} {time.time() - t0:.0f} s] {r['design']} seed {r['seed']}: {len(path)} steps "
                  f"to {r['n']} cases, replay CPU {r['replay_cpu_s']:.0f} s", flush=True)
            if i % 4 == 0 or i == len(todo):
                with atomic_path(paths_file) as tmp:
                    pd.concat(parts, ignore_index=True).to_csv(tmp, index=False)
    paths = pd.concat(parts, ignore_index=True) if parts else done
    with atomic_path(paths_file) as tmp:
        paths.to_csv(tmp, index=False)
    # the margin: calibrated on the first seeds (half unless told), judged on the others
    half = a.seeds // 2 if a.calibration_seeds is None else a.calibration_seeds
    if not 0 < half < a.seeds:
        raise SystemExit(f"--calibration-seeds: value {half} must be between 1 and --seeds - 1 ({a.seeds - 1})")
    calib, test = paths[paths["seed"] < a.first_seed + half], paths[paths["seed"] >= a.first_seed + half]
    min_cases = (int(config["converge"].get("min_stop_cases") or 0) if a.min_stop_cases is None
                 else a.min_stop_cases)
    margin = replay.calibrate_margin(calib, a.calibrate_on, min_cases=min_cases)
    calib_seeds = f"{a.first_seed}-{a.first_seed + half - 1}"
    print(f"margin calibrated on seeds {calib_seeds} at tolerances {a.calibrate_on}, stops from {min_cases} cases: "
          f"{margin} (the smallest that makes 90 % of their stops, pooled over the designs, honest)")
    all_stops, all_honesty = [], []
    for rule, m, frame in (("bare estimate", 1.0, paths), (f"x{margin:g} (held-out seeds)", margin, test)):
        if not np.isfinite(m):
            continue
        for tol in a.tolerances:
            st = replay.stops(frame, {t: tol for t in replay.TARGETS}, margin=m,
                              min_cases=min_cases).assign(tolerance=tol, rule=rule, margin=m)
            all_stops.append(st)
            all_honesty.append(replay.honesty(st).assign(tolerance=tol, rule=rule, margin=m))
    stops = pd.concat(all_stops, ignore_index=True)
    hon = pd.concat(all_honesty, ignore_index=True)
    for name, frame in (("stops.csv", stops), ("honesty.csv", hon)):
        with atomic_path(a.out / name) as tmp:
            frame.to_csv(tmp, index=False)
    with pd.option_context("display.width", 220, "display.max_columns", 20, "display.max_rows", 200):
        print(hon.round(3).to_string(index=False))
    from spreadlab.experiments.replay_plots import plot_replay

    plot_replay(paths, hon, a.out / "replay")
    write_text_atomically(a.out / "summary.md", summary_markdown(paths, hon, margin, law))
    meta = {"command": "benchmarks/replay.py " + " ".join(argv if argv is not None else sys.argv[1:]),
            "margin": margin, "margin_calibrated_on_seeds": calib_seeds, "min_stop_cases": min_cases,
            "margin_calibrated_at_tolerances": a.calibrate_on, "seeds": a.seeds, "first_seed": a.first_seed,
            "max_cases": a.max_cases,
            "designs": a.designs, "tolerances": a.tolerances,
            "replays": int(paths.groupby(["design", "seed"]).ngroups),
            "replay_cpu_s_total": float(paths.groupby(["design", "seed"])["replay_cpu_s"].first().sum())
            if "replay_cpu_s" in paths else None}
    write_text_atomically(a.out / "meta.json", json.dumps(meta, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
