"""A known function as a draw source: every draw is the function itself (no model uncertainty)."""
from __future__ import annotations

import numpy as np


class FunctionDraws:
    """``fn(X) -> (n, len(targets))``; ``noise_sd``: per-target constant noise SD (default 0)."""

    def __init__(self, fn, targets, noise_sd=None):
        self.fn, self.targets = fn, tuple(targets)
        self.noise = dict(noise_sd or {t: 0.0 for t in self.targets})

    def draws(self, X, n, seed=0, targets=None):
        Y = np.asarray(self.fn(np.asarray(X, float)), float).reshape(len(X), -1)
        return {t: np.repeat(Y[None, :, self.targets.index(t)], n, axis=0) for t in (targets or self.targets)}

    def predict_stats(self, X):
        Y = np.asarray(self.fn(np.asarray(X, float)), float).reshape(len(X), -1)
        z = np.zeros(len(X))
        return {t: (Y[:, k], z, np.full(len(X), self.noise[t])) for k, t in enumerate(self.targets)}
