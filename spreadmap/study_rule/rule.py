"""The study's rule: partition statistics of MFR and PD and the relative-change criterion.

Kept exactly as the reference study ran it (it is the study's row of every convergence report);
the workflow's own stopping rule is about the map (``spreadmap.loop.map_criteria``).

The criterion (SPEC, "Sampling and convergence")
------------------------------------------------
For each target (``mfr``, ``pd``) five statistics are computed on a partition (the first N cases
of a sweep, or one lattice):

* ``mean``     -- ``numpy.mean``
* ``std``      -- sample standard deviation, ``numpy.std(ddof=1)`` (the unbiased-variance
                  estimator's square root, not the population ``ddof=0`` one)
* ``median``   -- ``numpy.median``
* ``kurtosis`` -- ``scipy.stats.kurtosis(fisher=True, bias=True)``: *excess* kurtosis (0 for a
                  Gaussian, -1.2 for a uniform distribution), biased moment estimator m4/m2^2 - 3
* ``skewness`` -- ``scipy.stats.skew(bias=True)``: biased moment estimator m3/m2^1.5

A sweep has converged at partition N when *every* statistic of *every* target changes by less
than the tolerance (default 0.005 = 0.5 %) from the previous partition (strict ``<``).

The rule for statistics near zero
---------------------------------
``|curr - prev| / |prev|`` is ill-posed when ``prev`` is near zero, and skewness and excess
kurtosis sit near zero for any roughly symmetric, roughly Gaussian sample: ``|prev|`` of 1e-3 would
demand an absolute change below 5e-6, which sampling noise never meets, so a naive rule never
converges.  The rule used here is

    change = |curr - prev| / max(|prev|, floor[statistic])

with the floors of ``DEFAULT_FLOORS`` (the schema's ``study_rule.floors``):

* ``skewness`` and ``kurtosis``: floor **1.0**.  Both are dimensionless standardised moments whose
  natural unit is 1 (a distribution with |skewness| or |excess kurtosis| below 1 is "moderately"
  shaped; their sampling standard errors are sqrt(6/N) and sqrt(24/N), about 0.08 and 0.15 at
  N = 1000).  Below |value| = 1 the test is therefore an *absolute* one: the change must be below
  ``tolerance * 1.0`` (0.005 by default); above it, it is the ordinary relative one.  The
  criterion stays continuous in ``prev`` and never becomes stricter than the absolute one.
* ``mean``, ``std``, ``median``: floor 1e-12 (``TINY``), i.e. an ordinary relative change.  MFR
  and PD are positive fractions of order 0.1-0.7, so their mean, median and spread are only near
  zero when a whole partition jams (MFR all 0); then 0/TINY = 0 reads as "no change".

The tables of ``convergence_table`` carry, for every statistic, the change *and* the denominator
used and whether that denominator was ``|prev|`` or the floor, so every decision can be audited.
A statistic that is NaN (fewer than two usable values, zero spread) gives a NaN change, and a NaN
change never satisfies the criterion.

Floors are configurable (``floors={"skewness": 0.5, ...}``); passing 0 (or ``TINY``) for
skewness/kurtosis gives back the naive relative rule (tests show that rule never converging on
symmetric data).

Partitions and order
--------------------
LDS cases are a prefix sequence (case i is the same whatever N), so partition N = the first N
cases in ``index`` order.  N counts the cases of the sequence, failed ones included; the
statistics use the usable ones among them (``status == "ok"`` and not ``flagged`` when the table
has those columns, and finite target values).  Lattices of different k are not nested, so for a
lattice sweep pass ``partition_col`` (a column holding the lattice k or a partition label): each
group is one partition, N is its number of cases, groups are compared in order of size.

For LDS the check can also run case by case (``running_statistics`` / ``first_stable_n``), and
``batches_until_converged`` is the stop rule of a "run until converged" workflow target.
"""
from __future__ import annotations

import heapq
import math
from typing import Any, Callable, Iterable, Mapping, Sequence

import numpy as np
import pandas as pd
from scipy import stats as _st

from .. import targets as registry
from ..schema import checked
from ..table import partition
from ..table import usable as usable_rows

