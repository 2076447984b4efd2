#!/usr/bin/env python
"""Where a sphere-step's CPU goes: YADE's per-engine timers (O.timingEnabled) in each phase of a
case, at a costly corner of the design space beside cheaper points.

Each case is the workflow's own scene (spreadmap.case.scene.scene_parameters, rendered from
yade_scripts/spreading_case.py) with `timing` on, stopped after ``--move-steps`` steps of the move
phase (the settle and relax phases run whole), each YADE single-threaded, ``--workers`` at once.
Prints per case and phase: steps, mean spheres, bodies, interactions and contacts at its end, the
seconds YADE's timers gave its engines (wall-clock time of this single-threaded process: CPU time on
an idle core), us per sphere-step, and each engine's share;
``--json PATH`` writes the same numbers.

    .venv/bin/python benchmarks/engine_profile.py                      # corner, normal, thin at default
    .venv/bin/python benchmarks/engine_profile.py --points corner --move-steps 5000 --preset smoke
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from spreadmap.host import description_lines

ROOT = Path(__file__).resolve().parent.parent

POINTS = {
    "corner": {"f": 0.30, "d_um": 10, "h_um": 75, "v_mm_s": 10},   # h/d 7.5: the study's costliest cases
    "normal": {"f": 0.30, "d_um": 30, "h_um": 65, "v_mm_s": 10},   # h/d 2.2
    "thin": {"f": 0.30, "d_um": 45, "h_um": 55, "v_mm_s": 10},     # h/d 1.2
}


def run_one(job: dict) -> dict:
    from spreadmap.case.launcher import run_case
    from spreadmap.case.render import render
    from spreadmap.files import write_text_atomically

    workdir = Path(job["workdir"])
    workdir.mkdir(parents=True, exist_ok=True)
    script, raw_path = workdir / "case.py", workdir / "raw.json"
    write_text_atomically(script, render(job["params"]))
    result = run_case(script, raw_path, workdir / "case.log", timeout_s=job["timeout_s"])
    raw = json.loads(raw_path.read_text()) if raw_path.exists() else {}
    return {"point": job["point"], "arm": job["arm"], "result": result, "phase_cost": raw.get("phase_cost", {}),
            "n_particles": job["params"]["n_particles"], "status": raw.get("status")}


def phase_rows(phase_cost: dict) -> list[dict]:
    rows = []
    for phase, cost in phase_cost.items():
        engines = cost.get("engine_seconds", {})
        total = sum(engines.values())
        sphere_steps = cost["steps"] * cost["spheres"]
        rows.append({"phase": phase, "steps": cost["steps"], "spheres": cost["spheres"], "timed_s": total,
                     "bodies": cost.get("bodies_at_end"), "interactions": cost.get("interactions_at_end"),
                     "contacts": cost.get("contacts_at_end"),
                     "us_per_sphere_step": 1e6 * total / sphere_steps if sphere_steps else float("nan"),
                     "shares": {k: v / total for k, v in engines.items()} if total else {}})
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--points", nargs="+", default=list(POINTS), choices=list(POINTS))
    parser.add_argument("--preset", default="default")
    parser.add_argument("--move-steps", type=int, default=20000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--config", default=str(ROOT / "config.yaml"))
    parser.add_argument("--arm", action="append", default=[], metavar="NAME:KEY=VALUE[,KEY=VALUE]",
                        help="a scene variant beside the plain one: scene params set (JSON values), e.g. "
                             "ordered:spatial_order=true; each point runs plain and every arm, interleaved")
    parser.add_argument("--seed", type=int, default=None, help="packing seed (default: the config's)")
    parser.add_argument("--json", help="write the numbers here")
    args = parser.parse_args(argv)

    from spreadmap.case.render import template_sha256
    from spreadmap.case.scene import scene_parameters
    from spreadmap.config import load

    config = load(args.config)
    print("\n".join(description_lines()))
    base = Path(tempfile.mkdtemp(prefix="engine_profile_"))
    arms = {"plain": {}}
    for spec in args.arm:
        arm, _, sets = spec.partition(":")
        arms[arm] = {k: json.loads(v) for k, v in (kv.split("=", 1) for kv in sets.split(",") if kv)}
    jobs = []
    for name in args.points:
        for arm, sets in arms.items():
            params = scene_parameters(POINTS[name], args.preset, config, f"profile_{name}_{arm}", args.seed)
            params.update(timing=True, move_steps_limit=args.move_steps, scene_sha256=template_sha256(), **sets)
            jobs.append({"point": name, "arm": arm, "params": params, "workdir": str(base / f"{name}_{arm}"),
                         "timeout_s": 4 * params["timeout_s"]})
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(run_one, jobs))
    report = []
    for res in results:
        rows = phase_rows(res["phase_cost"])
        report.append({"point": res["point"], "arm": res["arm"], "n_particles": res["n_particles"],
                       "cpu_time": res["result"]["cpu_time"], "outcome": res["result"]["outcome"],
                       "status": res["status"], "phases": rows})
        print(f"\n{res['point']} {POINTS[res['point']]} [{res['arm']}] at {args.preset}: {res['n_particles']} spheres, "
              f"CPU {res['result']['cpu_time']:.1f} s, {res['result']['outcome']} / {res['status']}")
        engines = sorted({k for r in rows for k in r["shares"]})
        print(f"  {'phase':8} {'steps':>8} {'spheres':>8} {'bodies':>7} {'intrs':>7} {'contacts':>8} "
              f"{'timed_s':>8} {'us/sph-step':>11}  "
              + " ".join(f"{e[:12]:>12}" for e in engines))
        for r in rows:
            print(f"  {r['phase']:8} {r['steps']:8d} {r['spheres']:8.0f} {r['bodies'] or 0:7d} {r['interactions'] or 0:7d} "
                  f"{r['contacts'] or 0:8d} {r['timed_s']:8.1f} {r['us_per_sphere_step']:11.3f}  "
                  + " ".join(f"{100 * r['shares'].get(e, 0):11.1f}%" for e in engines))
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1))
    return 0 if all(r["outcome"] in ("ok", "blown") for r in report) else 1


if __name__ == "__main__":
    sys.exit(main())
