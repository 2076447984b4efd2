"""Figure of the noise law: each seed-repeat cell's relative SD against h/d (at the law's reference
count) and against N (at its reference h/d), with the fitted law and its 95 % band."""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from spreadlab.noise_law.cells import COUNT
from spreadlab.noise_law.fit import HD_REF, N_REF, NoiseLaw
from spreadmap.figures import new_figure, save_figure

GROUPS = {"study": ("study_", "o", "tab:blue"), "fidelity presets": ("fidelity_presets", "s", "tab:orange"),
          "fidelity knobs": ("fidelity_k", "D", "tab:green"), "fidelity density x1e4": ("fidelity_fast", "v", "tab:olive"),
          "precision window8 / shipped": ("precision", "^", "tab:red")}


def _group(source: str) -> str:
    return next(name for name, (prefix, _, _) in GROUPS.items() if source.startswith(prefix))


def _grid(cells: pd.DataFrame, column: str, n: float, hd: float) -> pd.DataFrame:
    lo, hi = cells[column].min(), cells[column].max()
    values = np.geomspace(lo * 0.9, hi * 1.1, 100)
    grid = pd.DataFrame({"n": n, "h_over_d": hd, "mean": 1.0}, index=range(100))
    grid[column] = values
    return grid


def law_figure(cells: dict[str, pd.DataFrame], laws: dict[str, NoiseLaw], stated_c: float, bands: list,
               path_stem, floor: str | None = None) -> dict:
    """The noise law's figure: per target, the cells' relative SD against h/d and against N.

    The points are s / mean scaled to the reference count (left) or h/d (right) by the law's own
    exponents, with their 68 % chi-square intervals; beside them the fitted law with its 95 % band
    and the stated counting law.

    Parameters
    ----------
    cells : dict of str to pandas.DataFrame
        Per target (mfr, pd): the seed-repeat cells the law was fitted on.
    laws : dict of str to NoiseLaw
        Per target (mfr, pd): the fitted law (its ``b_ln_n`` and ``g_ln_hd`` are read).
    stated_c : float
        The counting law's constant c (dimensionless) of the stated SDs, c / sqrt(N).
    bands : list
        The `noise_calibration` regions the stated SDs are scaled by
        (``spreadmap.metrics.noise.calibration_factors``).
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv``.
    floor : str or None, optional
        The floor the cells' cases ran on (spreadmap.case.substrate.floor_label).

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    from spreadmap.metrics.noise import calibration_factors
    fig = new_figure(10.5, 8.0)
    axes = fig.subplots(2, 2)
    rows = []
    for row, target in enumerate(COUNT):  # mfr, pd: the targets the law covers
        c, law = cells[target], laws[target]
        b, g = law.coefficient("b_ln_n"), law.coefficient("g_ln_hd")
        rel = np.sqrt(c["s2"]) / c["mean"]
        dof = c["dof"].to_numpy(float)
        lo_q, hi_q = stats.chi2.ppf(0.84, dof), stats.chi2.ppf(0.16, dof)
        band = np.column_stack([np.sqrt(dof / lo_q), np.sqrt(dof / hi_q)])
        to_n = (c["n"] / N_REF) ** (-b)
        to_hd = (c["h_over_d"] / HD_REF) ** (-g)
        panels = (("h_over_d", to_n, "h/d (nominal gap)"), ("n", to_hd, "N, spheres' worth counted"))
        for col, (x_col, scale, xlabel) in enumerate(panels):
            ax = axes[row, col]
            y = rel * scale
            for name, (_, marker, colour) in GROUPS.items():
                sel = c["source"].map(_group) == name
                if sel.any():
                    ax.errorbar(c.loc[sel, x_col], y[sel],
                                yerr=[y[sel] * (1 - band[sel.to_numpy(), 0]), y[sel] * (band[sel.to_numpy(), 1] - 1)],
                                fmt=marker, color=colour, ms=4, lw=0.6, alpha=0.75, label=f"{name} ({int(sel.sum())} cells)")
            grid = _grid(c, x_col, N_REF, HD_REF)
            fit = law.sd(grid)
            half = 1.96 * law.se_ln_sd(grid)
            ax.plot(grid[x_col], fit, color="k", lw=1.6, label="fitted law")
            ax.fill_between(grid[x_col], fit * np.exp(-half), fit * np.exp(half), color="k", alpha=0.15, lw=0,
                            label="95 % interval of the law")
            stated = stated_c / np.sqrt(grid["n"]) * calibration_factors(
                grid.assign(h_um=grid["h_over_d"], d_um=1.0), bands, target)
            ax.plot(grid[x_col], stated, color="grey", ls="--", lw=1.2,
                    label=f"stated {stated_c:g}/sqrt(N) x the hand bands" if bands else f"stated {stated_c:g}/sqrt(N)")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(xlabel)
            at = f"N = {N_REF:g}" if col == 0 else f"h/d = {HD_REF:g}"
            ax.set_ylabel(f"{target.upper()} seed SD / mean, scaled to {at}")
            ax.set_title(f"{target.upper()}: against {'h/d' if col == 0 else 'N'} "
                         f"(law: h/d^{g:.2f}, N^{b:.2f})", fontsize=10)
            if x_col == "h_over_d":
                ax.set_xticks([1, 1.5, 2, 3, 4, 6, 8], ["1", "1.5", "2", "3", "4", "6", "8"])
            ax.grid(True, which="both", alpha=0.2)
            rows.append(pd.DataFrame({"target": target, "panel": f"against {x_col}", "point": c["point"],
                                      "variant": c["variant"], "source": c["source"], "x": c[x_col], "y": y,
                                      "interval": 68, "y_lo": y * band[:, 0], "y_hi": y * band[:, 1]}))
            rows.append(pd.DataFrame({"target": target, "panel": f"against {x_col}", "point": "law", "variant": "",
                                      "source": "fit", "x": grid[x_col], "y": fit,
                                      "interval": 95, "y_lo": fit * np.exp(-half), "y_hi": fit * np.exp(half)}))
    axes[0, 0].legend(fontsize=7, loc="lower left")
    fig.suptitle("Seed-to-seed noise of one case against h/d and the count N: seed-repeat cells (68 % intervals) "
                 "and the fitted law (95 % band)", fontsize=10)
    return save_figure(fig, path_stem, pd.concat(rows, ignore_index=True), floor)
