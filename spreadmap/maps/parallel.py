"""Parallel coordinates of the DEM sample (no surrogate): one polyline per usable case over the four
parameters, coloured by normalised MFR (top) and PD (bottom), the best case drawn thick."""
from __future__ import annotations

from typing import Callable, Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib import colors as mcolors  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402

from .. import slices  # noqa: E402
from .. import targets as registry  # noqa: E402
from ..design import BY_NAME, NAMES, Design  # noqa: E402
from ..figures import save_figure  # noqa: E402
from ..table import usable_cases  # noqa: E402
from .style import MapResult  # noqa: E402
from .style import fmt as _fmt


def best_case(
    cases: pd.DataFrame,
    mfr_min: float = 0.0,
    score: Callable[[pd.DataFrame], np.ndarray] | None = None,
) -> pd.Series:
    """The best case of a table of (usable) cases.

    Default rule: the highest PD among the cases with MFR >= ``mfr_min`` (a dense layer from a
    setting that still flows). With ``score`` given, the case with the highest ``score(cases)``
    among those same cases.

    Parameters
    ----------
    cases : pandas.DataFrame
        Usable cases with ``mfr`` and ``pd``.
    mfr_min : float, optional
        The least MFR [-] a case needs to qualify.
    score : callable or None, optional
        ``score(cases) -> array`` of one value per case, higher better; None: PD.

    Returns
    -------
    pandas.Series
        The best case's row.

    Raises
    ------
    ValueError
        If no case has MFR >= `mfr_min`, or no qualifying case has a finite score.
    """
    ok = cases[cases["mfr"].to_numpy(float) >= mfr_min]
    if ok.empty:
        raise ValueError(f"no case has MFR >= {mfr_min}")
    value = np.asarray(score(ok), float) if score is not None else ok["pd"].to_numpy(float)
    if not np.isfinite(value).any():
        raise ValueError("no finite score")
    return ok.iloc[int(np.nanargmax(value))]


