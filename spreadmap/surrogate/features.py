"""The inputs a model sees, from the design parameters in physical units.

``physics``: f, ln d, h/d, v. The gap in particle diameters is what decides whether powder passes
(a gap below one diameter jams by construction), and the diameter spans a factor of five, so its
logarithm spreads the small-particle end, where the response changes fastest. ``raw``: f, d, h, v.
Either is then standardised on the training cases (mean 0, SD 1 per column).
"""
from __future__ import annotations

import numpy as np

KINDS = ("physics", "raw")
LABELS = {"physics": ("f", "ln d", "h/d", "v"), "raw": ("f", "d", "h", "v")}


def features(X: np.ndarray, kind: str) -> np.ndarray:
    X = np.asarray(X, float)
    if kind == "raw":
        return X.copy()
    if kind != "physics":
        raise ValueError(f"inputs must be one of {KINDS}, got {kind!r}")
    f, d, h, v = X.T
    return np.column_stack([f, np.log(d), h / d, v])


class Standardiser:
    """Feature transform fitted on the training cases: z = (features(X) - mean) / sd."""

    def __init__(self, kind: str):
        self.kind = kind

    def fit(self, X: np.ndarray) -> "Standardiser":
        Z = features(X, self.kind)
        self.mean_ = Z.mean(axis=0)
        sd = Z.std(axis=0)
        self.sd_ = np.where(sd > 0, sd, 1.0)
        return self

    def __call__(self, X: np.ndarray) -> np.ndarray:
        return (features(X, self.kind) - self.mean_) / self.sd_
