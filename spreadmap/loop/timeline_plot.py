"""The run's timeline drawn: one bar per job on the core it ran on, coloured by kind, with the core
time by kind and the idle time written beside it (numbers: spreadmap.loop.timeline)."""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from ..figures import new_figure, save_figure

COLOURS = {"DEM case": "tab:blue", "loop step": "tab:orange", "analysis": "tab:green"}


def draw_timeline(placed: pd.DataFrame, summary: dict, path_stem: Path | str, title: str,
                  floor: str | None = None) -> dict:
    """Draw the jobs on their lanes against minutes from the run's start; save PNG, PDF and CSV.

    Parameters
    ----------
    placed : pandas.DataFrame
        ``spreadmap.loop.timeline.place_on_cores``' table.
    summary : dict
        ``spreadmap.loop.timeline.core_time``'s numbers, written on the figure.
    path_stem : pathlib.Path or str
        Where to save (``<stem>.png``, ``.pdf``, ``.csv``).
    title : str
        The figure's title.
    floor : str or None, optional
        The floor and powder the cases ran with, named above the title.

    Returns
    -------
    dict
        The paths written (``spreadmap.figures.save_figure``).
    """
    t0 = placed["start"].min()
    data = placed.assign(start_min=(placed["start"] - t0).dt.total_seconds() / 60.0,
                         end_min=(placed["end"] - t0).dt.total_seconds() / 60.0)
    working = data[data["lane"] >= 0]
    lanes = int(working["lane"].max() + 1) if len(working) else 1
    fig = new_figure(11.0, 1.6 + 0.55 * lanes)
    ax = fig.add_subplot(1, 1, 1)
    for kind, colour in COLOURS.items():
        part = working[working["kind"] == kind]
        if len(part):
            ax.barh(part["lane"], part["end_min"] - part["start_min"], left=part["start_min"], height=0.8,
                    color=colour, edgecolor="white", linewidth=0.4, label=kind)
    ax.set_yticks(range(lanes), [f"core {i + 1}" for i in range(lanes)])
    ax.invert_yaxis()
    ax.set_xlabel("wall time from the run's first job [min]")
    ax.set_xlim(0, max(1.0, data["end_min"].max()))
    wall = summary["wall_s"]
    text = (f"wall {wall / 60:.1f} min on {summary['cores']} cores; core time: DEM cases {summary['DEM_case_s'] / 60:.1f} min, "
            f"loop steps {summary['loop_step_s'] / 60:.1f} min, analyses {summary['analysis_s'] / 60:.1f} min, "
            f"idle {summary['idle_s'] / 60:.1f} min ({summary['idle_share']:.0%})")
    ax.set_title(f"{title}\n{text}", fontsize=9)
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8, frameon=False)
    columns = ["jobid", "rule", "kind", "wildcards", "lane", "start_min", "end_min", "seconds", "finished"]
    return save_figure(fig, path_stem, data[columns], floor=floor)
