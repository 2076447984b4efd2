"""The explorer page: one self-contained HTML file to explore the 4-D map by hand.

Heat maps over the (v, h) plane, one pair per target: the posterior mean and the model SD (what
the map does not know; the hover and the read-out add the SD of one new run). Two sliders set the
parameters not on the axes, friction f and diameter d. Settings beyond the data (the maps' rule,
``maps.support``) are shaded grey; the DEM cases of the slider's (f, d) cell are drawn as circles;
the recommended region (probability of meeting the ``decisions.bounds`` at least the confidence,
within the data: ``feasibility``) is outlined. Clicking a cell moves the read-out's probe.

Plotted with plotly (plotly.py writing plotly.js): a well-kept library (Plotly's, MIT licence,
released with plotly.js monthly) that writes one HTML file with its JavaScript inlined, so the
page opens from disk without a server or network, and that has sliders of its own. The model is
evaluated in Python at every grid point of the sliders and axes (``SurrogateModel.predict_stats``,
6 significant digits) and the numbers are embedded as JSON; a plotly slider step then swaps the
traces' data (two sliders combine, which plain slider steps cannot, so their ``plotly_sliderchange``
events drive a few lines of script). What the page shows at a slider position is therefore the
Python model at that point, not an interpolation.
"""
from __future__ import annotations

import html
import json

import numpy as np
import pandas as pd

from .. import slices
from ..design import NAMES
from ..files import write_text_atomically
from ..maps import grids
from ..maps.style import support_rule
from ..targets import axis_label, short
from .feasibility import Powder, feasibility
from .figure import bounds_text

COLUMNS = 3
# the page's four axes: sliders over a powder (the powder maps' f, d), heat maps over the machine's
# settings (the decisions' slice, h, v); any other axis at its nominal value
EXPLORED = (*slices.POWDER.varying, *slices.DECISIONS.varying)
DIGITS = 6


def _round(values) -> list:
    return [float(f"{x:.{DIGITS}g}") for x in np.asarray(values, float).ravel()]


def explorer_data(model, dec: dict, support: dict) -> dict:
    """Everything the page shows, on the slider and axis grids (flat arrays ordered f, d, h, v)."""
    ex = dec["explorer"]
    low, high = np.asarray(model.design_low, float), np.asarray(model.design_high, float)
    axis = {n: np.linspace(low[NAMES.index(n)], high[NAMES.index(n)], ex[slices.size_key(n)]) for n in EXPLORED}
    frame = grids.grid_frame(**axis)  # any other axis at its nominal value
    targets = list(model.targets)
    ev = grids.evaluate(model, frame, targets, support)
    fs, ds, hs, vs = (axis[n] for n in EXPLORED)
    region, prob = [], []
    for f in fs:
        for d in ds:
            grid = feasibility(model, Powder("slider", (f, f), (d, d)), hs, vs, dec["bounds"], dec["quality"],
                               support, dec["about"], dec["draws"], dec["seed"], 2)
            prob.append(grid["probability"].to_numpy())
            region.append((grid["probability"].to_numpy() >= dec["confidence"]) & ~grid["beyond_data"].to_numpy(bool))
    cases = np.asarray(model.train_X, float)
    half_f = (fs[1] - fs[0]) / 2 if len(fs) > 1 else np.inf
    half_d = (ds[1] - ds[0]) / 2 if len(ds) > 1 else np.inf
    cf, cd = (cases[:, NAMES.index(n)] for n in slices.POWDER.varying)
    near = [[int(k) for k in np.nonzero((np.abs(cf - f) <= half_f) & (np.abs(cd - d) <= half_d))[0]]
            for f in fs for d in ds]
    return {"targets": targets, "labels": {t: axis_label(t) for t in targets},
            "short": {t: short(t) for t in targets},
            "f": fs.tolist(), "d": ds.tolist(), "h": hs.tolist(), "v": vs.tolist(),
            "mean": {t: _round(ev[t]) for t in targets}, "model_sd": {t: _round(ev[f"{t}_model_sd"]) for t in targets},
            "run_sd": {t: _round(ev[f"{t}_run_sd"]) for t in targets},
            "beyond": (~ev["supported"].to_numpy(bool)).astype(int).tolist(),
            "probability": _round(np.concatenate(prob)), "region": np.concatenate(region).astype(int).tolist(),
            "cases": {**{k: cases[:, NAMES.index(dict(zip("fdhv", EXPLORED))[k])].tolist() for k in "hvfd"}, "near": near},
            "confidence": dec["confidence"], "about": dec["about"], "bounds_text": bounds_text(dec["bounds"]),
            "support_text": support_rule(support)}


