#!/usr/bin/env python
"""Two powder models side by side (issue 49: dry and adhesive spheres; issue 51: one size and a size
distribution): two main jobs' results (or the analyses of their cases), the powder band map's MFR and
layer measure against d at the powder slice (h, v of `maps.powder`), the lowest and highest friction,
with the models' 95 % bands, their difference (second - first) at chosen diameters, and each run's
recommended settings per powder:

    .venv/bin/python tools/compare_powder_models.py DRY_RESULTS ADHESIVE_RESULTS --out docs/adhesion/compare
    .venv/bin/python tools/compare_powder_models.py ONE_SIZE PSD --names "one size" "span 1" \
        --title "spheres of one size against a size distribution" --out docs/size_distribution/main_job/compare

Each RESULTS is a `results/` folder (maps/powder_band_map.csv and decisions/recommendations.csv in
it). `--names` labels the two (default: dry, adhesive). Writes <out>/powder_models.png (+ PDF, CSV)
and <out>/powder_models.md.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

from spreadmap import design, slices
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


NAMES = ("dry", "adhesive")  # the two models' default labels (issue 49's comparison)


def at_diameters(first: pd.DataFrame, second: pd.DataFrame, targets, names=NAMES) -> pd.DataFrame:
    """Both models at the nearest grid diameter to each of DIAMETERS, lowest and highest f: the
    means (columns ``<target>_<name>``), the difference second - first and its SD (the two models
    independent)."""
    a_name, b_name = names
    rows = []
    for f in (first["f"].min(), first["f"].max()):
        for d in DIAMETERS:
            a = first[np.isclose(first["f"], f)]
            grid_d = a["d_um"].to_numpy()[np.argmin(np.abs(a["d_um"].to_numpy() - d))]
            one = {"f": f, "d_um": grid_d}
            for name, table in ((a_name, first), (b_name, second)):
                r = table[np.isclose(table["f"], f) & np.isclose(table["d_um"], grid_d)].iloc[0]
                for t in targets:
                    one[f"{t}_{name}"], one[f"{t}_{name}_sd"] = r[t], r[f"{t}_model_sd"]
                one[f"supported_{name}"] = bool(r["supported"])
            for t in targets:
                one[f"{t}_change"] = one[f"{t}_{b_name}"] - one[f"{t}_{a_name}"]
                one[f"{t}_change_sd"] = math.hypot(one[f"{t}_{b_name}_sd"], one[f"{t}_{a_name}_sd"])
            rows.append(one)
    return pd.DataFrame(rows)


def draw(first: pd.DataFrame, second: pd.DataFrame, targets, stem: Path, title: str, names=NAMES) -> None:
    fig = new_figure(11.0, 4.2)
    axes = fig.subplots(1, len(targets))
    colours = dict(zip(names, ("tab:orange", "tab:blue")))
    for ax, t in zip(axes, targets):
        for name, table in zip(names, (first, second)):
            for f, style in ((table["f"].min(), "--"), (table["f"].max(), "-")):
                part = table[np.isclose(table["f"], f)].sort_values("d_um")
                ax.plot(part["d_um"], part[t], style, color=colours[name], label=f"{name}, f = {f:g}")
                ax.fill_between(part["d_um"], part[t] - Z95 * part[f"{t}_model_sd"],
                                part[t] + Z95 * part[f"{t}_model_sd"], color=colours[name], alpha=0.15, lw=0)
        ax.set_xlabel("particle diameter d (a size distribution's D50) [um]")
        ax.set_ylabel(f"{t} [-]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    both = pd.concat([first.assign(model=names[0]), second.assign(model=names[1])], ignore_index=True)
    columns = ["model", *design.NAMES, *[c for t in targets for c in (t, f"{t}_model_sd")], "supported"]
    save_figure(fig, stem, both[columns])


def recommendations(results: Path) -> pd.DataFrame:
    table = pd.read_csv(results / "decisions" / "recommendations.csv")
    columns = ["powder", "kind", "status", "h_um", "v_mm_s", "probability", "quality"]
    return table[table["recommended"].astype(str) == "True"][columns]


def markdown(changes: pd.DataFrame, targets, rec_first: pd.DataFrame, rec_second: pd.DataFrame, slice_text: str,
             names=NAMES) -> str:
    a_name, b_name = names
    lines = [f"Powder band map at {slice_text}: each model's mean (its 95 % half-width), the change {b_name} - {a_name} "
             "(95 % half-width, the two models independent); `*`: beyond a model's data.", "",
             "| f | d [um] | " + " | ".join(f"{t} {a_name} | {t} {b_name} | change" for t in targets) + " |",
             "|---|---|" + "---|---|---|" * len(targets)]
    for r in changes.to_dict("records"):
        cells = []
        for t in targets:
            for name in names:
                mark = "" if r[f"supported_{name}"] else "*"
                cells.append(f"{r[f'{t}_{name}']:.3f} ({Z95 * r[f'{t}_{name}_sd']:.3f}){mark}")
            cells.append(f"{r[f'{t}_change']:+.3f} ({Z95 * r[f'{t}_change_sd']:.3f})")
        lines.append(f"| {r['f']:g} | {r['d_um']:.1f} | " + " | ".join(cells) + " |")
    lines += ["", "Recommended settings (probability of meeting the bounds; quality: the best-quality target's mean):", "",
              f"| powder | choice | {a_name}: h, v, P | {b_name}: h, v, P |", "|---|---|---|---|"]
    keys = sorted(set(zip(rec_first["powder"], rec_first["kind"])) | set(zip(rec_second["powder"], rec_second["kind"])))

    def cell(table, powder, kind):
        r = table[(table["powder"] == powder) & (table["kind"] == kind)]
        if r.empty:
            return "none"
        r = r.iloc[0]
        return f"{r['h_um']:g} um, {r['v_mm_s']:g} mm/s, P {r['probability']:.2f}"
    for powder, kind in keys:
        lines.append(f"| {powder} | {kind} | {cell(rec_first, powder, kind)} | {cell(rec_second, powder, kind)} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("first", type=Path, help="the first run's results/ folder (e.g. dry spheres)")
    parser.add_argument("second", type=Path, help="the second run's results/ folder (e.g. adhesive spheres)")
    parser.add_argument("--names", nargs=2, default=list(NAMES), metavar=("FIRST", "SECOND"),
                        help="labels of the two runs (default: dry adhesive)")
    parser.add_argument("--title", default="dry against adhesive spheres (0.1 mJ/m^2)",
                        help="the figure's title, before the slice")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    names = tuple(args.names)
    if len(set(names)) != 2:
        parser.error(f"--names must be two different labels, got {names}")
    first, second = band_table(args.first), band_table(args.second)
    targets = ["mfr", second_target(second)]
    fixed = slices.POWDER.fixed_of(second)  # the maps' h and v (and any other fixed axis)
    slice_text = ", ".join(f"{design.BY_NAME[n].symbol} {x:g}" + ("" if design.BY_NAME[n].unit == "-" else
                                                                 f" {design.BY_NAME[n].unit}") for n, x in fixed.items())
    args.out.mkdir(parents=True, exist_ok=True)
    draw(first, second, targets, args.out / "powder_models",
         f"{args.title}, {slice_text}: the lowest (dashed) and highest friction, 95 % bands", names)
    changes = at_diameters(first, second, targets, names)
    text = markdown(changes, targets, recommendations(args.first), recommendations(args.second), slice_text, names)
    write_text_atomically(args.out / "powder_models.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