STATISTICS: tuple[str, ...] = ("mean", "std", "median", "kurtosis", "skewness")
TINY = 1e-12  # a scale below which a spread is taken for none
# the schema's study_rule.floors and study_rule.tolerance, for callers without a config
DEFAULT_FLOORS: dict[str, float] = checked("study_rule")["floors"]
DEFAULT_TOLERANCE = checked("study_rule")["tolerance"]
NOT_CONVERGED = "not converged within the cases run"
DEFAULT_TARGETS: tuple[str, ...] = registry.names("base")  # mfr, pd (spreadmap.targets)


# ----------------------------------------------------------------------------------------------
# statistics of one partition and the change between two
# ----------------------------------------------------------------------------------------------
def partition_statistics(values) -> dict[str, float]:
    """The five statistics of one partition of one target.

    Non-finite values (NaN: failed cases) are dropped first.  std uses ddof=1; kurtosis is
    Fisher's excess kurtosis with the biased estimator (scipy's default ``bias=True``); skewness
    is scipy's default biased estimator.  Fewer than two values, or zero spread, give NaN for the
    statistics that are undefined.
    """
    x = np.asarray(values, dtype=float).ravel()
    x = x[np.isfinite(x)]
    nan = float("nan")
    if x.size == 0:
        return {s: nan for s in STATISTICS}
    out = {"mean": float(np.mean(x)), "median": float(np.median(x))}
    out["std"] = float(np.std(x, ddof=1)) if x.size > 1 else nan
    if x.size > 1 and np.ptp(x) > 0:
        out["kurtosis"] = float(_st.kurtosis(x, fisher=True, bias=True))
        out["skewness"] = float(_st.skew(x, bias=True))
    else:
        out["kurtosis"] = out["skewness"] = nan
    return {s: out[s] for s in STATISTICS}


def _floors(floors: Mapping[str, float] | None) -> dict[str, float]:
    merged = dict(DEFAULT_FLOORS)
    if floors:
        unknown = set(floors) - set(STATISTICS)
        if unknown:
            raise ValueError(f"unknown statistics in floors: {sorted(unknown)}")
        merged.update({k: float(v) for k, v in floors.items()})
    return merged


def _change_arrays(prev, curr, floor: float):
    """Vectorised rule: |curr - prev| / max(|prev|, floor); also the denominator and its basis."""
    prev = np.asarray(prev, float)
    curr = np.asarray(curr, float)
    denom = np.maximum(np.abs(prev), floor)
    with np.errstate(divide="ignore", invalid="ignore"):
        change = np.abs(curr - prev) / denom
    # 0/0 (both zero, floor zero) is "no change"; anything involving NaN stays NaN
    change = np.where((curr == prev) & np.isfinite(prev), 0.0, change)
    basis = np.where(~np.isfinite(prev), "undefined",
                     np.where(np.abs(prev) >= floor, "previous", "floor"))
    return change, denom, basis


def _stat_row(frames: Mapping[str, np.ndarray], prev_row: dict | None, fl: dict,
              tolerance: float) -> dict:
    row: dict[str, Any] = {}
    changes = []
    for t, vals in frames.items():
        st = partition_statistics(vals)
        row[f"{t}_n_used"] = int(np.isfinite(np.asarray(vals, float)).sum())
        for s in STATISTICS:
            row[f"{t}_{s}"] = st[s]
            if prev_row is None:
                row[f"{t}_{s}_change"] = float("nan")
                row[f"{t}_{s}_denominator"] = float("nan")
                row[f"{t}_{s}_basis"] = ""
            else:
                c, d, b = _change_arrays(prev_row[f"{t}_{s}"], st[s], fl[s])
                row[f"{t}_{s}_change"] = float(c)
                row[f"{t}_{s}_denominator"] = float(d)
                row[f"{t}_{s}_basis"] = str(b)
                changes.append(float(c))
    if prev_row is None:
        row["max_change"] = float("nan")
        row["converged"] = False
    else:
        arr = np.array(changes)
        row["max_change"] = float(np.max(arr)) if not np.any(np.isnan(arr)) else float("nan")
        row["converged"] = bool(np.all(arr < tolerance))  # NaN < tol is False
    return row


