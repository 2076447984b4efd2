"""The counting law's constant c from seed repeats: across packing seeds the relative SD of MFR and
of PD is about c / sqrt(N), N the spheres' worth of volume measured (``spreadmap.metrics.noise``).
``counting_constant`` reads c per cell of seeds, ``pooled_constant`` pools it over cells
(benchmarks/counting_noise.py, the fidelity study's cases).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import stats

from spreadmap.design import NAMES
from spreadmap.table import usable_cases
from spreadmap.targets import names as target_names


def counting_constant(cases: pd.DataFrame, presets: dict, group=("preset", "name"), level: float = 0.9) -> pd.DataFrame:
    """The counting law's constant c per cell of seeds, with its confidence interval.

    Per cell of seeds (default: preset x point name): mean, seed SD and relative SD of MFR and
    PD, N = spheres' worth of volume passed (MFR x h x W x window travel / sphere volume, W and the
    window from the preset, in d) and c = relative SD x sqrt(N), with a `level` confidence interval
    from the chi-square law of the sample variance (normal seeds). Rows not usable
    (``spreadmap.table.usable``) are left out. For PD the box is the window (the published study's):
    N_pd = PD x h x W x window / v. A table with the cases' own count (`n_passed`, windows sized by a
    precision target) uses the cell's mean count as N for both (the deposit holds what passed), and
    needs no presets.

    Parameters
    ----------
    cases : pandas.DataFrame
        A results table of seed repeats: the four parameters, ``mfr``, ``pd``, ``status``,
        ``flagged``, the `group` columns and, where known, ``n_passed``.
    presets : dict
        The config's ``presets`` (``width_d``, ``window_d``), for tables without ``n_passed``.
    group : tuple of str, optional
        The columns whose values make one cell.
    level : float, optional
        Confidence level of the intervals.

    Returns
    -------
    pandas.DataFrame
        One row per cell of two seeds or more: the group's values, the point, ``seeds``, and per
        target (mfr, pd) ``<t>_mean``, ``<t>_sd``, ``<t>_rel_sd``, ``n_<t>``, ``c_<t>``,
        ``c_<t>_lo`` and ``c_<t>_hi``.
    """
    ok = usable_cases(cases)
    rows = []
    for key, cell in ok.groupby(list(group)):
        key = dict(zip(group, key if isinstance(key, tuple) else (key,)))
        if len(cell) < 2:  # one seed says nothing of the spread
            continue
        d, h = cell["d_um"].iloc[0], cell["h_um"].iloc[0]
        counted = "n_passed" in cell and bool(cell["n_passed"].notna().all())
        if not counted:
            preset = presets[key["preset"]] if "preset" in key else presets[cell["preset"].iloc[0]]
            spheres_per_fraction = h * preset["width_d"] * d * preset["window_d"] * d / (math.pi * d ** 3 / 6.0)
        row = {**key, **{name: cell[name].iloc[0] for name in NAMES}, "seeds": len(cell)}
        dof = len(cell) - 1
        lo_q, hi_q = stats.chi2.ppf([(1 + level) / 2, (1 - level) / 2], dof) if dof > 0 else (math.nan, math.nan)
        for name in target_names("base"):
            mean, sd = cell[name].mean(), cell[name].std(ddof=1)
            n = float(cell["n_passed"].mean()) if counted else mean * spheres_per_fraction
            c = sd / mean * math.sqrt(n)
            row.update({f"{name}_mean": mean, f"{name}_sd": sd, f"{name}_rel_sd": sd / mean, f"n_{name}": n,
                        f"c_{name}": c, f"c_{name}_lo": c * math.sqrt(dof / lo_q), f"c_{name}_hi": c * math.sqrt(dof / hi_q)})
        rows.append(row)
    return pd.DataFrame(rows)


def pooled_constant(cells: pd.DataFrame, name: str, level: float = 0.9) -> tuple[float, float, float]:
    """c pooled over cells, with its chi-square interval.

    The root of the dof-weighted mean of c^2 (the pooled relative variance x N).

    Parameters
    ----------
    cells : pandas.DataFrame
        ``counting_constant``'s table.
    name : str
        The target (``mfr`` or ``pd``).
    level : float, optional
        Confidence level of the interval.

    Returns
    -------
    c, low, high : float
        The pooled constant and its interval.
    """
    dof = (cells["seeds"] - 1).to_numpy(float)
    c2 = cells[f"c_{name}"].to_numpy(float) ** 2
    total = dof.sum()
    pooled = math.sqrt(np.sum(dof * c2) / total)
    lo_q, hi_q = stats.chi2.ppf([(1 + level) / 2, (1 - level) / 2], total)
    return pooled, pooled * math.sqrt(total / lo_q), pooled * math.sqrt(total / hi_q)
