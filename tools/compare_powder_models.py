#!/usr/bin/env python
"""The dry and the adhesive powder model side by side (issue 49): two main jobs' results (or the
analyses of their cases), the powder band map's MFR and layer measure against d at the powder
slice (h, v of `maps.powder`), the lowest and highest friction, with the models' 95 % bands, their
difference at chosen diameters, and each run's recommended settings per powder:

    .venv/bin/python tools/compare_powder_models.py DRY_RESULTS ADHESIVE_RESULTS --out docs/adhesion/compare

DRY_RESULTS and ADHESIVE_RESULTS are `results/` folders (maps/powder_band_map.csv and
decisions/recommendations.csv in each). Writes <out>/powder_models.png (+ PDF, CSV) and
<out>/powder_models.md.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

from spreadmap.figures import new_figure, save_figure
from spreadmap.files import write_text_atomically

DIAMETERS = (10.0, 15.0, 20.0, 30.0, 45.0, 50.0)
Z95 = 1.959963984540054


def band_table(results: Path) -> pd.DataFrame:
    return pd.read_csv(results / "maps" / "powder_band_map.csv")


def second_target(table: pd.DataFrame) -> str:
    """The band map's layer measure: the target besides MFR that has a model SD column."""
    names = [c[: -len("_model_sd")] for c in table.columns if c.endswith("_model_sd")]
    return next(n for n in names if n != "mfr")


def at_diameters(dry: pd.DataFrame, adhesive: pd.DataFrame, targets) -> pd.DataFrame:
    """Both models at the nearest grid diameter to each of DIAMETERS, lowest and highest f: the
    means, the difference adhesive - dry and its SD (the two models independent)."""
    rows = []
    for f in (dry["f"].min(), dry["f"].max()):
        for d in DIAMETERS:
            a = dry[np.isclose(dry["f"], f)]
            grid_d = a["d_um"].to_numpy()[np.argmin(np.abs(a["d_um"].to_numpy() - d))]
            one = {"f": f, "d_um": grid_d}
            for name, table in (("dry", dry), ("adhesive", adhesive)):
                r = table[np.isclose(table["f"], f) & np.isclose(table["d_um"], grid_d)].iloc[0]
                for t in targets:
                    one[f"{t}_{name}"], one[f"{t}_{name}_sd"] = r[t], r[f"{t}_model_sd"]
                one[f"supported_{name}"] = bool(r["supported"])
            for t in targets:
                one[f"{t}_change"] = one[f"{t}_adhesive"] - one[f"{t}_dry"]
                one[f"{t}_change_sd"] = math.hypot(one[f"{t}_adhesive_sd"], one[f"{t}_dry_sd"])
            rows.append(one)
    return pd.DataFrame(rows)


def draw(dry: pd.DataFrame, adhesive: pd.DataFrame, targets, stem: Path, title: str) -> None:
    fig = new_figure(11.0, 4.2)
    axes = fig.subplots(1, len(targets))
    colours = {"dry": "tab:orange", "adhesive": "tab:blue"}
    for ax, t in zip(axes, targets):
        for name, table in (("dry", dry), ("adhesive", adhesive)):
            for f, style in ((table["f"].min(), "--"), (table["f"].max(), "-")):
                part = table[np.isclose(table["f"], f)].sort_values("d_um")
                ax.plot(part["d_um"], part[t], style, color=colours[name], label=f"{name}, f = {f:g}")
                ax.fill_between(part["d_um"], part[t] - Z95 * part[f"{t}_model_sd"],
                                part[t] + Z95 * part[f"{t}_model_sd"], color=colours[name], alpha=0.15, lw=0)
        ax.set_xlabel("particle diameter d [um]")
        ax.set_ylabel(f"{t} [-]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    both = pd.concat([dry.assign(model="dry"), adhesive.assign(model="adhesive")], ignore_index=True)
    columns = ["model", "f", "d_um", "h_um", "v_mm_s", *[c for t in targets for c in (t, f"{t}_model_sd")], "supported"]
    save_figure(fig, stem, both[columns])


def recommendations(results: Path) -> pd.DataFrame:
    table = pd.read_csv(results / "decisions" / "recommendations.csv")
    columns = ["powder", "kind", "status", "h_um", "v_mm_s", "probability", "quality"]
    return table[table["recommended"].astype(str) == "True"][columns]


def markdown(changes: pd.DataFrame, targets, rec_dry: pd.DataFrame, rec_adh: pd.DataFrame, slice_text: str) -> str:
    lines = [f"Powder band map at {slice_text}: each model's mean (its 95 % half-width), the change adhesive - dry "
             "(95 % half-width, the two models independent); `*`: beyond a model's data.", "",
             "| f | d [um] | " + " | ".join(f"{t} dry | {t} adhesive | change" for t in targets) + " |",
             "|---|---|" + "---|---|---|" * len(targets)]
    for r in changes.itertuples():
        cells = []
        for t in targets:
            mark = lambda ok: "" if ok else "*"  # noqa: E731
            for model, ok in (("dry", r.supported_dry), ("adhesive", r.supported_adhesive)):
                cells.append(f"{getattr(r, f'{t}_{model}'):.3f} ({Z95 * getattr(r, f'{t}_{model}_sd'):.3f}){mark(ok)}")
            cells.append(f"{getattr(r, f'{t}_change'):+.3f} ({Z95 * getattr(r, f'{t}_change_sd'):.3f})")
        lines.append(f"| {r.f:g} | {r.d_um:.1f} | " + " | ".join(cells) + " |")
    lines += ["", "Recommended settings (probability of meeting the bounds; quality: the best-quality target's mean):", "",
              "| powder | choice | dry: h, v, P | adhesive: h, v, P |", "|---|---|---|---|"]
    keys = sorted(set(zip(rec_dry["powder"], rec_dry["kind"])) | set(zip(rec_adh["powder"], rec_adh["kind"])))

    def cell(table, powder, kind):
        r = table[(table["powder"] == powder) & (table["kind"] == kind)]
        if r.empty:
            return "none"
        r = r.iloc[0]
        return f"{r['h_um']:g} um, {r['v_mm_s']:g} mm/s, P {r['probability']:.2f}"
    for powder, kind in keys:
        lines.append(f"| {powder} | {kind} | {cell(rec_dry, powder, kind)} | {cell(rec_adh, powder, kind)} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dry", type=Path)
    parser.add_argument("adhesive", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    dry, adhesive = band_table(args.dry), band_table(args.adhesive)
    targets = ["mfr", second_target(adhesive)]
    h, v = adhesive["h_um"].iloc[0], adhesive["v_mm_s"].iloc[0]
    slice_text = f"h {h:g} um, v {v:g} mm/s"
    args.out.mkdir(parents=True, exist_ok=True)
    draw(dry, adhesive, targets, args.out / "powder_models",
         f"dry against adhesive spheres (0.1 mJ/m^2), {slice_text}: the lowest (dashed) and highest friction, 95 % bands")
    changes = at_diameters(dry, adhesive, targets)
    text = markdown(changes, targets, recommendations(args.dry), recommendations(args.adhesive), slice_text)
    write_text_atomically(args.out / "powder_models.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
