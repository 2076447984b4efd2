"""The figures of the two floors' comparison (numbers from spreadlab.floors)."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.ticker import NullFormatter  # noqa: E402

from spreadmap.figures import save_figure  # noqa: E402
from spreadmap.maps.style import HATCH  # noqa: E402
from spreadmap.targets import short  # noqa: E402


def plot_ratio_box(table: pd.DataFrame, targets, stem, names: tuple[str, str], hollow_d: float | None = None) -> dict:
    """Per target a panel: each box point's ratio (median, 95 % interval) against h/d, coloured by f.

    Points where the ratio is not defined (floor B may read nothing) are marked on the top edge.
    With ``hollow_d`` the ratio the effective gap alone would give, (h/d + hollow_d) / (h/d), is
    drawn too.

    Parameters
    ----------
    table : pandas.DataFrame
        ``spreadlab.floors.compare``'s table over the box (also the CSV saved).
    targets : sequence of str
        The targets, one panel each.
    stem : pathlib.Path or str
        Where to save: ``<stem>.png``, ``.pdf`` and ``.csv``.
    names : tuple of (str, str)
        The names of floor A and floor B, for the labels.
    hollow_d : float or None, optional
        Floor A's mean hollow depth [d] (``spreadmap.case.substrate.mean_hollow_depth``); None: no
        effective-gap curve.

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    fig, axes = plt.subplots(1, len(targets), figsize=(5.2 * len(targets), 4.2), squeeze=False)
    hd = np.linspace(table["h_over_d"].min(), table["h_over_d"].max(), 200)
    for ax, t in zip(axes[0], targets):
        ok = table[table[f"{t}_ratio_defined"]]
        bad = table[~table[f"{t}_ratio_defined"]]
        ax.vlines(ok["h_over_d"], ok[f"{t}_ratio_lo"], ok[f"{t}_ratio_hi"], color="0.75", lw=0.6, zorder=1)
        sc = ax.scatter(ok["h_over_d"], ok[f"{t}_ratio"], c=ok["f"], cmap="viridis", s=10, zorder=2)
        ax.axhline(1.0, color="black", lw=0.8)
        if hollow_d is not None:
            ax.plot(hd, (hd + hollow_d) / hd, color="tab:red", lw=1.2,
                    label=f"effective gap alone: (h/d + {hollow_d:.2f}) / (h/d)")
            ax.legend(loc="upper right", fontsize=8, frameon=False)
        top = float(np.nanmax(ok[f"{t}_ratio_hi"])) if len(ok) else 2.0
        ax.set_ylim(0.0, min(top * 1.05, 12.0))
        if len(bad):
            ax.plot(bad["h_over_d"], np.full(len(bad), ax.get_ylim()[1] * 0.98), "x", color="tab:red", ms=4,
                    label=f"{names[1]} may read ~0: no ratio ({len(bad)})")
            ax.legend(loc="upper right", fontsize=8, frameon=False)
        ax.set_xscale("log")
        ax.set_xticks([1, 1.5, 2, 3, 5, 7])
        ax.set_xticklabels(["1", "1.5", "2", "3", "5", "7"])
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("gap / particle diameter h/d [-] (nominal)")
        ax.set_ylabel(f"{short(t)} on {names[0]} / on {names[1]} [-]")
        ax.set_title(f"{short(t)}: {names[0]} over {names[1]}, {len(table)} points of the box\n"
                     "median and 95 % interval of the ratio of the two map means", fontsize=9)
        fig.colorbar(sc, ax=ax, label="friction f [-]")
    fig.tight_layout()
    return save_figure(fig, stem, table)


def plot_side_by_side(grid: pd.DataFrame, targets, stem, names: tuple[str, str], fixed: str) -> dict:
    """Rows: targets; columns: the target on floor A, on floor B (same colour scale) and A / B.

    Over a (d, h) plane of ``grid`` (the other two parameters fixed, named in ``fixed``). The ratio
    is hatched where it is not defined or its 95 % interval holds 1.

    Parameters
    ----------
    grid : pandas.DataFrame
        ``spreadlab.floors.compare``'s table over a (d, h) grid (also the CSV saved).
    targets : sequence of str
        The targets, one row of panels each.
    stem : pathlib.Path or str
        Where to save: ``<stem>.png``, ``.pdf`` and ``.csv``.
    names : tuple of (str, str)
        The names of floor A and floor B, for the titles.
    fixed : str
        The fixed parameters in words, for the title (e.g. "f = 0.3, v = 10 mm/s").

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    d = np.sort(grid["d_um"].unique())
    h = np.sort(grid["h_um"].unique())

    def field(col):
        return grid.pivot_table(index="h_um", columns="d_um", values=col, dropna=False).loc[h, d].to_numpy(float)

    fig, axes = plt.subplots(len(targets), 3, figsize=(13.5, 3.6 * len(targets)), squeeze=False)
    for row, t in zip(axes, targets):
        a, b = field(f"{t}_a"), field(f"{t}_b")
        vmin, vmax = float(np.nanmin([a, b])), float(np.nanmax([a, b]))
        for ax, values, name in ((row[0], a, names[0]), (row[1], b, names[1])):
            cs = ax.contourf(d, h, values, levels=np.linspace(vmin, vmax, 13), cmap="viridis")
            ax.contour(d, h, values, levels=cs.levels[::2], colors="white", linewidths=0.5)
            fig.colorbar(cs, ax=ax, label=f"{short(t)} [-]", format="%.2f")
            ax.set_title(f"{short(t)} on {name}", fontsize=10)
        ratio = field(f"{t}_ratio")
        unsure = ~grid.pivot_table(index="h_um", columns="d_um", values=f"{t}_ratio_defined").loc[h, d].to_numpy(bool)
        holds_one = (field(f"{t}_ratio_lo") <= 1.0) & (field(f"{t}_ratio_hi") >= 1.0)
        finite = ratio[np.isfinite(ratio)]
        lo = min(1.0, float(finite.min())) if finite.size else 1.0
        hi = max(float(np.percentile(finite, 98)) if finite.size else 2.0, lo + 0.05)
        cs = row[2].contourf(d, h, np.clip(ratio, None, hi), levels=np.linspace(lo, hi, 13), cmap="magma_r")
        fig.colorbar(cs, ax=row[2], label=f"{short(t)} ratio [-]", format="%.2f")
        row[2].contourf(d, h, (unsure | holds_one).astype(float), levels=[0.5, 1.5], **HATCH)
        row[2].set_title(f"{short(t)}: {names[0]} / {names[1]}\nhatched: 1 inside the 95 % interval, or no ratio",
                         fontsize=9)
        for ax in row:
            ax.set_xlabel("particle diameter d [um]")
            ax.set_ylabel("layer thickness h [um] (nominal)")
    fig.suptitle(f"Both floors' maps at {fixed}", fontsize=11)
    fig.tight_layout()
    return save_figure(fig, stem, grid)