def convergence_table(table: pd.DataFrame, target_cols: Sequence[str] = DEFAULT_TARGETS,
                      partitions: Iterable[int] | None = None, order_col: str = "index",
                      tolerance: float = DEFAULT_TOLERANCE,
                      floors: Mapping[str, float] | None = None,
                      partition_col: str | None = None) -> pd.DataFrame:
    """Statistics, changes and the criterion for each partition of one sweep.

    Prefix mode (default, LDS): partition N = the cases at positions 0 .. N-1 of the sequence
    (``table.partition``: ``order_col`` below N), which must all be rows of the table;
    ``partitions`` defaults to multiples of 100 up to the number of rows (plus the total).
    Group mode (``partition_col`` set, lattices): each value of ``partition_col`` is one
    partition, N = its number of rows, partitions are ordered by N.

    Parameters
    ----------
    table : pandas.DataFrame
        The results table's rows of one sweep (statistics use its usable rows).
    target_cols : sequence of str, optional
        The targets (columns) whose statistics are compared.
    partitions : iterable of int or None, optional
        Prefix mode: the partition sizes N, each in 1..len(table); None: multiples of 100 and
        the total.
    order_col : str, optional
        Prefix mode: the column giving the cases' order in the sequence.
    tolerance : float, optional
        The criterion's tolerance (0.005 = 0.5 %).
    floors : Mapping of str to float or None, optional
        Denominator floors per statistic (``DEFAULT_FLOORS`` for the ones left out).
    partition_col : str or None, optional
        Group mode: the column whose values name the partitions (lattices).

    Returns
    -------
    pandas.DataFrame
        One row per partition, by increasing N. Columns: ``partition`` (N), ``group`` (group
        mode only), ``n_usable``, per target ``{t}_n_used`` and per target and statistic
        ``{t}_{s}``, ``{t}_{s}_change``, ``{t}_{s}_denominator``, ``{t}_{s}_basis``;
        ``max_change`` and ``converged`` (all changes < tolerance; False for the first
        partition, which has nothing to compare with).

    Raises
    ------
    ValueError
        If the table holds several sweeps, two groups have the same size, a partition lies
        outside 1..len(table), or a prefix partition does not hold its N positions once each.
    """
    if "sweep" in table.columns and table["sweep"].nunique() > 1:
        raise ValueError("table holds several sweeps; filter it to one sweep first")
    fl = _floors(floors)
    usable = usable_rows(table)
    work = table.assign(_usable=usable)
    groups: list[tuple[int, Any, pd.DataFrame]] = []
    if partition_col is not None:
        for label, g in work.groupby(partition_col, sort=False):
            groups.append((len(g), label, g))
        groups.sort(key=lambda item: item[0])
        sizes = [n for n, _, _ in groups]
        if len(set(sizes)) != len(sizes):
            raise ValueError(f"partitions of equal size in {partition_col!r}: {sizes}")
    else:
        work = work.sort_values(order_col, kind="stable").reset_index(drop=True)
        n_total = len(work)
        if partitions is None:
            partitions = list(range(100, n_total + 1, 100))
            if not partitions or partitions[-1] != n_total:
                partitions.append(n_total)
        parts = sorted({int(p) for p in partitions})
        if parts and (parts[0] < 1 or parts[-1] > n_total):
            raise ValueError(f"partitions must lie in 1..{n_total}, got {parts}")
        groups = [(n, None, partition(work, n, sweep=None, order_col=order_col)) for n in parts]
        short = [(n, len(g)) for n, _, g in groups if len(g) != n]
        if short:
            raise ValueError(f"partitions (N, rows with {order_col} < N) {short}: the sequence's positions are "
                             f"not 0 .. N-1 each once; a missing case must still have its row (status failed)")

    rows = []
    prev = None
    for n, label, g in groups:
        use = g[g["_usable"]]
        frames = {t: use[t].to_numpy(dtype=float) for t in target_cols}
        row = {"partition": int(n)}
        if partition_col is not None:
            row["group"] = label
        row["n_usable"] = int(len(use))
        row.update(_stat_row(frames, prev, fl, tolerance))
        rows.append(row)
        prev = row
    return pd.DataFrame(rows)


def difference_from(reference: pd.DataFrame, other: pd.DataFrame, target_cols: Sequence[str] = DEFAULT_TARGETS,
                    floors: Mapping[str, float] | None = None) -> pd.DataFrame:
    """How far one sample's five statistics lie from a reference sample's, by the rule's own
    measure |other - reference| / max(|reference|, floor) (usable rows of each): e.g. a lattice
    and the LDS partition of the same size, each against the largest LDS partition. One row per
    target and statistic: ``target``, ``statistic``, ``reference``, ``other``, ``difference``."""
    fl = _floors(floors)
    ref, oth = reference[usable_rows(reference)], other[usable_rows(other)]
    rows = []
    for t in target_cols:
        a, b = partition_statistics(ref[t].to_numpy(float)), partition_statistics(oth[t].to_numpy(float))
        for s in STATISTICS:
            change = _change_arrays(a[s], b[s], fl[s])[0]
            rows.append({"target": t, "statistic": s, "reference": a[s], "other": b[s], "difference": float(change)})
    return pd.DataFrame(rows)


