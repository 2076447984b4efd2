"""Where the next batch of cases goes: where the model is least sure about the maps.

After an LDS start, each batch is chosen from a large seeded candidate set (scrambled Halton,
``candidates(n, seed)``) greedily, one point at a time, with the posterior updated after each
pick (the GP's posterior variance does not depend on the values not yet observed, so the update
is exact, not a guess).  The update is what keeps a batch from clustering: once a point is
picked, the variance around it drops and the next pick goes elsewhere.

Acquisitions (``acquisition``)
------------------------------
* ``ivr`` (integrated variance reduction, default): the candidate whose case would most reduce
  the summed posterior variance of the map over ``reference`` points (the map grids: the design
  box, the machine and the powder planes), sum_r cov(r, c)^2 / (var(c) + noise).  It spends cases
  where they help the maps, not where the variance is largest for its own sake (often the
  corners of the box, which the maps read little).
* ``ivr_per_cpu``: the same reduction per CPU-second a case there is expected to cost (``cost``:
  the CPU law of the spheres and steps the scene plans for the case, the same on every machine
  and after every resume, ``cost.PlannedCost``): variance reduction bought per unit of
  the scarce resource. On this scene a case costs 25-1350 s over the design space (fine powders
  at large h/d the most: the pile's standing reserve), so where two candidates teach the maps
  alike, the one that costs a tenth is taken; the LDS share of each batch keeps sampling
  everywhere whatever the cost (measured against ``ivr`` at equal CPU on a known truth with the
  scene's cost law: ``cost_study``, docs/sampling).
* ``max_sd``: the candidate with the largest posterior variance.

With several targets (MFR and PD) the scores are summed in units of each target's noise
variance, so a target counts by how unsure its map is relative to what one case can resolve.

Models without a posterior covariance (an MLP ensemble behind ``model``'s interface) get
``max_sd`` without the update, with an exclusion radius instead: no two picks (nor a pick and a
finished case) closer than half the typical spacing of the grown sample.

Reproducible: the same models, finished cases, seed and batch size give the same batch;
another seed gives another candidate set and so another batch.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Callable, Sequence

import numpy as np
from scipy.stats import qmc

from ..design import NAMES, Design, to_physical, to_unit

ACQUISITIONS = ("ivr", "ivr_per_cpu", "max_sd")


def candidates(n: int, seed: int) -> np.ndarray:
    """n scrambled Halton points of the unit cube, seeded (a set independent of the LDS sweep's)."""
    return qmc.Halton(d=len(NAMES), scramble=True, seed=np.random.default_rng([int(seed), 16])).random(int(n))


class _Posterior:
    """Posterior (co)variances of one GP target over candidates C and references R (physical
    points, embedded in the model's input space), with exact rank-one updates for every point
    added to the batch.  Standardised units; scores in units of the target's typical new-run
    noise variance, so that targets add up by how unsure each map is against what a case resolves."""

    def __init__(self, model, C: np.ndarray, R: np.ndarray | None):
        X = model.X_train_embedded
        k = model.latent_kernel
        K = k(X) + np.diag(model.train_noise_var())
        L = np.linalg.cholesky(K + 1e-10 * np.eye(len(X)))
        Ce = model.embed(C)
        self.k, self.C = k, Ce
        self.VC = np.linalg.solve(L, k(X, Ce))
        self.noise_c = np.asarray(model.new_case_noise_var(C), float)  # a new run's noise at each candidate
        self.noise = float(np.mean(self.noise_c))  # the target's unit of variance
        self.var = np.maximum(k.diag(Ce) - np.sum(self.VC**2, axis=0), 0.0)
        self.us: list[np.ndarray] = []  # rank-one update vectors over C
        self.has_R = R is not None
        if R is not None:
            Re = model.embed(R)
            VR = np.linalg.solve(L, k(X, Re))
            self.covRC = k(Re, Ce) - VR.T @ self.VC

    def cov_C(self, j: int) -> np.ndarray:
        """Current posterior covariance between all candidates and candidate j."""
        c = self.k(self.C, self.C[j:j + 1])[:, 0] - self.VC.T @ self.VC[:, j]
        for u in self.us:
            c = c - u * u[j]
        return c

    def score(self, acquisition: str) -> np.ndarray:
        """The variance reduction (``ivr``, ``ivr_per_cpu``) or variance (``max_sd``) of each candidate."""
        if acquisition == "max_sd":
            return self.var / self.noise
        return np.sum(self.covRC**2, axis=0) / (self.var + self.noise_c) / self.noise

    def add(self, j: int) -> None:
        c = self.cov_C(j)
        denom = np.sqrt(c[j] + self.noise_c[j])
        u = c / denom
        if self.has_R:
            self.covRC = self.covRC - np.outer(self.covRC[:, j] / denom, u)
        self.var = np.maximum(self.var - u**2, 0.0)
        self.us.append(u)


def choose_batch(models: Sequence, n: int, seed: int, done: np.ndarray | None = None,
                 n_candidates: int = 4096, acquisition: str = "ivr",
                 reference: np.ndarray | None = None, ranges: Design | Mapping | None = None,
                 max_reference: int = 1024, pending: np.ndarray | None = None,
                 cost: Callable[[np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    """The next ``n`` design points (physical units, NAMES order) for the fitted ``models``.

    ``done``: the finished (or already scheduled) cases, physical units: used by the fallback's
    exclusion radius (the GP already knows its training cases).  ``reference``: where the map is
    read (``map_criteria.map_grids`` stacked), needed by ``ivr``; a seeded subset of at most
    ``max_reference`` of them is used.  ``pending``: points already in this batch (physical
    units, e.g. its LDS share), conditioned on before the picks (GP models only). ``cost``:
    predicted CPU seconds of cases at physical points (``cost.PlannedCost``), needed by
    ``ivr_per_cpu``.
    """
    if acquisition not in ACQUISITIONS:
        raise ValueError(f"acquisition {acquisition!r}; allowed: {list(ACQUISITIONS)}")
    if n < 1:
        raise ValueError(f"a batch needs n >= 1 (n = {n})")
    C = candidates(max(int(n_candidates), n), seed)
    per_cpu = acquisition == "ivr_per_cpu"
    if per_cpu and cost is None:
        raise ValueError("acquisition 'ivr_per_cpu' needs a cost model (cost=)")
    if not all(getattr(m, "has_covariance", False) for m in models):
        return _fallback(models, n, C, done, ranges)
    R = None
    if acquisition in ("ivr", "ivr_per_cpu"):
        if reference is None:
            raise ValueError("acquisition 'ivr' needs reference points (the map grids)")
        R = np.asarray(reference, float)
        if len(R) > max_reference:
            pick = np.random.default_rng([int(seed), 17]).choice(len(R), max_reference, replace=False)
            R = R[np.sort(pick)]
    n_cand = len(C)
    C = to_physical(C, ranges)
    if pending is not None and len(pending):
        C = np.vstack([C, np.asarray(pending, float)])
    # relative cost of each candidate (the median candidate's is 1): the reduction is divided by it
    relative_cost = np.ones(len(C))
    if per_cpu:
        c = np.asarray(cost(C), float)
        relative_cost = c / np.median(c[:n_cand])
    posts = [_Posterior(m, C, R) for m in models]
    for j in range(n_cand, len(C)):  # the pending points: update the posterior, never pick them
        for p in posts:
            p.add(j)
    chosen: list[int] = list(range(n_cand, len(C)))
    first = len(chosen)
    for _ in range(int(n)):
        score = sum(p.score(acquisition) for p in posts) / relative_cost
        score[chosen] = -np.inf
        j = int(np.argmax(score))
        chosen.append(j)
        for p in posts:
            p.add(j)
    return C[chosen[first:]]


def _fallback(models, n, C, done, ranges) -> np.ndarray:
    phys = to_physical(C, ranges)
    score = np.zeros(len(C))
    for m in models:
        _, sd = m.predict(phys, return_std=True)
        score += (np.asarray(sd, float) / max(float(m.noise_sd), 1e-12)) ** 2
    placed = [] if done is None else list(to_unit(np.asarray(done, float), ranges))
    radius = 0.5 * (len(placed) + n) ** (-1.0 / len(NAMES))
    chosen = []
    for j in np.argsort(-score):
        if all(np.linalg.norm(C[j] - p) >= radius for p in placed):
            chosen.append(j)
            placed.append(C[j])
            if len(chosen) == n:
                break
    if len(chosen) < n:  # the radius left too few: fill with the next best
        rest = [j for j in np.argsort(-score) if j not in chosen]
        chosen += rest[: n - len(chosen)]
    return phys[chosen]
