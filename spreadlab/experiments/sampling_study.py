"""How many samples does each design need to meet the convergence criterion?  (No DEM.)

The SPEC's reference outcome is that a scrambled-Halton (LDS) sweep converged at about 1000
cases against about 10,000 for a uniform lattice.  This module *tests* that kind of claim on
cheap functions instead of assuming it: on smooth test functions of the unit cube [0, 1]^4, or on
any predictor ``predict(points[n, 4] in physical units) -> ndarray[n, 2]`` (e.g. a surrogate
trained on real DEM results), it counts the cases each design needs before the criterion of
``spreadmap.study_rule`` (five statistics of each output, relative change < tolerance, floor 1
for skewness and kurtosis) holds for good.

Designs (``method``)
--------------------
* ``lds``: scrambled Halton, ``scipy.stats.qmc.Halton(d=4, scramble=True, seed=seed)``, grown as
  a prefix sequence; one run per seed.
* ``random``: i.i.d. uniform points, ``numpy.random.default_rng(seed)``, grown as a prefix.
* ``lattice``: k points per dimension, end points included, k^4 cases for k = 2 .. k_max; one
  deterministic run (seed is NA, and it has no spread).

Schedules (``schedule``): where the criterion is checked
--------------------------------------------------------
* ``case`` (LDS and random): after every added case, comparing N with N - 1 (the SPEC allows
  single-case granularity for LDS).
* ``lattice_sizes`` (all three): at N = k^4 only, comparing k^4 with (k-1)^4 cases.  For the
  lattice these are different lattices; for LDS and random, prefixes of one sequence.

``n_converged`` is the first N from which the criterion holds at every later check up to the
budget (``rule.first_stable_n``), NaN if that does not happen within the budget
(censored).  ``n_first_holds`` is the first N at which it held at all.

Caveats, measured or structural
-------------------------------
* **Granularity of the lattice.**  A lattice can only stop at 16, 81, 256, 625, 1296, 2401,
  4096, 6561, 10000, 14641, ... cases: a lattice "converged at 10000" converged somewhere in
  (6561, 10000], so any lattice/LDS ratio is uncertain by the factor (k/(k-1))^4 (1.5 at k = 10,
  2.4 at k = 5), and the budget k_max^4 caps what can be observed at all.
* **The check compares different steps.**  Under ``case`` the LDS change is that of one added
  case out of N, which shrinks like 1/N whatever the quality of the sample (the mean moves by
  (x_N - mean)/N for any design); the lattice change is that of a jump from (k-1)^4 to k^4
  cases.  The single-case check is therefore much easier to pass, and a ratio lattice/LDS under
  ``case`` mixes the quality of the designs with the leniency of the check.  For the same reason
  ``case`` hardly tells LDS from random sampling.  ``lattice_sizes`` compares all three designs
  with the same steps and is the like-for-like comparison; report both.
* **Why the lattice is slow here.**  With end points included and every point weighted
  equally, a lattice over-weights the faces of the cube: its mean, std, ... carry an O(1/k)
  bias, so they change by O(1/k^2) between successive k, which falls below 0.5 % only at large
  k.  Smooth or not, a function is hard for the lattice when its statistics depend on the
  boundary region.
* **"Holds for good" depends on the budget**: a longer run offers more chances to fail (a
  single extreme case moves the excess kurtosis by about z^4 / N).
* **Relative changes of mean, median and std depend on the offset of the output**: adding a
  constant to a function makes its mean "converge" sooner.  The test functions here have
  offsets and spreads of the order of MFR and PD (coefficient of variation ~0.1-0.6).

The default study (4 functions, 8 seeds, k_max = 14: budget 38,416 cases for every design) takes
about 5-10 s on the 2-core development machine; ``seeds``, ``k_max`` and ``n_max`` make it larger.
Measured with the defaults (median n, tolerance 0.5 %): checked at the lattice sizes, LDS needs
4096 (cosine, flow curve), 14,641 (Gaussian bump) and 38,416 (Ishigami) cases; random sampling
needs 28,561 or more; the lattice converged within the budget only on the flow curve (38,416).
Checked case by case, LDS and random need about the same (ratio random/LDS 0.83-1.19).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from spreadmap.design import NAMES, to_physical
from spreadmap.sampling import halton_unit as lds_points  # the workflow's own LDS and lattice points
from spreadmap.sampling import lattice_unit as lattice_points
from spreadmap.study_rule import rule as cv

D = len(NAMES)


# ----------------------------------------------------------------------------------------------
# test functions on the unit cube: u[n, 4] -> y[n]
# ----------------------------------------------------------------------------------------------
# Centres off the middle of the cube on purpose: a function symmetric about u = 1/2 takes one
# value on all 16 corners (the k = 2 lattice) and flatters or penalises lattices by accident.
_CENTRE = np.array([0.35, 0.45, 0.6, 0.7])


def cosine_product(u: np.ndarray) -> np.ndarray:
    """prod_i cos(a_i (u_i - c_i)), a = (1, 1.5, 2, 2.5), c = (0.35, 0.45, 0.6, 0.7).

    Smooth and positive (every argument stays below pi/2), values ~0.1-1.
    """
    a = np.array([1.0, 1.5, 2.0, 2.5])
    return np.prod(np.cos(a * (np.asarray(u, float) - _CENTRE)), axis=1)


def gaussian_bump(u: np.ndarray) -> np.ndarray:
    """exp(-sum_i b_i (u_i - c_i)^2), b = (2, 3, 4, 5), c as for cosine_product: an exponential
    of a quadratic (a Genz "Gaussian" integrand), right-skewed output."""
    b = np.array([2.0, 3.0, 4.0, 5.0])
    return np.exp(-np.sum(b * (np.asarray(u, float) - _CENTRE) ** 2, axis=1))


def flow_curve(u: np.ndarray) -> np.ndarray:
    """An MFR-like saturating flow curve.

    With u in NAMES order (f, d, h, v) mapped to the SPEC ranges, the gap-to-diameter ratio
    r = h/d runs 1.1 .. 7.5; the flow rises from 0 at r = 1 and saturates, and falls with
    friction and blade speed: 0.7 (1 - exp(-(r - 1)/1.5)) (1 - (f - 0.15)) (1 - 0.02 (v - 5)).

    Parameters
    ----------
    u : numpy.ndarray
        Points of the unit cube, shape (n, 4), NAMES order.

    Returns
    -------
    numpy.ndarray
        The flow at each point, shape (n,) (dimensionless).
    """
    u = np.asarray(u, float)
    f = 0.15 + 0.30 * u[:, 0]
    d = 10.0 + 40.0 * u[:, 1]
    h = 55.0 + 20.0 * u[:, 2]
    v = 5.0 + 10.0 * u[:, 3]
    r = h / d
    return 0.7 * (1.0 - np.exp(-(r - 1.0) / 1.5)) * (1.0 - (f - 0.15)) * (1.0 - 0.02 * (v - 5.0))


def ishigami4(u: np.ndarray) -> np.ndarray:
    """Ishigami function (a = 7, b = 0.1) on X = pi (2u - 1), plus a weak fourth input 0.5 cos X4.

    Mean 3.5 + 0 (its output is roughly symmetric: skewness near 0, negative excess kurtosis),
    a hard case for the relative criterion and for lattices (strong interaction X1-X3).
    """
    x = np.pi * (2.0 * np.asarray(u, float) - 1.0)
    return (np.sin(x[:, 0]) + 7.0 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])
            + 0.5 * np.cos(x[:, 3]))


TEST_FUNCTIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "cosine_product": cosine_product,
    "gaussian_bump": gaussian_bump,
    "flow_curve": flow_curve,
    "ishigami4": ishigami4,
}


def predictor_on_unit_cube(predict: Callable[[np.ndarray], np.ndarray],
                           ranges: dict | None = None) -> Callable[[np.ndarray], np.ndarray]:
    """Wrap ``predict(points in physical units) -> [n, 2]`` as a function of the unit cube."""
    def f(u: np.ndarray) -> np.ndarray:
        return np.asarray(predict(to_physical(u, ranges)), dtype=float)
    return f


# ----------------------------------------------------------------------------------------------
# designs
# ----------------------------------------------------------------------------------------------
def random_points(n: int, seed: int) -> np.ndarray:
    """n i.i.d. uniform points of the unit cube."""
    return np.random.default_rng(seed).random((n, D))


def _as_2d(y) -> np.ndarray:
    y = np.asarray(y, dtype=float)
    return y[:, None] if y.ndim == 1 else y


def _names(m: int) -> tuple[str, ...]:
    return tuple(f"y{j}" for j in range(m))


def _stats_frame(blocks: Sequence[tuple[int, np.ndarray]]) -> pd.DataFrame:
    """Statistics frame (index N, columns y{j}_{stat}) for a list of (N, outputs[N, m])."""
    rows = {}
    for n, y in blocks:
        y = _as_2d(y)
        row = {}
        for j, name in enumerate(_names(y.shape[1])):
            for s, v in cv.partition_statistics(y[:, j]).items():
                row[f"{name}_{s}"] = v
        rows[n] = row
    return pd.DataFrame.from_dict(rows, orient="index").rename_axis("n")


def _verdict(frame: pd.DataFrame, tolerance, window, floors) -> tuple[float, float]:
    res = cv.first_stable_n(frame, tolerance=tolerance, window=window, lag=1, floors=floors)
    nan = float("nan")
    return (nan if res["stable_from"] is None else float(res["stable_from"]),
            nan if res["first_holds"] is None else float(res["first_holds"]))


# ----------------------------------------------------------------------------------------------
# the study
# ----------------------------------------------------------------------------------------------
def run_study(functions: Mapping[str, Callable[[np.ndarray], np.ndarray]] | None = None,
              predictor: Callable[[np.ndarray], np.ndarray] | None = None,
              ranges: dict | None = None,
              seeds: int | Iterable[int] = 8, k_max: int = 14, n_max: int | None = None,
              tolerance: float = cv.DEFAULT_TOLERANCE,
              floors: Mapping[str, float] | None = None,
              start: int = 16, window: int = 1,
              schedules: Sequence[str] = ("case", "lattice_sizes")) -> pd.DataFrame:
    """Cases needed by LDS, random and lattice designs to meet the same criterion.

    ``functions``: name -> f(u[n, 4] in the unit cube) -> y[n] or y[n, m] (default
    ``TEST_FUNCTIONS``); ``predictor`` (physical units, ``[n, 2]`` out) is added as "predictor".
    ``seeds``: a count (0 .. seeds-1) or the seeds themselves.  Lattices run k = 2 .. k_max;
    LDS and random run ``n_max`` cases (default k_max^4, the same budget as the lattice).
    ``start``: the first N checked case by case.  ``window``: the minimum number of holding
    checks in the final run (see ``rule.first_stable_n``).

    Returns a tidy frame: function, method, schedule, seed (Int64, NA for the lattice),
    n_converged (float, NaN = not converged within the budget), n_first_holds, budget.
    """
    funcs = dict(TEST_FUNCTIONS if functions is None else functions)
    if predictor is not None:
        funcs["predictor"] = predictor_on_unit_cube(predictor, ranges)
    seed_list = list(range(seeds)) if isinstance(seeds, (int, np.integer)) else list(seeds)
    if k_max < 3:
        raise ValueError("k_max must be >= 3 (two lattices to compare)")
    ks = list(range(2, k_max + 1))
    sizes = [k**D for k in ks]
    n_max = int(n_max if n_max is not None else sizes[-1])
    bad = set(schedules) - {"case", "lattice_sizes"}
    if bad:
        raise ValueError(f"unknown schedules {sorted(bad)}")
    rows = []

    def record(name, method, schedule, seed, verdict, budget):
        rows.append({"function": name, "method": method, "schedule": schedule, "seed": seed,
                     "n_converged": verdict[0], "n_first_holds": verdict[1], "budget": budget})

    for name, f in funcs.items():
        lat = _stats_frame([(n, f(lattice_points(k))) for k, n in zip(ks, sizes)])
        record(name, "lattice", "lattice_sizes", pd.NA,
               _verdict(lat, tolerance, 1, floors), sizes[-1])
        for seed in seed_list:
            for method, points in (("lds", lds_points), ("random", random_points)):
                y = _as_2d(f(points(n_max, seed)))
                if "case" in schedules:
                    frame = cv.running_statistics(y, start=start, names=_names(y.shape[1]))
                    record(name, method, "case", seed,
                           _verdict(frame, tolerance, window, floors), n_max)
                if "lattice_sizes" in schedules:
                    frame = _stats_frame([(n, y[:n]) for n in sizes if n <= n_max])
                    record(name, method, "lattice_sizes", seed,
                           _verdict(frame, tolerance, 1, floors), n_max)
    out = pd.DataFrame(rows)
    out["seed"] = out["seed"].astype("Int64")
    return out


def _censored_quantiles(g: pd.DataFrame) -> pd.Series:
    """Median and quartiles with not-converged runs counted as above the budget (+inf)."""
    v = g["n_converged"].to_numpy(dtype=float)
    v = np.where(np.isnan(v), np.inf, v)
    q = np.quantile(v, [0.25, 0.5, 0.75], method="lower")
    q = [float(t) if np.isfinite(t) else np.nan for t in q]
    return pd.Series({"q25": q[0], "median": q[1], "q75": q[2], "iqr": q[2] - q[0],
                      "runs": int(v.size), "not_converged": int(np.isinf(v).sum()),
                      "budget": int(g["budget"].max())})


def summarise(table: pd.DataFrame) -> pd.DataFrame:
    """Median, quartiles and IQR of n_converged per function, method and schedule.

    Not-converged runs count as larger than any observed n (censored at the budget); a median
    or quartile that falls among them is NaN and ``not_converged`` says how many there were.
    Quartiles use ``numpy.quantile(method="lower")``: always an observed n (a lattice size, for
    the ``lattice_sizes`` schedule).  The lattice is one deterministic run: its IQR is 0.

    Parameters
    ----------
    table : pandas.DataFrame
        ``run_study``'s tidy table.

    Returns
    -------
    pandas.DataFrame
        One row per (function, method, schedule): ``q25``, ``median``, ``q75``, ``iqr`` (cases),
        ``runs``, ``not_converged`` and ``budget``.
    """
    rows = []
    for (fn, method, sched), g in table.groupby(["function", "method", "schedule"], sort=False):
        rows.append({"function": fn, "method": method, "schedule": sched,
                     **_censored_quantiles(g).to_dict()})
    out = pd.DataFrame(rows)
    for c in ("runs", "not_converged", "budget"):
        out[c] = out[c].astype(int)
    return out


def ratios(summary_df: pd.DataFrame) -> pd.DataFrame:
    """lattice/LDS and random/LDS ratios of the median n, per function and LDS schedule.

    ``lattice_over_lds`` compares the lattice (its only schedule, k^4) with LDS under each
    schedule; ``random_over_lds`` compares random and LDS under the same schedule.
    ``*_kind`` is ``"ratio"`` when both medians exist; ``"lower bound"`` when the numerator's
    median is censored (not converged within the budget): the value is then budget / LDS median
    and the true ratio is larger; ``"undefined"`` (NaN) when the LDS median itself is censored.
    """
    rows = []
    for fn, g in summary_df.groupby("function", sort=False):
        lat = g[g["method"] == "lattice"]
        for _, lds_row in g[g["method"] == "lds"].iterrows():
            sched = lds_row["schedule"]
            lds = float(lds_row["median"])
            row = {"function": fn, "schedule": sched, "lds_median": lds,
                   "lds_iqr": float(lds_row["iqr"])}
            others = (("lattice", lat),
                      ("random", g[(g["method"] == "random") & (g["schedule"] == sched)]))
            for label, sub in others:
                if sub.empty:
                    continue
                med = float(sub["median"].iloc[0])
                row[f"{label}_median"] = med
                if not np.isfinite(lds):
                    value, kind = np.nan, "undefined"
                elif np.isfinite(med):
                    value, kind = med / lds, "ratio"
                else:
                    value, kind = float(sub["budget"].iloc[0]) / lds, "lower bound"
                row[f"{label}_over_lds"] = value
                row[f"{label}_over_lds_kind"] = kind
            rows.append(row)
    return pd.DataFrame(rows)


@dataclass
class StudyResult:
    """The tidy table of ``run_study``, its ``summarise`` and its ``ratios``."""
    table: pd.DataFrame
    summary: pd.DataFrame
    ratios: pd.DataFrame


def study(**kwargs) -> StudyResult:
    """``run_study(**kwargs)`` with its summary and ratios.

    Parameters
    ----------
    **kwargs : dict
        ``run_study``'s arguments (functions, predictor, ranges, seeds, k_max, n_max, tolerance,
        floors, start, window, schedules).

    Returns
    -------
    StudyResult
        ``table`` (``run_study``), ``summary`` (``summarise``) and ``ratios`` (``ratios``).

    Raises
    ------
    ValueError
        If ``k_max`` is below 3 or a schedule is unknown (``run_study``).
    """
    table = run_study(**kwargs)
    summ = summarise(table)
    return StudyResult(table, summ, ratios(summ))
