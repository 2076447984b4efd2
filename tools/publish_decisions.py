"""Publish the decisions on the study's committed surrogate (docs/study/surrogate/model.joblib) with
the shipped config's `decisions:` and `maps.support`: docs/decisions/recommendations.csv, the figure
probability.png (+ .pdf, .csv) and a screenshot of the explorer page (explorer.png, by headless
Chromium; the page itself, ~9 MB, is written to a temporary folder and not kept).

    .venv/bin/python tools/publish_decisions.py
"""
import subprocess
import tempfile
from pathlib import Path

from spreadmap import config as spreadmap_config
from spreadmap.case.substrate import floor_label
from spreadmap.decisions import decision_config, powders_from_config, recommendations
from spreadmap.decisions.explorer import write_explorer
from spreadmap.decisions.figure import decision_figure
from spreadmap.files import write_text_atomically
from spreadmap.surrogate import load_model
from spreadmap.surrogate.settings import map_config

ROOT = Path(__file__).resolve().parent.parent

OUT = ROOT / "docs" / "decisions"


def screenshot(html: Path, png: Path, width: int = 1440, height: int = 1200) -> None:
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run(["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                        "--disable-component-update", "--disable-sync", "--no-first-run", "--hide-scrollbars",
                        f"--user-data-dir={profile}", f"--window-size={width},{height}", "--virtual-time-budget=20000",
                        f"--screenshot={png}", html.resolve().as_uri()], check=True, capture_output=True, timeout=180)


def main() -> None:
    config = spreadmap_config.load(ROOT / "config.yaml")
    dec = decision_config(config["decisions"])
    support = map_config(config["maps"])["support"]
    model = load_model(ROOT / "docs" / "study" / "surrogate" / "model.joblib")
    floor = floor_label(spreadmap_config.load(ROOT / "docs" / "study" / "config.yaml"))  # the floor the model's cases ran on
    table, grids = recommendations(model, dec, support)
    decision_figure(grids, table, powders_from_config(dec), dec, support, OUT / "probability", floor)
    write_text_atomically(OUT / "recommendations.csv", table.assign(floor=floor).to_csv(index=False))
    for note in table["powder"] + ": " + table["note"]:
        print(note)
    with tempfile.TemporaryDirectory() as tmp:
        html = Path(tmp) / "explorer.html"
        write_explorer(model, dec, support, html, floor=floor)
        screenshot(html, OUT / "explorer.png")


if __name__ == "__main__":
    main()