def first_converged(conv_df: pd.DataFrame) -> int | None:
    """First partition N at which the criterion holds; None = not converged within the cases run."""
    hit = conv_df.loc[conv_df["converged"].astype(bool), "partition"]
    return None if hit.empty else int(hit.iloc[0])


# ----------------------------------------------------------------------------------------------
# case by case (LDS prefixes)
# ----------------------------------------------------------------------------------------------
def _running_one(x: np.ndarray) -> dict[str, np.ndarray]:
    """Five statistics of x[:n] for n = 1..len(x), from cumulative central-moment sums."""
    n = np.arange(1, x.size + 1, dtype=float)
    y = x - np.mean(x)  # a shift for numerical conditioning only
    s1, s2, s3, s4 = (np.cumsum(y**p) for p in (1, 2, 3, 4))
    m = s1 / n
    e2, e3, e4 = s2 / n, s3 / n, s4 / n
    m2 = np.maximum(e2 - m**2, 0.0)
    m3 = e3 - 3 * m * e2 + 2 * m**3
    m4 = e4 - 4 * m * e3 + 6 * m**2 * e2 - 3 * m**4
    scale = np.maximum(np.abs(np.mean(x)), np.max(np.abs(y)) if y.size else 0.0)
    degenerate = m2 <= (1e-12 * max(scale, TINY)) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        std = np.sqrt(m2 * n / (n - 1))
        skew = m3 / m2**1.5
        kurt = m4 / m2**2 - 3.0
    std[0] = np.nan
    skew[degenerate] = np.nan
    kurt[degenerate] = np.nan
    return {"mean": m + np.mean(x), "std": std, "median": _running_median(x),
            "kurtosis": kurt, "skewness": skew}


def _running_median(x: np.ndarray) -> np.ndarray:
    """Median of x[:n] for every n, with the two-heap method (O(log n) per added value).

    ``low`` is a max-heap (stored negated) of the smaller half, ``high`` a min-heap of the larger
    half; ``low`` holds the extra element when n is odd.
    """
    low: list[float] = []
    high: list[float] = []
    med = np.empty(x.size)
    push, pushpop = heapq.heappush, heapq.heappushpop
    for i, v in enumerate(x.tolist()):
        if len(low) == len(high):  # the new n is odd: low grows
            push(low, -pushpop(high, v) if high else -v)
            med[i] = -low[0]
        else:  # the new n is even: high grows
            push(high, -pushpop(low, -v))
            med[i] = 0.5 * (high[0] - low[0])
    return med


def running_statistics(values, start: int = 2, names: Sequence[str] | None = None) -> pd.DataFrame:
    """The five statistics after each added case, for n = start .. len(values).

    ``values``: 1-D (one target, column prefix ``names[0]``, default ``"y"``) or 2-D
    ``[n_cases, n_targets]`` in prefix order (default names ``mfr, pd`` for two columns,
    ``y0, y1, ...`` otherwise).  Values must be finite: drop failed cases first (their position
    in the sequence is then lost, which is what "statistics of the usable cases" means).

    Parameters
    ----------
    values : array_like
        The targets of the cases in prefix order: shape (n_cases,) or (n_cases, n_targets).
    start : int, optional
        The first n reported (at least 1).
    names : sequence of str or None, optional
        One name per target column (the column prefixes).

    Returns
    -------
    pandas.DataFrame
        Indexed by ``n`` (start .. n_cases) with columns ``{name}_{statistic}``; the numbers
        equal ``partition_statistics(values[:n])`` (same estimators), computed in O(n log n)
        overall.

    Raises
    ------
    ValueError
        If `names` does not give one name per column, a value is not finite, or there are fewer
        cases than `start`.
    """
    arr = np.asarray(values, dtype=float)
    if arr.ndim == 1:
        arr = arr[:, None]
        names = tuple(names) if names else ("y",)
    elif names is None:
        names = DEFAULT_TARGETS if arr.shape[1] == 2 else tuple(f"y{j}" for j in range(arr.shape[1]))
    if len(names) != arr.shape[1]:
        raise ValueError("one name per target column")
    if not np.all(np.isfinite(arr)):
        raise ValueError("running_statistics needs finite values; drop failed cases first")
    start = max(int(start), 1)
    if arr.shape[0] < start:
        raise ValueError(f"{arr.shape[0]} cases, fewer than start={start}")
    cols = {}
    for j, name in enumerate(names):
        res = _running_one(arr[:, j])
        for s in STATISTICS:
            cols[f"{name}_{s}"] = res[s][start - 1:]
    return pd.DataFrame(cols, index=pd.Index(np.arange(start, arr.shape[0] + 1), name="n"))


