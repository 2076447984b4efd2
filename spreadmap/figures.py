"""Saving figures: every figure as PNG (for eyes and reports) and PDF (vector, for papers), with
the numbers behind it as CSV beside it; a figure of DEM results (or of a model of them) names
the floor they were measured on (spreadmap.case.substrate.floor_label) above its title and in a
`floor` column of its CSV."""
from __future__ import annotations

import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from .files import atomic_path, write_text_atomically  # noqa: E402

N_LABEL = "number of cases N [-]"  # the x axis of every figure against the number of cases


def new_figure(width: float, height: float) -> Figure:
    """A constrained-layout figure on its own Agg canvas: no pyplot state, safe in parallel jobs."""
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def floor_note(fig, floor: str) -> None:
    """Write the floor (and the gap it implies) as a line above everything else on the figure."""
    fig.text(0.5, 1.0, textwrap.fill(floor, 110, break_long_words=False), ha="center", va="bottom", fontsize=9,
             color="0.15")


def save_figure(fig, path_stem, data: pd.DataFrame, floor: str | None = None) -> dict[str, Path]:
    """Save ``fig`` as ``<path_stem>.png`` and ``.pdf`` and ``data`` as ``<path_stem>.csv``.

    With ``floor`` (spreadmap.case.substrate.floor_label) the figure names it above its title and the
    CSV gets it as a last column, ``floor``. Parent directories are created; the figure is closed.
    Returns ``{"png", "pdf", "csv"}``.
    """
    if floor:
        floor_note(fig, floor)
        data = pd.DataFrame(data).assign(floor=floor)
    stem = Path(path_stem)
    if stem.suffix.lower() in (".png", ".pdf", ".csv"):
        stem = stem.with_suffix("")
    stem.parent.mkdir(parents=True, exist_ok=True)
    paths = {ext: stem.parent / f"{stem.name}.{ext}" for ext in ("png", "pdf", "csv")}
    try:  # each file written beside its target and renamed over it (spreadmap.files): never a partial figure
        with atomic_path(paths["png"]) as tmp:
            fig.savefig(tmp, format="png", dpi=150, bbox_inches="tight")
        with atomic_path(paths["pdf"]) as tmp:
            fig.savefig(tmp, format="pdf", bbox_inches="tight", metadata={"CreationDate": None})
    finally:
        plt.close(fig)
    write_text_atomically(paths["csv"], pd.DataFrame(data).to_csv(index=False))
    return paths
