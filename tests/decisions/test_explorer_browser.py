"""The explorer page in a real browser: headless Chromium (Debian's package; tools/setup.sh installs
it) opens the page from disk, a mouse click moves a slider (and then a heat-map cell), and the
prediction the page displays must be the Python model's at that point.

The browser is driven over the DevTools protocol on a pipe (tests/browser.py): the clicks are the
browser's own input events, through plotly.js's slider code, so what is checked is what a person
sees. The expected numbers come from ``SurrogateModel.predict_stats`` at the point, computed here
from the design ranges, not from the page's data."""
import json
import re
import warnings

import numpy as np
import pytest
from browser import Chromium
from conftest import ROOT

from spreadmap.decisions import decision_config
from spreadmap.decisions.explorer import write_explorer
from spreadmap.surrogate import load_model
from spreadmap.surrogate.settings import map_config

MODEL = ROOT / "docs" / "study" / "surrogate" / "model.joblib"
GRID = {"n_f": 3, "n_d": 4, "n_h": 5, "n_v": 6}


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a scikit-learn version note on the committed model
        model = load_model(MODEL)
    dec = decision_config({"explorer": GRID, "draws": 64})
    path = tmp_path_factory.mktemp("explorer") / "explorer.html"
    write_explorer(model, dec, map_config({})["support"], path)
    return model, path


SLIDERS = """JSON.stringify(Array.from(document.querySelectorAll('.slider-group')).map(function (g) {
  return {label: g.querySelector(':scope > text.slider-label').textContent,
          ticks: Array.from(g.querySelectorAll('.slider-tick-rect')).map(function (r) {
            var b = r.getBoundingClientRect(); return b.left + b.width / 2; }),
          y: (function () { var b = g.querySelector('.slider-rail-rect').getBoundingClientRect();
                            return b.top + b.height / 2; })()}; }))"""

READOUT = """(function () { var D = explorer.data, S = explorer.state, gd = explorer.plot, IDX = explorer.traces;
  return JSON.stringify({point: document.getElementById('probe-point').textContent,
  values: Object.fromEntries(D.targets.map(function (t) { return [t, [
      +document.getElementById('mean-' + t).textContent, +document.getElementById('model-sd-' + t).textContent,
      +document.getElementById('run-sd-' + t).textContent]]; })),
  heat: Object.fromEntries(D.targets.map(function (t, k) {
      var tr = gd.data[IDX.mean[k]], sd = gd.data[IDX.sd[k]];
      return [t, [tr.z[S.hi][S.vi], sd.z[S.hi][S.vi], tr.customdata[S.hi][S.vi][1]]]; })),
  probe: [S.hi, S.vi]}); })()"""


def _axis(low, high, n):
    return np.linspace(low, high, n)


def _check(model, shown, point):
    """The read-out (4 decimals) and the heat maps' cell (6 significant digits) against Python."""
    expected = model.predict_stats(np.array([point]))
    for t, (mean, msd, rsd) in expected.items():
        want = np.array([mean[0], msd[0], rsd[0]])
        np.testing.assert_allclose(shown["values"][t], want, rtol=0, atol=5.1e-5, err_msg=f"read-out of {t}")
        np.testing.assert_allclose(shown["heat"][t], want, rtol=1e-5, atol=1e-9, err_msg=f"heat map of {t}")


def test_moving_a_slider_shows_the_python_models_prediction(page):
    model, path = page
    low, high = model.design_low, model.design_high
    f, d, h, v = (_axis(low[i], high[i], GRID[k]) for i, k in enumerate(("n_f", "n_d", "n_h", "n_v")))
    with Chromium(1440, 1300) as browser:
        browser.open(path.resolve().as_uri())
        browser.wait_for("window.explorerReady === true")
        before = browser.evaluate(READOUT)
        before = json.loads(before)
        # the page opens at the middle of each slider, the probe at the middle of the plane
        _check(model, before, [f[1], d[2], h[2], v[3]])
        sliders = json.loads(browser.evaluate(SLIDERS))
        diameter = next(s for s in sliders if s["label"].startswith("diameter"))
        browser.click(diameter["ticks"][0], diameter["y"])  # d to its first step
        browser.wait_for("document.getElementById('probe-point').textContent.indexOf('d = " + f"{d[0]:.3g}" + "') >= 0", 20)
        friction = next(s for s in json.loads(browser.evaluate(SLIDERS)) if s["label"].startswith("friction"))
        browser.click(friction["ticks"][2], friction["y"])  # f to its last step
        browser.wait_for("document.getElementById('probe-point').textContent.indexOf('f = " + f"{f[2]:.3f}" + "') >= 0", 20)
        after = json.loads(browser.evaluate(READOUT))
        labels = [s["label"] for s in json.loads(browser.evaluate(SLIDERS))]
        assert any(re.search(r"diameter.*= 10\b", s) for s in labels) and any("friction f = 0.45" in s for s in labels), labels
        _check(model, after, [f[2], d[0], h[2], v[3]])
        assert after["values"]["mfr"] != before["values"]["mfr"]  # the slider changed what is shown
        # a click on the MFR map's cell (h[1], v[4]) moves the probe there
        where = json.loads(browser.evaluate(
            "(function () { var gd = explorer.plot, L = gd._fullLayout, xa = L.xaxis, ya = L.yaxis, "
            "b = gd.getBoundingClientRect();"
            f" return JSON.stringify([b.left + xa._offset + xa.d2p({v[4]}), b.top + ya._offset + ya.d2p({h[1]})]); }})()"))
        browser.click(*where)
        browser.wait_for("explorer.state.hi === 1 && explorer.state.vi === 4", 20)
        clicked = json.loads(browser.evaluate(READOUT))
        assert clicked["probe"] == [1, 4]
        _check(model, clicked, [f[2], d[0], h[1], v[4]])