def _stat_of_column(col: str) -> str:
    for s in STATISTICS:
        if col.endswith("_" + s) or col == s:
            return s
    raise ValueError(f"column {col!r} does not name a statistic")


def criterion_holds(stats_df: pd.DataFrame, tolerance: float = DEFAULT_TOLERANCE, lag: int = 1,
                    floors: Mapping[str, float] | None = None) -> pd.DataFrame:
    """For each row of a statistics frame (rows = growing N, columns ``{target}_{statistic}``):
    the largest change from the row ``lag`` rows earlier and whether the criterion holds there.

    Only columns named ``{target}_{statistic}`` (or a bare statistic) are used, so a
    ``convergence_table`` frame works too.  Rows without a predecessor get NaN / False.  Returns
    a frame with the same index and columns ``max_change`` and ``holds``.
    """
    fl = _floors(floors)
    cols = [c for c in stats_df.columns
            if isinstance(c, str) and any(c == st or c.endswith("_" + st) for st in STATISTICS)]
    if not cols:
        raise ValueError("no statistics columns ({target}_{statistic}) in the frame")
    x = stats_df[cols].to_numpy(dtype=float)
    change = np.full_like(x, np.nan)
    if x.shape[0] > lag:
        for j, c in enumerate(cols):
            change[lag:, j] = _change_arrays(x[:-lag, j], x[lag:, j], fl[_stat_of_column(c)])[0]
    holds = np.all(change < tolerance, axis=1)  # NaN -> False
    with np.errstate(invalid="ignore"):
        mx = np.where(np.any(np.isnan(change), axis=1), np.nan,
                      np.max(np.nan_to_num(change, nan=0.0), axis=1))
    return pd.DataFrame({"max_change": mx, "holds": holds}, index=stats_df.index)


def first_stable_n(running_df: pd.DataFrame, tolerance: float = DEFAULT_TOLERANCE,
                   window: int = 1, lag: int = 1,
                   floors: Mapping[str, float] | None = None) -> dict[str, Any]:
    """Where the criterion first holds, and where it holds for good, on growing-N statistics.

    ``running_df``: rows in increasing N (its index, e.g. from ``running_statistics``, or a
    ``partition`` column), columns ``{target}_{statistic}``.  The check at row i compares row i
    with row i - ``lag`` (``lag=1``: one added case for a case-by-case frame, the previous
    lattice for a per-lattice frame).

    * ``first_holds``: the first N at which the criterion holds at all.
    * ``stable_from``: the first N from which the criterion holds at *every* later check up to
      the last case run (``n_last``) -- "keeps holding" means no single failing check afterwards,
      among the cases run; cases not run say nothing.  To keep a verdict resting on the last one
      or two cases from passing as stability, the unbroken run of holding checks must contain at
      least ``window`` checks (K); otherwise ``stable_from`` is None.
    * ``checks_in_final_run``: the length of that final unbroken run of holding checks.

    None means "not converged within the cases run".

    Parameters
    ----------
    running_df : pandas.DataFrame
        Growing-N statistics: rows in increasing N (its index or a ``partition`` column),
        columns ``{target}_{statistic}``.
    tolerance : float, optional
        The criterion's tolerance (0.005 = 0.5 %).
    window : int, optional
        K, the fewest holding checks the final unbroken run must contain for ``stable_from``.
    lag : int, optional
        The check at row i compares row i with row i - lag.
    floors : Mapping of str to float or None, optional
        Denominator floors per statistic (``DEFAULT_FLOORS`` for the ones left out).

    Returns
    -------
    dict
        ``first_holds``, ``stable_from`` (N or None), ``n_last``, ``checks_in_final_run``,
        ``window``, ``tolerance`` and ``lag``.

    Raises
    ------
    ValueError
        If the frame has no ``{target}_{statistic}`` column.
    """
    if "partition" in running_df.columns:
        n_values = running_df["partition"].to_numpy()
        frame = running_df.set_index("partition")
    else:
        n_values = running_df.index.to_numpy()
        frame = running_df
    crit = criterion_holds(frame, tolerance, lag, floors)
    holds = crit["holds"].to_numpy()
    checked = np.arange(holds.size) >= lag
    out: dict[str, Any] = {"first_holds": None, "stable_from": None,
                           "n_last": int(n_values[-1]) if n_values.size else None,
                           "checks_in_final_run": 0, "window": int(window),
                           "tolerance": float(tolerance), "lag": int(lag)}
    idx = np.flatnonzero(holds & checked)
    if idx.size:
        out["first_holds"] = int(n_values[idx[0]])
    fails = np.flatnonzero(~holds & checked)
    begin = (fails[-1] + 1) if fails.size else lag
    run = holds.size - begin
    out["checks_in_final_run"] = int(max(run, 0))
    if run >= max(int(window), 1):
        out["stable_from"] = int(n_values[begin])
    return out