def _slice(data: dict, flat, i: int, j: int) -> np.ndarray:
    nh, nv = len(data["h"]), len(data["v"])
    per = nh * nv
    start = (i * len(data["d"]) + j) * per
    return np.asarray(flat[start:start + per], float).reshape(nh, nv)


def explorer_figure(data: dict, i: int, j: int):
    """The plotly figure at slider position (i, j) of f and d, and the trace indices the page's
    script updates (kind -> list of trace indices; ``mean`` and ``sd`` in target order)."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    targets = data["targets"]
    blocks = -(-len(targets) // COLUMNS)
    titles = []
    for b in range(blocks):
        group = targets[b * COLUMNS:(b + 1) * COLUMNS]
        titles += [f"{data['short'][t]}: mean" for t in group] + [""] * (COLUMNS - len(group))
        titles += [f"{data['short'][t]}: model SD" for t in group] + [""] * (COLUMNS - len(group))
    fig = make_subplots(rows=2 * blocks, cols=COLUMNS, subplot_titles=titles, horizontal_spacing=0.08,
                        vertical_spacing=0.07 if blocks > 1 else 0.12)
    v, h = data["v"], data["h"]
    beyond = np.where(_slice(data, data["beyond"], i, j) > 0, 1.0, np.nan)
    region = _slice(data, data["region"], i, j)
    near = data["cases"]["near"][i * len(data["d"]) + j]
    index = {"mean": [], "sd": [], "beyond": [], "cases": [], "region": [], "probe": []}
    hover = ("v %{x:.3g} mm/s, h %{y:.3g} um<br>mean %{z:.4f}<br>model SD %{customdata[0]:.4f}"
             "<br>new run SD %{customdata[1]:.4f}<extra>%{meta}</extra>")
    grey = [[0, "rgba(110,110,110,0.55)"], [1, "rgba(110,110,110,0.55)"]]
    for k, t in enumerate(targets):
        row, col = 2 * (k // COLUMNS) + 1, k % COLUMNS + 1
        mean, msd, rsd = (_slice(data, data[key][t], i, j) for key in ("mean", "model_sd", "run_sd"))
        for r, kind, z, scale in ((row, "mean", mean, "Viridis"), (row + 1, "sd", msd, "Magma")):
            allz = np.asarray(data["mean" if kind == "mean" else "model_sd"][t], float)
            xaxis = fig.get_subplot(r, col).xaxis
            yaxis = fig.get_subplot(r, col).yaxis
            bar = dict(x=xaxis.domain[1] + 0.003, y=sum(yaxis.domain) / 2, len=yaxis.domain[1] - yaxis.domain[0],
                       thickness=9, tickfont=dict(size=9))
            # colours fixed over all slider positions; the SD's top 2 % saturate (corners beyond the data)
            top = float(allz.max()) if kind == "mean" else float(np.quantile(allz, 0.98))
            fig.add_trace(go.Heatmap(x=v, y=h, z=z, customdata=np.dstack([msd, rsd]), zmin=float(allz.min()),
                                     zmax=top, colorscale=scale, colorbar=bar, hovertemplate=hover,
                                     meta=data["short"][t]), row=r, col=col)
            index[kind].append(len(fig.data) - 1)
            fig.add_trace(go.Heatmap(x=v, y=h, z=beyond, colorscale=grey, showscale=False, hoverinfo="skip",
                                     name="beyond the data", showlegend=False), row=r, col=col)
            index["beyond"].append(len(fig.data) - 1)
            if kind == "mean":
                fig.add_trace(go.Contour(x=v, y=h, z=region, showscale=False, hoverinfo="skip",
                                         contours=dict(start=0.5, end=0.5, size=1, coloring="none"),
                                         line=dict(color="#ff2bd6", width=3), name="recommended region",
                                         showlegend=False), row=r, col=col)
                index["region"].append(len(fig.data) - 1)
                fig.add_trace(go.Scatter(x=[data["cases"]["v"][n] for n in near], y=[data["cases"]["h"][n] for n in near],
                                         mode="markers", marker=dict(symbol="circle-open", color="white", size=8,
                                                                     line=dict(width=2)),
                                         name="DEM cases", showlegend=False, hoverinfo="x+y"), row=r, col=col)
                index["cases"].append(len(fig.data) - 1)
                fig.add_trace(go.Scatter(x=[v[len(v) // 2]], y=[h[len(h) // 2]], mode="markers", hoverinfo="skip",
                                         marker=dict(symbol="x-thin", size=12, line=dict(width=2, color="red")),
                                         showlegend=False), row=r, col=col)
                index["probe"].append(len(fig.data) - 1)
    for name, style in (("recommended region: P >= confidence, within the data",
                         dict(mode="lines", line=dict(color="#ff2bd6", width=3))),
                        ("beyond the data",
                         dict(mode="markers", marker=dict(symbol="square", size=12, color="rgba(110,110,110,0.55)"))),
                        ("DEM cases run at this (f, d) cell",
                         dict(mode="markers", marker=dict(symbol="circle-open", size=9, color="black", line=dict(width=2)))),
                        ("read-out probe (click a cell to move it)",
                         dict(mode="markers", marker=dict(symbol="x-thin", size=11, line=dict(width=2, color="red"))))):
        fig.add_trace(go.Scatter(x=[None], y=[None], name=name, showlegend=True, **style))
    fig.update_xaxes(title_text="v [mm/s]", title_font_size=10, tickfont_size=9)
    fig.update_yaxes(title_text="h [um]", title_font_size=10, tickfont_size=9)

    def slider(name, values, active, x, prefix, fmt):
        return dict(name=name, active=active, x=x, len=0.45, y=1.0, yanchor="bottom", pad=dict(t=0, b=30),
                    currentvalue=dict(prefix=prefix, font=dict(size=13)),
                    steps=[dict(method="skip", label=format(val, fmt), value=str(k), args=[]) for k, val in enumerate(values)])

    height = 330 * 2 * blocks + 210
    fig.update_layout(height=height, width=1400, margin=dict(t=170, b=40, l=60, r=40),
                      legend=dict(orientation="h", x=0, y=1 + 130 / (height - 210), yanchor="bottom",
                                  font=dict(size=11)),
                      sliders=[slider("f", data["f"], i, 0.0, "friction f = ", ".3g"),
                               slider("d", data["d"], j, 0.55, "diameter d [um] = ", ".3g")])
    return fig, index


SCRIPT = """
var D = JSON.parse(document.getElementById('explorer-data').textContent);
var gd = document.getElementById('{plot_id}');
var S = {fi: INITIAL_F, di: INITIAL_D, hi: Math.floor(D.h.length / 2), vi: Math.floor(D.v.length / 2)};
function cell(flat, fi, di) {
  var nh = D.h.length, nv = D.v.length, start = (fi * D.d.length + di) * nh * nv, out = [];
  for (var r = 0; r < nh; r++) out.push(flat.slice(start + r * nv, start + (r + 1) * nv));
  return out;
}
function pair(a, b) { return a.map(function (row, r) { return row.map(function (x, c) { return [x, b[r][c]]; }); }); }
function show() {
  var z = [], cd = [], idx = [];
  D.targets.forEach(function (t, k) {
    var m = cell(D.mean[t], S.fi, S.di), s = cell(D.model_sd[t], S.fi, S.di), r = cell(D.run_sd[t], S.fi, S.di);
    z.push(m); cd.push(pair(s, r)); idx.push(IDX.mean[k]);
    z.push(s); cd.push(pair(s, r)); idx.push(IDX.sd[k]);
  });
  Plotly.restyle(gd, {z: z, customdata: cd}, idx);
  var shade = cell(D.beyond, S.fi, S.di).map(function (row) { return row.map(function (b) { return b ? 1 : null; }); });
  Plotly.restyle(gd, {z: IDX.beyond.map(function () { return shade; })}, IDX.beyond);
  var reg = cell(D.region, S.fi, S.di);
  Plotly.restyle(gd, {z: IDX.region.map(function () { return reg; })}, IDX.region);
  var near = D.cases.near[S.fi * D.d.length + S.di];
  var cx = near.map(function (n) { return D.cases.v[n]; }), cy = near.map(function (n) { return D.cases.h[n]; });
  Plotly.restyle(gd, {x: IDX.cases.map(function () { return cx; }), y: IDX.cases.map(function () { return cy; })}, IDX.cases);
  Plotly.restyle(gd, {x: IDX.probe.map(function () { return [D.v[S.vi]]; }), \
y: IDX.probe.map(function () { return [D.h[S.hi]]; })}, IDX.probe);
  readout(near.length);
}
function readout(ncases) {
  var nh = D.h.length, nv = D.v.length, at = (S.fi * D.d.length + S.di) * nh * nv + S.hi * nv + S.vi;
  document.getElementById('probe-point').textContent = 'f = ' + D.f[S.fi].toPrecision(3) + ', d = ' +
    D.d[S.di].toPrecision(3) + ' um, h = ' + D.h[S.hi].toPrecision(3) + ' um, v = ' + D.v[S.vi].toPrecision(3) + ' mm/s';
  D.targets.forEach(function (t) {
    document.getElementById('mean-' + t).textContent = D.mean[t][at].toFixed(4);
    document.getElementById('model-sd-' + t).textContent = D.model_sd[t][at].toFixed(4);
    document.getElementById('run-sd-' + t).textContent = D.run_sd[t][at].toFixed(4);
  });
  document.getElementById('probability').textContent = D.probability[at].toFixed(3);
  document.getElementById('beyond').textContent = D.beyond[at] ? 'yes: beyond the data' : 'no';
  document.getElementById('in-region').textContent = D.region[at] ? 'yes' : 'no';
  document.getElementById('near-cases').textContent = String(ncases);
}
gd.on('plotly_sliderchange', function (e) {
  if (e.slider.name === 'f') S.fi = +e.step.value; else S.di = +e.step.value;
  show();
});
gd.on('plotly_click', function (e) {
  var p = e.points[0];
  S.vi = D.v.indexOf(p.x); S.hi = D.h.indexOf(p.y);
  if (S.vi < 0 || S.hi < 0) return;
  show();
});
show();
window.explorer = {data: D, state: S, plot: gd, traces: IDX};  // for the console (and the browser test)
window.explorerReady = true;
"""

PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>spreadmap explorer</title>
<style>body{{font-family:sans-serif;margin:16px;color:#222}} table{{border-collapse:collapse;font-size:14px}}
td,th{{padding:2px 10px;text-align:right}} th{{border-bottom:1px solid #999}} \
.note{{color:#555;font-size:13px;max-width:1350px}}</style>
</head><body>
<h2>spreadmap explorer: the surrogate's map over (v, h), friction and diameter on the sliders</h2>
<p id="floor"><b>{floor}</b></p>
<p class="note">{intro}</p>
<div id="readout"><b>At <span id="probe-point"></span></b>
<table><tr><th style="text-align:left">target</th><th>mean</th><th>model SD</th><th>new run SD</th></tr>
{rows}
</table>
<p>P(meets {bounds}) = <b id="probability"></b> &nbsp; recommended region: <b id="in-region"></b> &nbsp;
beyond the data: <b id="beyond"></b> &nbsp; DEM cases in this (f, d) cell: <b id="near-cases"></b></p></div>
<script type="application/json" id="explorer-data">{data}</script>
{plot}
</body></html>
"""


