"""Case identity. A case is its content: the design point (at the precision simulated), the
preset and the packing seed. Two requests for the same content are the same case, run once."""
from __future__ import annotations

# Precision at which a design point is simulated (and named).
DECIMALS = {"f": 4, "d_um": 3, "h_um": 3, "v_mm_s": 4}
CASE_ID_PATTERN = r"[a-z][a-z0-9_]*-f\d+\.\d{4}-d\d+\.\d{3}-h\d+\.\d{3}-v\d+\.\d{4}-s\d+"


def rounded(point: dict) -> dict:
    """The design point as simulated: each parameter rounded to DECIMALS."""
    return {k: round(float(point[k]), n) for k, n in DECIMALS.items()}


def case_id(point: dict, preset: str, seed: int) -> str:
    p = rounded(point)
    return f"{preset}-f{p['f']:.4f}-d{p['d_um']:.3f}-h{p['h_um']:.3f}-v{p['v_mm_s']:.4f}-s{int(seed)}"
