"""Bar chart of a ranking table: per target, band width (left) and S1, ST (right) with their 95 %
intervals over the surrogate's draws, the ranks the draws resolve, and the noise share."""
from __future__ import annotations

import numpy as np

from ..design import BY_NAME, NAMES
from ..figures import new_figure, save_figure
from ..targets import short


def plot_ranking(table, stem, floor: str | None = None, columns: int = 3) -> dict:
    """One panel per target, in a grid of at most `columns` panels a row: each parameter's band
    width (left axis) and its S1 and ST (right axis) with their intervals, the ranks the draws
    resolve, and the noise share of one run; one legend for all.

    Parameters
    ----------
    table : pandas.DataFrame
        The ranking table of ``sensitivity`` (also the CSV saved).
    stem : pathlib.Path or str
        Where to save: ``<stem>.png``, ``.pdf`` and ``.csv``.
    floor : str or None, optional
        The floor the surrogate's cases ran on (spreadmap.case.substrate.floor_label).
    columns : int, optional
        Panels a row at most (3: six targets are 1,950 px wide at the 150 dpi of ``save_figure``).

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    targets = list(dict.fromkeys(table["target"]))
    ncols = max(1, min(int(columns), len(targets)))
    nrows = -(-len(targets) // ncols)
    fig = new_figure(4.3 * ncols, 3.7 * nrows + 0.5)
    axes = np.atleast_1d(fig.subplots(nrows, ncols, squeeze=False)).ravel()
    for ax in axes[len(targets):]:  # a last row not full: its empty panels go
        ax.remove()
    for ax, t in zip(axes, targets):
        sub = table[table["target"] == t].set_index("parameter").loc[list(NAMES)]
        x = np.arange(len(sub))
        w = 0.27
        ax2 = ax.twinx()
        err = np.vstack([sub["band"] - sub["band_low"], sub["band_high"] - sub["band"]]).clip(0)
        ax.bar(x - w, sub["band"], w, yerr=err, capsize=3, color="0.6", label="band width (left axis)")
        for off, col, colour in ((0.0, "S1", "tab:blue"), (w, "ST", "tab:red")):
            e = np.vstack([sub[col] - sub[f"{col}_low"], sub[f"{col}_high"] - sub[col]])
            e = np.where(np.isfinite(e), np.clip(e, 0, None), 0.0)
            ax2.bar(x + off, sub[col], w, yerr=e, capsize=3, color=colour, label=f"{col} (right axis)")
        ax.set_xticks(x, [f"{BY_NAME[p].symbol}\nband #{rb}\nST #{r}" for p, rb, r in
                          zip(sub.index, sub["rank_band"], sub["rank_ST"])])
        ax.set_ylabel(f"band width of {short(t)} [-]")
        ax2.set_ylabel("Sobol index [-]")
        ax2.set_ylim(min(0.0, float(np.nanmin(sub["S1_low"]))) - 0.02, max(1.0, float(np.nanmax(sub["ST_high"]))) + 0.02)
        ns = sub.iloc[0]
        ax.set_title(f"{short(t)}: noise share of one run {ns['noise_share']:.2f} "
                     f"[{ns['noise_share_low']:.2f}, {ns['noise_share_high']:.2f}]", fontsize=9)
    h1, l1 = axes[0].get_legend_handles_labels()
    h2, l2 = fig.axes[-1].get_legend_handles_labels()  # the last twin axes: S1 and ST
    fig.legend(h1 + h2, l1 + l2, loc="outside lower center", ncols=3, fontsize=8, frameon=False)
    fig.suptitle("Ranking of the parameters over the surrogate's draws (95 % intervals); "
                 "#: the rank the draws resolve, a range = not separated", fontsize=10)
    return save_figure(fig, stem, table, floor)