def explorer_html(data: dict, n_cases: int) -> str:
    """The page as one HTML string (plotly.js inlined, the model's numbers as JSON) from
    ``explorer_data``; ``n_cases``: the cases the surrogate was trained on."""
    i, j = len(data["f"]) // 2, len(data["d"]) // 2
    fig, index = explorer_figure(data, i, j)
    script = SCRIPT.replace("INITIAL_F", str(i)).replace("INITIAL_D", str(j))
    script = f"var IDX = {json.dumps(index)};\n" + script
    plot = fig.to_html(full_html=False, include_plotlyjs=True, div_id="explorer", post_script=script,
                       config={"displaylogo": False, "responsive": False})
    what = "a new DEM run (mean + its noise)" if data["about"] == "run" else "the mean function"
    intro = (f"Top of each pair: the posterior mean of the surrogate trained on {n_cases} DEM cases; "
             f"below: its model SD (what the map does not know). Grey: beyond the data ({data['support_text']}). "
             f"Outlined: where the probability that {what} meets {data['bounds_text']} is at least "
             f"{data['confidence']:g} and the setting lies within the data. Circles: the DEM cases whose f and d "
             f"lie in the sliders' cell. Numbers: the model evaluated at each grid point in Python.")
    rows = "\n".join(f'<tr><td style="text-align:left">{data["labels"][t]}</td><td id="mean-{t}"></td>'
                     f'<td id="model-sd-{t}"></td><td id="run-sd-{t}"></td></tr>' for t in data["targets"])
    payload = json.dumps(data, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    floor = html.escape(data.get("floor") or "floor not stated")
    return PAGE.format(floor=floor, intro=intro, rows=rows, bounds=data["bounds_text"], plot=plot, data=payload)


def write_explorer(model, dec: dict, support: dict, path, csv=None, floor: str | None = None) -> dict:
    """Write the page (and, given ``csv``, its numbers as a table); return the page's data.

    Parameters
    ----------
    model : spreadmap.surrogate.saved_model.SurrogateModel
        The fitted surrogate (``load_model``), evaluated at every grid point of the sliders and
        axes.
    dec : dict
        The ``decisions:`` config with defaults (``decision_config``): its ``explorer`` grid
        sizes, ``bounds``, ``quality``, ``confidence`` and ``about``.
    support : dict
        The maps' support rule (``map_config(...)["support"]``).
    path : pathlib.Path or str
        The HTML file to write (self-contained; written atomically).
    csv : pathlib.Path or str or None, optional
        Where to write the page's numbers as CSV (one row per grid point); None: not written.
    floor : str or None, optional
        The floor the model's cases ran on (spreadmap.case.substrate.floor_label), named on the
        page and in the table.

    Returns
    -------
    dict
        The page's data (``explorer_data`` plus ``floor``): the axis values ``f``, ``d``, ``h``,
        ``v``, the ``targets``, their means and SDs, ``probability``, ``beyond`` and ``region``.
    """
    data = {**explorer_data(model, dec, support), "floor": floor}
    write_text_atomically(path, explorer_html(data, len(model.train_X)))
    if csv is not None:
        write_text_atomically(csv, explorer_table(data).to_csv(index=False))
    return data


def explorer_table(data: dict) -> pd.DataFrame:
    """The page's numbers as a table (one row per grid point), for the CSV beside it."""
    mesh = np.meshgrid(data["f"], data["d"], data["h"], data["v"], indexing="ij")
    out = pd.DataFrame({n: m.ravel() for n, m in zip(EXPLORED, mesh)})
    for t in data["targets"]:
        out[t], out[f"{t}_model_sd"], out[f"{t}_run_sd"] = data["mean"][t], data["model_sd"][t], data["run_sd"][t]
    out["beyond_data"], out["probability"], out["recommended_region"] = data["beyond"], data["probability"], data["region"]
    if data.get("floor"):
        out["floor"] = data["floor"]
    return out
