"""The noise law of a case: its seed-to-seed SD as a smooth function of what it depends on, fitted
by maximum likelihood to the sample variances of seed-repeat cells.

The law, per target (MFR or PD):

    ln SD = ln value + a + b ln(N / N_REF) + g ln((h/d) / HD_REF)  [+ other terms]

i.e. a relative SD exp(a) at N_REF spheres and h/d = HD_REF, a power b of the count (-1/2 is the
counting law) and a power g of h/d. A cell of k seeds gives s^2 with nu = k - 1 degrees of
freedom, and for normal seeds nu s^2 / sigma^2 ~ chi2_nu: the likelihood of each cell is that
chi-square (a Gamma law of s^2 of shape nu/2, mean sigma^2), not least squares on ln s, which
would be biased (E ln s^2 < ln sigma^2 by ~0.3-1 at nu = 2-3) and weigh a cell of 2 dof like one of
3. With eta = ln sigma^2 = 2 (offset + X beta) the score is sum nu (r - 1) x and the observed
information 2 sum nu r x x', r = s^2 / sigma^2 (Newton's method below).

Intervals: profile likelihood (`profile_interval`: the values where 2 (ll_max - ll_profile) reaches
the chi2_1 quantile), the default for the law's coefficients; `NoiseLaw.cov` (the inverse observed
information, Wald) is kept for quantities derived from several coefficients (the SD at a point).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import optimize, special, stats

N_REF = 150.0   # the shipped preset's window: (0.37 / 0.03)^2 = 152 spheres
HD_REF = 2.0


def _indicator(column: str, name: str):
    """variant:<name> the cells of that variant; source:<prefix> the cells whose source starts so."""
    if column == "source":
        return lambda cells: cells[column].str.startswith(name).to_numpy(float)
    return lambda cells: (cells[column] == name).to_numpy(float)


# name -> the column of the design matrix it adds (a function of a cells table)
TERMS = {
    "a": lambda cells: np.ones(len(cells)),
    "b_ln_n": lambda cells: np.log(cells["n"].to_numpy(float) / N_REF),
    "g_ln_hd": lambda cells: np.log(cells["h_over_d"].to_numpy(float) / HD_REF),
    "ln_hd_sq": lambda cells: np.log(cells["h_over_d"].to_numpy(float) / HD_REF) ** 2,
    "ln_value": lambda cells: np.log(cells["mean"].to_numpy(float) / 0.45),
    "ln_v": lambda cells: np.log(cells["v_mm_s"].to_numpy(float) / 10.0),
    "f": lambda cells: cells["f"].to_numpy(float) - 0.3,
    "ln_h": lambda cells: np.log(cells["h_um"].to_numpy(float) / 65.0),  # beside ln(h/d): h apart from d
}
LAW = ("a", "b_ln_n", "g_ln_hd")


def design(cells: pd.DataFrame, terms) -> np.ndarray:
    cols = []
    for term in terms:
        if term in TERMS:
            cols.append(TERMS[term](cells))
        elif term.split(":", 1)[0] in ("variant", "source") and ":" in term:
            cols.append(_indicator(*term.split(":", 1))(cells))
        else:
            raise ValueError(f"unknown term {term!r}: one of {sorted(TERMS)}, 'variant:<name>' or 'source:<name>'")
    return np.column_stack(cols) if cols else np.zeros((len(cells), 0))


def offset(cells: pd.DataFrame) -> np.ndarray:
    """ln of the cell's mean value: the law is one of the relative SD."""
    return np.log(cells["mean"].to_numpy(float))


def loglik(eta: np.ndarray, s2: np.ndarray, dof: np.ndarray) -> float:
    """Sum over cells of ln density of s^2 given ln sigma^2 = eta (nu s^2 / sigma^2 ~ chi2_nu):
    ln chi2_nu.pdf(x) + ln(nu / sigma^2), x = nu s^2 / sigma^2, written out (scipy's logpdf per call
    is most of a profile's time)."""
    x = dof * s2 * np.exp(-eta)
    half = 0.5 * dof
    return float(np.sum((half - 1) * np.log(x) - 0.5 * x - half * math.log(2.0) - special.gammaln(half)
                        + np.log(dof) - eta))