# ----------------------------------------------------------------------------------------------
# the stop rule of "run until converged"
# ----------------------------------------------------------------------------------------------
def _target_statistics(y, names: Sequence[str] | None) -> dict[str, dict[str, float]]:
    arr = np.asarray(y, dtype=float)
    if arr.ndim == 1:
        arr = arr[:, None]
    if names is None:
        names = DEFAULT_TARGETS if arr.shape[1] == 2 else tuple(f"y{j}" for j in range(arr.shape[1]))
    return {t: partition_statistics(arr[:, j]) for j, t in enumerate(names)}


def batches_until_converged(evaluate: Callable[[int], Any], batch_size: int,
                            k_consecutive: int = 3, budget: int = 2000,
                            start: int | None = None, tolerance: float = DEFAULT_TOLERANCE,
                            floors: Mapping[str, float] | None = None,
                            names: Sequence[str] | None = None) -> dict[str, Any]:
    """Grow a prefix sweep by batches until the criterion holds K times in a row, or the budget.

    ``evaluate(n)`` returns the targets of the first n cases (1-D, or ``[n, n_targets]``; NaN
    for failed cases, which are dropped per target).  n runs ``start`` (default ``batch_size``),
    ``start + batch_size``, ... and is capped at ``budget`` (the last batch may be short).  After
    each evaluation but the first, the criterion is checked against the previous evaluation;
    the run stops with reason ``"converged"`` as soon as it has held at ``k_consecutive``
    consecutive checks, or with reason ``"budget"`` once n == budget without that.

    Returns ``{"stopped_at", "reason", "converged_n", "k_consecutive", "tolerance", "history"}``
    where ``converged_n`` is the first n of the final run of K holding checks (the partition at
    which the sweep converged; None when it did not) and ``history`` a list of JSON-friendly
    dicts ``{"n", "max_change", "holds", "streak", "statistics": {target: {stat: value}}}``.
    """
    if batch_size < 1 or k_consecutive < 1 or budget < 1:
        raise ValueError("batch_size, k_consecutive and budget must be >= 1")
    fl = _floors(floors)
    n = min(int(start if start is not None else batch_size), int(budget))
    history: list[dict[str, Any]] = []
    prev = None
    streak = 0
    streak_start = None
    reason = "budget"
    while True:
        st = _target_statistics(evaluate(n), names)
        entry: dict[str, Any] = {"n": int(n), "max_change": None, "holds": False, "streak": 0,
                                 "statistics": st}
        if prev is not None:
            changes = [float(_change_arrays(prev[t][s], st[t][s], fl[s])[0])
                       for t in st for s in STATISTICS]
            ok = all(c < tolerance for c in changes)  # NaN fails
            entry["max_change"] = None if any(math.isnan(c) for c in changes) else max(changes)
            entry["holds"] = bool(ok)
            if ok:
                streak += 1
                if streak == 1:
                    streak_start = n
            else:
                streak, streak_start = 0, None
            entry["streak"] = streak
        history.append(entry)
        if streak >= k_consecutive:
            reason = "converged"
            break
        if n >= budget:
            break
        prev = st
        n = min(n + int(batch_size), int(budget))
    return {"stopped_at": int(n), "reason": reason,
            "converged_n": int(streak_start) if reason == "converged" else None,
            "k_consecutive": int(k_consecutive), "tolerance": float(tolerance),
            "history": history}


