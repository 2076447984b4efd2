"""Saving figures: every figure as PNG (for eyes and reports) and PDF (vector, for papers), with
the numbers behind it as CSV beside it."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402


def new_figure(width: float, height: float) -> Figure:
    """A constrained-layout figure on its own Agg canvas: no pyplot state, safe in parallel jobs."""
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path_stem, data: pd.DataFrame) -> dict[str, Path]:
    """Save ``fig`` as ``<path_stem>.png`` and ``.pdf`` and ``data`` as ``<path_stem>.csv``.

    Parent directories are created; the figure is closed. Returns ``{"png", "pdf", "csv"}``.
    """
    stem = Path(path_stem)
    if stem.suffix.lower() in (".png", ".pdf", ".csv"):
        stem = stem.with_suffix("")
    stem.parent.mkdir(parents=True, exist_ok=True)
    paths = {ext: stem.parent / f"{stem.name}.{ext}" for ext in ("png", "pdf", "csv")}
    try:
        fig.savefig(paths["png"], dpi=150, bbox_inches="tight")
        fig.savefig(paths["pdf"], bbox_inches="tight", metadata={"CreationDate": None})
    finally:
        plt.close(fig)
    pd.DataFrame(data).to_csv(paths["csv"], index=False)
    return paths