def _newton(X: np.ndarray, off: np.ndarray, s2: np.ndarray, dof: np.ndarray, intercept: int | None, tol=1e-10,
            start: np.ndarray | None = None):
    beta = np.zeros(X.shape[1]) if start is None else np.array(start, float)
    if X.shape[1] == 0:
        return beta, loglik(2 * off, s2, dof)
    if start is None and intercept is not None:  # start the intercept at the pooled relative variance
        beta[intercept] = 0.5 * math.log(np.sum(dof * s2 * np.exp(-2 * off)) / np.sum(dof))
    ll = loglik(2 * (off + X @ beta), s2, dof)
    for _ in range(200):
        r = s2 * np.exp(-2 * (off + X @ beta))
        grad = X.T @ (dof * (r - 1))
        info = 2 * (X * (dof * r)[:, None]).T @ X
        step = np.linalg.solve(info + 1e-12 * np.eye(len(beta)), grad)
        t = 1.0
        while True:
            trial = beta + t * step
            ll_trial = loglik(2 * (off + X @ trial), s2, dof)
            if ll_trial >= ll - 1e-12 or t < 1e-8:
                break
            t *= 0.5
        beta, done = trial, abs(ll_trial - ll) < tol and np.max(np.abs(t * step)) < 1e-8
        ll = ll_trial
        if done:
            break
    return beta, ll


@dataclass
class NoiseLaw:
    """A fitted law: coefficients by term, their covariance (inverse observed information), the
    log-likelihood, and what it was fitted on."""
    terms: tuple
    coef: np.ndarray
    cov: np.ndarray
    loglik: float
    cells: int
    dof: int
    fixed: dict = field(default_factory=dict)

    def eta(self, cells: pd.DataFrame) -> np.ndarray:
        """ln sigma of the relative SD (without the ln value offset)."""
        x = design(cells, self.terms) @ self.coef
        for term, value in self.fixed.items():
            x = x + value * design(cells, [term])[:, 0]
        return x

    def rel_sd(self, cells: pd.DataFrame) -> np.ndarray:
        return np.exp(self.eta(cells))

    def sd(self, cells: pd.DataFrame) -> np.ndarray:
        """The SD of one case at each cell's point (its mean value, count and h/d)."""
        return np.exp(offset(cells) + self.eta(cells))

    def se_ln_sd(self, cells: pd.DataFrame) -> np.ndarray:
        """Wald SE of ln SD at each cell's inputs."""
        X = design(cells, self.terms)
        return np.sqrt(np.einsum("ij,jk,ik->i", X, self.cov, X))

    def coefficient(self, term: str) -> float:
        return float(self.fixed[term]) if term in self.fixed else float(self.coef[list(self.terms).index(term)])


def fit_law(cells: pd.DataFrame, terms=LAW, fixed: dict | None = None) -> NoiseLaw:
    """Maximum-likelihood fit of ln SD = ln value + sum_t beta_t x_t over the cells (one target),
    with the terms in `fixed` held at the given values.

    Parameters
    ----------
    cells : pandas.DataFrame
        Seed-repeat cells of one target (``spreadlab.noise_law.cells.seed_cells``): ``s2`` (sample
        variance, the target's units squared), ``dof``, ``mean`` and the columns the terms read
        (``n``, ``h_over_d``, ...).
    terms : sequence of str, optional
        The law's terms (names of ``TERMS``, ``variant:<name>`` or ``source:<prefix>``); default
        ``LAW``: a, b ln(N / N_REF), g ln((h/d) / HD_REF).
    fixed : dict or None, optional
        Terms held at given values (term -> coefficient), not fitted.

    Returns
    -------
    NoiseLaw
        The free terms' coefficients, their covariance (inverse observed information), the
        log-likelihood, the cells and degrees of freedom fitted on, and `fixed`.

    Raises
    ------
    ValueError
        If a cell has s2 <= 0 or dof < 1, a term is unknown, or the free terms are not identified
        by the cells.
    """
    fixed = dict(fixed or {})
    free = tuple(t for t in terms if t not in fixed)
    if (cells["s2"] <= 0).any() or (cells["dof"] < 1).any():
        raise ValueError("every cell needs a positive sample variance and >= 1 degree of freedom")
    X = design(cells, free)
    off = offset(cells) + sum((v * design(cells, [t])[:, 0] for t, v in fixed.items()), np.zeros(len(cells)))
    s2, dof = cells["s2"].to_numpy(float), cells["dof"].to_numpy(float)
    if X.shape[1] and np.linalg.matrix_rank(X) < X.shape[1]:
        raise ValueError(f"the terms {free} are not identified by these cells")
    beta, ll = _newton(X, off, s2, dof, free.index("a") if "a" in free else None)
    r = s2 * np.exp(-2 * (off + X @ beta))
    info = 2 * (X * (dof * r)[:, None]).T @ X
    cov = np.linalg.inv(info) if X.shape[1] else np.zeros((0, 0))
    return NoiseLaw(free, beta, cov, ll, len(cells), int(dof.sum()), fixed)