def parallel_coordinates(
    cases: pd.DataFrame,
    path_stem,
    mfr_min: float = 0.0,
    score: Callable[[pd.DataFrame], np.ndarray] | None = None,
    ranges: Design | Mapping | None = None,
    n_ticks: int = 5,
    floor: str | None = None,
) -> MapResult:
    """Parallel coordinates of a sample of DEM cases (the converged LDS sample).

    Only usable cases with finite MFR and PD (``table.usable_cases``) are drawn. Axes: the four parameters, each normalised to
    its design range and ticked in physical units. Top panel coloured by normalised MFR, bottom by
    normalised PD (min-max over the drawn cases; the colour bars give the physical values too).
    The best case (``best_case``: ``mfr_min`` and ``score``) is drawn thick red and annotated.

    Parameters
    ----------
    cases : pandas.DataFrame
        A results table.
    path_stem : pathlib.Path or str
        Where to save: ``<path_stem>.png``, ``.pdf`` and ``.csv``.
    mfr_min : float, optional
        The least MFR [-] of the best case.
    score : callable or None, optional
        The best case's score (``best_case``); None: PD.
    ranges : Design, mapping or None, optional
        The design space (``spreadmap.design.Design``, or the config's ``ranges``); None: the default ranges.
    n_ticks : int, optional
        Ticks per parameter axis.
    floor : str or None, optional
        The floor the cases ran on (``spreadmap.case.substrate.floor_label``), named on the figure
        and in the CSV.

    Returns
    -------
    MapResult
        ``paths`` (``png``, ``pdf``, ``csv``), ``data``: the drawn cases with their normalised
        values and a boolean column ``best``, and ``info`` (the best case).

    Raises
    ------
    ValueError
        If no case is usable, or none qualifies as the best (``best_case``).
    """
    data = usable_cases(cases, [t for t in registry.names("base") if t in cases]).copy()
    if data.empty:
        raise ValueError("no usable case to draw")
    best = best_case(data, mfr_min=mfr_min, score=score)
    design = Design.of(ranges)
    low, high = design.bounds()
    x = design.to_unit(data[list(NAMES)].to_numpy(float))
    for k, n in enumerate(NAMES):
        data[f"{n}_norm"] = x[:, k]
    for t in registry.names("base"):
        z = data[t].to_numpy(float)
        span = np.ptp(z)
        data[f"{t}_norm"] = (z - z.min()) / span if span > 0 else 0.5
    data["best"] = data.index == best.name
    xb = design.to_unit(best[list(NAMES)].to_numpy(float))

    xpos = np.arange(len(NAMES), dtype=float)
    fig, axes = plt.subplots(2, 1, figsize=(12, 8.5), sharex=True)
    cmap = plt.get_cmap("viridis")
    for ax, t in zip(axes, registry.names("base")):
        name = registry.short(t)
        c = data[f"{t}_norm"].to_numpy(float)
        order = np.argsort(c)  # high values drawn last, on top
        segs = [np.column_stack([xpos, row]) for row in x[order]]
        alpha = float(np.clip(8.0 / np.sqrt(len(data)), 0.15, 0.9))
        lc = LineCollection(segs, cmap=cmap, norm=mcolors.Normalize(0, 1), lw=1.0, alpha=alpha)
        lc.set_array(c[order])
        ax.add_collection(lc)
        ax.plot(xpos, xb, color="white", lw=5.5, zorder=5)
        ax.plot(xpos, xb, color="tab:red", lw=3.0, marker="o", ms=7, zorder=6,
                label="best case")
        for k, _n in enumerate(NAMES):
            ax.axvline(xpos[k], color="0.2", lw=1.0, zorder=3)
            for tv in np.linspace(0, 1, n_ticks):
                phys = low[k] + tv * (high[k] - low[k])
                ax.plot([xpos[k] - 0.02, xpos[k]], [tv, tv], color="0.2", lw=1.0, zorder=3)
                ax.text(xpos[k] - 0.03, tv, _fmt(phys), ha="right", va="center", fontsize=8,
                        bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7),
                        zorder=4)
        z = data[t].to_numpy(float)
        cb = fig.colorbar(plt.cm.ScalarMappable(norm=mcolors.Normalize(0, 1), cmap=cmap), ax=ax,
                          pad=0.02)
        cb.set_label(f"normalised {name} [-]\n(0 = {z.min():.3f}, 1 = {z.max():.3f})")
        ax.set_ylim(-0.06, 1.06)
        ax.set_yticks([])
        ax.set_xlim(-0.35, len(NAMES) - 1 + 1.25)  # right margin holds the best-case box
        ax.set_title(f"Cases coloured by normalised {name}", fontsize=10)
        point = "\n".join(slices.text({n: best[n] for n in NAMES[i:i + 2]}, 3) for i in range(0, len(NAMES), 2))
        text = (f"best case{': ' + str(best['case_id']) if 'case_id' in best else ''}\n{point}\n"
                f"MFR = {best['mfr']:.3f}, PD = {best['pd']:.3f}")
        ax.annotate(text, (xpos[-1], xb[-1]), xytext=(xpos[-1] + 0.2, 0.5), textcoords="data",
                    va="center", ha="left", fontsize=8.5, zorder=7,
                    bbox=dict(boxstyle="round", fc="white",
                              ec="tab:red", alpha=0.95),
                    arrowprops=dict(arrowstyle="-", color="tab:red"))
    axes[1].set_xticks(xpos, [BY_NAME[n].label for n in NAMES])
    rule = ("highest score" if score is not None else "highest PD") + (
        f" among cases with MFR >= {mfr_min:g}" if mfr_min > 0 else "")
    fig.suptitle(f"Parallel coordinates of {len(data)} DEM cases; best case = {rule}",
                 fontsize=11)
    fig.tight_layout()
    cols = [c for c in ("case_id", "sweep", "index") if c in data] + list(NAMES) + [
        *registry.names("base")] + [f"{n}_norm" for n in NAMES] + [f"{t}_norm" for t in registry.names("base")] + ["best"]
    table = data[cols].reset_index(drop=True)
    paths = save_figure(fig, path_stem, table, floor)
    return MapResult(paths, table, {"best": best})
