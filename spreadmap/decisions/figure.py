"""The decisions figure: per powder, the probability of meeting every bound over the machine's
(h, v) plane, the confidence contour, the settings beyond the data hatched, and the recommended
fastest and best-quality settings marked (open marks: beyond the data, not recommended)."""
from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.patches import Patch

from ..design import BY_NAME
from ..figures import new_figure, save_figure
from ..maps.style import HATCH, support_rule
from ..targets import short

MARKS = {"fastest": dict(marker="^", color="#d62728", label="fastest"),
         "best_quality": dict(marker="*", color="#1f77b4", label="best quality")}


def _cell_edges(values: np.ndarray) -> np.ndarray:
    mid = (values[1:] + values[:-1]) / 2
    return np.concatenate([[values[0] - (mid[0] - values[0])], mid, [values[-1] + (values[-1] - mid[-1])]])


def bounds_text(bounds: dict) -> str:
    parts = []
    for t, b in bounds.items():
        name = short(t)
        if "min" in b and "max" in b:
            parts.append(f"{b['min']:g} <= {name} <= {b['max']:g}")
        elif "min" in b:
            parts.append(f"{name} >= {b['min']:g}")
        else:
            parts.append(f"{name} <= {b['max']:g}")
    return ", ".join(parts)


def decision_figure(grids: dict, table: pd.DataFrame, powders, dec: dict, support: dict, stem,
                    floor: str | None = None):
    """Draw and save (PNG, PDF, and the grids as CSV) the probability maps with the recommendations.

    Parameters
    ----------
    grids : dict of str to pandas.DataFrame
        Powder name -> ``feasibility`` frame (the second value of ``recommendations``).
    table : pandas.DataFrame
        ``recommendations``' table.
    powders : sequence of Powder
        The powders, one panel each, in this order (``powders_from_config``).
    dec : dict
        The ``decisions:`` config with defaults (``confidence``, ``about`` and ``bounds`` are
        read).
    support : dict
        The maps' support rule (``map_config(...)["support"]``), stated in the title.
    stem : pathlib.Path or str
        Where to save: ``<stem>.png``, ``.pdf`` and ``.csv``.
    floor : str or None, optional
        The floor the surrogate's cases were spread on (spreadmap.case.substrate.floor_label).

    Returns
    -------
    dict of str to pathlib.Path
        The files written, keyed ``png``, ``pdf``, ``csv`` (``figures.save_figure``).
    """
    n = len(powders)
    cols = min(n, 3)
    rows = -(-n // cols)
    fig = new_figure(4.3 * cols + 1.0, 3.9 * rows + 0.9)
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    mesh = None
    for ax, powder in zip(axes, powders):
        grid = grids[powder.name]
        h, v = np.unique(grid["h_um"]), np.unique(grid["v_mm_s"])
        P = grid["probability"].to_numpy().reshape(len(h), len(v))
        beyond = grid["beyond_data"].to_numpy(bool).reshape(len(h), len(v))
        mesh = ax.pcolormesh(_cell_edges(v), _cell_edges(h), P, cmap="viridis", vmin=0, vmax=1, shading="flat")
        if P.min() < dec["confidence"] <= P.max():
            ax.contour(v, h, P, levels=[dec["confidence"]], colors="k", linewidths=1.4, linestyles="--")
        ev, eh = _cell_edges(v), _cell_edges(h)
        for i, j in zip(*np.nonzero(beyond)):
            ax.fill_between([ev[j], ev[j + 1]], eh[i], eh[i + 1], **{**HATCH, "edgecolor": "0.5"})
        mine = table[table["powder"] == powder.name]
        for _, row in mine.iterrows():
            style = MARKS[row["kind"]]
            if row["status"] == "none_meets":
                continue
            filled = bool(row["recommended"])
            ax.plot(row["v_mm_s"], row["h_um"], ls="none", marker=style["marker"], ms=13 if style["marker"] == "*" else 10,
                    mfc=style["color"] if filled else "none", mec="white" if filled else style["color"], mew=1.5,
                    zorder=5)
            ax.annotate(f"{row['probability']:.2f}", (row["v_mm_s"], row["h_um"]),
                        xytext=(6, -12 if row["kind"] == "fastest" else 6),
                        textcoords="offset points", fontsize=8, color="white", zorder=6,
                        bbox=dict(boxstyle="round,pad=0.15", fc=style["color"], ec="none", alpha=0.85))
        status = set(mine["status"])
        title = powder.label()
        if "none_meets" in status:
            best = float(mine["best_probability_in_data"].iloc[0])
            title += f"\nno setting reaches {dec['confidence']:g}: best P {best:.2f}"
        elif "beyond_data_only" in status:
            title += f"\nP >= {dec['confidence']:g} only beyond the data"
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(BY_NAME["v_mm_s"].label)
        ax.set_ylabel(BY_NAME["h_um"].label)
    for ax in axes[n:]:
        ax.set_visible(False)
    fig.colorbar(mesh, ax=axes[:n].tolist(), label=("P(a new run meets every bound)" if dec["about"] == "run"
                                                    else "P(the mean meets every bound)"), shrink=0.9)
    handles = [axes[0].plot([], [], ls="none", marker=s["marker"], mfc=s["color"], mec="white", ms=10, label=s["label"])[0]
               for s in MARKS.values()]
    handles.append(axes[0].plot([], [], color="k", lw=1.4, ls="--", label=f"P = {dec['confidence']:g}")[0])
    handles.append(Patch(**{**HATCH, "edgecolor": "0.5"}, label="beyond the data"))
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=8, frameon=False)
    fig.suptitle(f"Where the layer meets {bounds_text(dec['bounds'])} (confidence {dec['confidence']:g}; "
                 f"{'a new run: mean + noise' if dec['about'] == 'run' else 'the mean function'})\n"
                 f"hatched, never recommended (open marks): {support_rule(support)}", fontsize=9)
    data = pd.concat([g.assign(powder=name) for name, g in grids.items()], ignore_index=True)
    return save_figure(fig, stem, data, floor)