def profile_interval(cells: pd.DataFrame, law: NoiseLaw, term: str, level: float = 0.95) -> tuple[float, float]:
    """Profile-likelihood interval of one coefficient: where 2 (ll_max - ll_profile) = chi2_1(level).

    Parameters
    ----------
    cells : pandas.DataFrame
        The cells `law` was fitted on.
    law : NoiseLaw
        The fitted law (``fit_law``).
    term : str
        One of the law's free terms.
    level : float, optional
        Confidence level of the interval.

    Returns
    -------
    low, high : tuple of float
        The interval's ends, in the coefficient's units.

    Raises
    ------
    ValueError
        If `term` is not a free term of `law`.
    RuntimeError
        If the profile does not reach the chi-square quantile within 1000 standard errors.
    """
    q = stats.chi2.ppf(level, 1)
    k = list(law.terms).index(term)
    best, se = law.coef[k], math.sqrt(law.cov[k, k])
    X = design(cells, law.terms)
    others = [j for j in range(len(law.terms)) if j != k]
    Xo, xk = X[:, others], X[:, k]
    off = offset(cells) + sum((v * design(cells, [t])[:, 0] for t, v in law.fixed.items()), np.zeros(len(cells)))
    s2, dof = cells["s2"].to_numpy(float), cells["dof"].to_numpy(float)
    start = law.coef[others]

    def excess(value):
        _, ll = _newton(Xo, off + value * xk, s2, dof, None, start=start)
        return 2 * (law.loglik - ll) - q

    bounds = []
    for sign in (-1, 1):
        step = 2 * se
        far = best + sign * step
        while excess(far) < 0:
            step *= 2
            far = best + sign * step
            if step > 1e3 * max(se, 1e-6):
                raise RuntimeError(f"profile of {term} does not close")
        bounds.append(optimize.brentq(excess, *sorted((best, far)), xtol=1e-7))
    return bounds[0], bounds[1]


def likelihood_ratio(cells: pd.DataFrame, general: NoiseLaw, restricted: NoiseLaw) -> tuple[float, int, float]:
    """(2 delta ll, the difference of free parameters, the chi-square p value).

    Parameters
    ----------
    cells : pandas.DataFrame
        The cells both laws were fitted on (not read: the laws carry their log-likelihoods).
    general : NoiseLaw
        The law with more free terms.
    restricted : NoiseLaw
        The law nested in it.

    Returns
    -------
    stat : float
        2 (ll_general - ll_restricted), at least 0.
    df : int
        The difference of free parameters.
    p : float
        The chi-square (df) p value of `stat`.
    """
    stat = max(2 * (general.loglik - restricted.loglik), 0.0)
    df = len(general.coef) - len(restricted.coef)
    return stat, df, float(stats.chi2.sf(stat, df))


def aic(law: NoiseLaw) -> float:
    return 2 * len(law.coef) - 2 * law.loglik
