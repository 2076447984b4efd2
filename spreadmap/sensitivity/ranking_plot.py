"""Bar chart of a ranking table: per target, band width (left) and S1, ST (right) with their 95 %
intervals over the surrogate's draws, the ranks the draws resolve, and the noise share."""
from __future__ import annotations

import numpy as np

from ..design import BY_NAME, NAMES
from ..figures import new_figure, save_figure


def plot_ranking(table, stem, floor: str | None = None) -> dict:
    """One panel per target: each parameter's band width (left axis) and its S1 and ST (right
    axis) with their intervals, the ranks the draws resolve, and the noise share of one run.

    Parameters
    ----------
    table : pandas.DataFrame
        The ranking table of ``sensitivity`` (also the CSV saved).
    stem : pathlib.Path or str
        Where to save: ``<stem>.png``, ``.pdf`` and ``.csv``.
    floor : str or None, optional
        The floor the surrogate's cases ran on (spreadmap.case.substrate.floor_label).

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    targets = list(dict.fromkeys(table["target"]))
    fig = new_figure(5.4 * len(targets), 4.8)
    axes = np.atleast_1d(fig.subplots(1, len(targets)))
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
        ax.set_ylabel(f"band width of {t} [-]")
        ax2.set_ylabel("Sobol index [-]")
        ax2.set_ylim(min(0.0, float(np.nanmin(sub["S1_low"]))) - 0.02, max(1.0, float(np.nanmax(sub["ST_high"]))) + 0.02)
        ns = sub.iloc[0]
        ax.set_title(f"{t}: noise share of one run {ns['noise_share']:.2f} "
                     f"[{ns['noise_share_low']:.2f}, {ns['noise_share_high']:.2f}]\n"
                     f"(#: rank the draws resolve; a range = not separated)", fontsize=9)
        h1, l1 = ax.get_legend_handles_labels()
        h2, l2 = ax2.get_legend_handles_labels()
        ax.legend(h1 + h2, l1 + l2, loc="upper right", fontsize=7.5)
    return save_figure(fig, stem, table, floor)
