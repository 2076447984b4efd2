"""Case identity. A case is its content: the design point (at the precision simulated), the
preset and the packing seed. Two requests for the same content are the same case, run once."""
from __future__ import annotations

import re

# Precision at which a design point is simulated (and named).
DECIMALS = {"f": 4, "d_um": 3, "h_um": 3, "v_mm_s": 4}
CASE_ID_PATTERN = r"[a-z][a-z0-9_]*-f\d+\.\d{4}-d\d+\.\d{3}-h\d+\.\d{3}-v\d+\.\d{4}-s\d+"


def rounded(point: dict) -> dict:
    """The design point as simulated: each parameter rounded to DECIMALS."""
    return {k: round(float(point[k]), n) for k, n in DECIMALS.items()}


def case_id(point: dict, preset: str, seed: int) -> str:
    p = rounded(point)
    return f"{preset}-f{p['f']:.4f}-d{p['d_um']:.3f}-h{p['h_um']:.3f}-v{p['v_mm_s']:.4f}-s{int(seed)}"


def parse_case_id(cid: str) -> tuple[dict, str, int]:
    """Inverse of case_id: (point, preset, seed)."""
    m = re.fullmatch(r"([a-z][a-z0-9_]*)-f([\d.]+)-d([\d.]+)-h([\d.]+)-v([\d.]+)-s(\d+)", cid)
    if not m:
        raise ValueError(f"not a case id: {cid!r} (expected e.g. default-f0.3000-d30.000-h65.000-v10.0000-s1)")
    preset, f, d, h, v, seed = m.groups()
    return {"f": float(f), "d_um": float(d), "h_um": float(h), "v_mm_s": float(v)}, preset, int(seed)