# ----------------------------------------------------------------------------------------------
# a JSON summary
# ----------------------------------------------------------------------------------------------
def _verdict(result) -> tuple[int | None, int | None]:
    """(converged N or None, cases run) from any of the results this module produces."""
    if isinstance(result, pd.DataFrame):
        return first_converged(result), int(result["partition"].max()) if len(result) else None
    if isinstance(result, Mapping):
        if "stable_from" in result:  # first_stable_n
            return result["stable_from"], result.get("n_last")
        if "reason" in result:  # batches_until_converged
            return result["converged_n"], result["stopped_at"]
        if "converged_n" in result:
            return result["converged_n"], result.get("cases_run")
    if isinstance(result, tuple) and len(result) == 2:
        return result
    raise TypeError(f"cannot read a convergence verdict from {type(result).__name__}")


def summary(sweeps: Mapping[str, Any], tolerance: float = DEFAULT_TOLERANCE,
            reference: str = "lds", baseline: str = "lattice") -> dict[str, Any]:
    """JSON-serialisable verdict of each sweep and the saving of ``reference`` over ``baseline``.

    ``sweeps`` maps a sweep name to a ``convergence_table`` frame, a ``first_stable_n`` dict, a
    ``batches_until_converged`` dict, or a tuple ``(converged_n or None, cases_run)``.

    The ratio baseline/reference is reported as ``"kind": "ratio"`` when both converged, as a
    ``"lower bound"`` (cases run by the baseline / N of the reference) when only the reference
    converged, and as ``"undefined"`` (value None) when the reference did not converge.

    Parameters
    ----------
    sweeps : Mapping of str to object
        Sweep name -> its convergence result (see above).
    tolerance : float, optional
        The criterion's tolerance, reported.
    reference : str, optional
        The sweep whose N the ratio divides by (the LDS sweep).
    baseline : str, optional
        The sweep compared with it (the lattice).

    Returns
    -------
    dict
        ``tolerance``, ``criterion`` (in words), ``sweeps`` (per sweep ``converged_n``,
        ``cases_run`` and ``status``) and, when both sweeps are given,
        ``ratio_{baseline}_to_{reference}`` (``value``, ``kind``, ``text``).

    Raises
    ------
    TypeError
        If a sweep's result is none of the kinds above.
    """
    out: dict[str, Any] = {"tolerance": float(tolerance),
                           "criterion": ("all of mean, std (ddof=1), median, excess kurtosis and "
                                         "skewness of each target change by less than the "
                                         "tolerance from the previous partition; change = "
                                         "|curr - prev| / max(|prev|, floor), floor 1 for "
                                         "skewness and kurtosis"),
                           "sweeps": {}}
    verdicts = {}
    for name, res in sweeps.items():
        n_conv, n_run = _verdict(res)
        n_conv = None if n_conv is None else int(n_conv)
        n_run = None if n_run is None else int(n_run)
        verdicts[name] = (n_conv, n_run)
        out["sweeps"][name] = {
            "converged_n": n_conv, "cases_run": n_run,
            "status": NOT_CONVERGED if n_conv is None else f"converged at {n_conv} cases"}
    key = f"ratio_{baseline}_to_{reference}"
    if reference in verdicts and baseline in verdicts:
        (n_ref, _), (n_base, run_base) = verdicts[reference], verdicts[baseline]
        if n_ref is None:
            ratio = {"value": None, "kind": "undefined",
                     "text": f"{reference}: {NOT_CONVERGED}; no ratio"}
        elif n_base is None:
            value = None if run_base is None else run_base / n_ref
            ratio = {"value": value, "kind": "lower bound",
                     "text": (f"{baseline}: {NOT_CONVERGED}; it needs more than {run_base} cases, "
                              f"i.e. more than {value:.3g} times the {n_ref} of {reference}"
                              if value is not None else f"{baseline}: {NOT_CONVERGED}")}
        else:
            ratio = {"value": n_base / n_ref, "kind": "ratio",
                     "text": f"{baseline} {n_base} / {reference} {n_ref} = {n_base / n_ref:.3g}"}
        out[key] = ratio
    return out
