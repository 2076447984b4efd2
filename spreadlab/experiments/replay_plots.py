"""The replay's figure (``replay``): what the stop rule's estimate says against the true map error,
how the true error falls with CPU per design, and, per tolerance, how often a stop is honest and
what it costs. Draws from the replay's tables only."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from spreadmap.figures import new_figure, save_figure


def plot_replay(paths: pd.DataFrame, honesty: pd.DataFrame, out: Path | str, shipped: str = "active_per_cpu"):
    """The replay's figure: four panels from the replay's tables.

    (a) the rule's estimate against the true error at every step of the ``shipped`` design; (b) the
    true MFR error against modelled CPU, median and 10-90 % over seeds, per design; (c) per
    tolerance, the share of honest stops with its 95 % interval (faint: the bare estimate, the
    shipped design's only; solid: with the margin); (d) the modelled CPU at the stop per tolerance,
    with the margin, median to p90.

    Parameters
    ----------
    paths : pandas.DataFrame
        ``replay.replay_one``'s tables of every replay.
    honesty : pandas.DataFrame
        ``replay.honesty``'s tables with ``tolerance`` (and, optionally, ``rule``) added (also the
        CSV saved).
    out : pathlib.Path or str
        Where to save: ``<out>.png``, ``.pdf`` and ``.csv``.
    shipped : str, optional
        The design drawn in panel (a) (the first design where it is missing).

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    import matplotlib.pyplot as plt

    designs = list(dict.fromkeys(paths["design"]))
    colours = dict(zip(designs, plt.cm.tab10(np.arange(len(designs)))))
    fig = new_figure(11, 8.5)
    ax = fig.subplots(2, 2)
    # (a) the rule's estimate against the true error, every step of the shipped design
    a = ax[0, 0]
    p = paths[paths["design"] == (shipped if shipped in designs else designs[0])]
    for t, m in (("mfr", "o"), ("pd", "s")):
        a.scatter(p[f"{t}_true"], p[f"{t}_estimate"], s=10, marker=m, alpha=0.5, label=t.upper())
    lim = [min(p[["mfr_true", "pd_true"]].min().min(), p[["mfr_estimate", "pd_estimate"]].min().min()) * 0.8,
           max(p[["mfr_true", "pd_true"]].max().max(), p[["mfr_estimate", "pd_estimate"]].max().max()) * 1.2]
    a.plot(lim, lim, "k-", lw=0.8, label="estimate = true")
    a.set(xscale="log", yscale="log", xlim=lim, ylim=lim, xlabel="true map error (RMS, worst grid)",
          ylabel="the rule's estimate (max of CV net of noise, posterior)",
          title=f"(a) estimate vs truth, every step, {p['design'].iloc[0]}")
    a.legend(fontsize=8)
    # (b) true MFR error against modelled CPU, median and 10-90 % over seeds, per design
    b = ax[0, 1]
    for d in designs:
        q = paths[paths["design"] == d]
        g = q.groupby("n").agg(cpu=("cpu_h_modelled", "median"), med=("mfr_true", "median"),
                               lo=("mfr_true", lambda x: np.quantile(x, 0.1)),
                               hi=("mfr_true", lambda x: np.quantile(x, 0.9)))
        b.plot(g["cpu"], g["med"], "-o", ms=3, color=colours[d], label=d)
        b.fill_between(g["cpu"], g["lo"], g["hi"], color=colours[d], alpha=0.15)
    b.set(xlabel="modelled CPU hours of the cases", ylabel="true MFR map error (RMS, worst grid)",
          yscale="log", title="(b) true MFR error per CPU hour (median, 10-90 %)")
    b.legend(fontsize=8)
    # (c) honesty per tolerance: the bare estimate (dashed) and with the margin (solid, held-out seeds)
    c = ax[1, 0]
    rules = list(dict.fromkeys(honesty["rule"])) if "rule" in honesty else [None]
    for k, rule in enumerate(rules):
        for j, d in enumerate(designs):
            if not k and len(rules) > 1 and d != shipped:
                continue  # the bare estimate: the shipped design's only, to keep the panel readable
            h = honesty[(honesty["design"] == d) & ((honesty["rule"] == rule) if rule else True)].sort_values("tolerance")
            x = h["tolerance"] * (1 + 0.012 * (j - len(designs) / 2))  # a little apart
            c.errorbar(x, h["honest_share"], yerr=[h["honest_share"] - h["honest_low"],
                                                   h["honest_high"] - h["honest_share"]],
                       fmt="-o" if k else "--s", ms=3, capsize=2, color=colours[d], alpha=1 if k else 0.45,
                       label=f"{d}, {rule}" if rule else d)
    c.axhline(0.9, color="k", ls="--", lw=0.8, label="goal 90 %")
    c.set(xlabel="tolerance (MFR and PD)", ylabel="share of stops with true error within tolerance",
          ylim=(0, 1.05), title="(c) honest stops (95 % CI); faint: no margin")
    c.legend(fontsize=6, ncol=1)
    # (d) CPU at the stop per tolerance
    e = ax[1, 1]
    for d in designs:
        h = honesty[(honesty["design"] == d) & ((honesty["rule"] == rules[-1]) if rules[-1] else True)].sort_values("tolerance")
        e.plot(h["tolerance"], h["cpu_h_median"], "-o", ms=4, color=colours[d], label=d)
        e.fill_between(h["tolerance"], h["cpu_h_median"], h["cpu_h_p90"], color=colours[d], alpha=0.12)
    e.set(xlabel="tolerance (MFR and PD)", ylabel="modelled CPU hours at the stop",
          title="(d) CPU at the stop, with the margin (median to p90)")
    e.legend(fontsize=8)
    return save_figure(fig, out, honesty)
