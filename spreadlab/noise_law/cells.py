"""Seed-repeat cells: the same design point and scene run with several packing seeds.

A cell is one design point (f, d, h, v) at one scene variant (a preset, a benchmark arm or a knob
setting) with k >= 2 usable seeds (status ok, not flagged). For each target (MFR, PD) a cell gives
the sample variance s^2 over its seeds with k - 1 degrees of freedom, the seeds' mean value and
the mean count N the case's counting law uses (`n_passed` for MFR, `n_pd` for PD), the RMS of
the noise SDs the cases stated, and each seed's deviation from the cell's mean scaled by
sqrt(k / (k - 1)), whose SD is then that of one case (`dev`, for the coverage of a case's interval).
`published_cells` assembles every seed repeat of the published tables under docs/ that ran the
shipped scene (rough substrate, the pile's standing reserve or, for `window8`, without it), and,
apart, the arms of other scenes the law is checked against.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from spreadmap.design import NAMES, h_over_d
from spreadmap.noise_law.apply import COUNT  # the count behind each target's counting law: mfr, pd
from spreadmap.table import usable_cases as usable


def point_key(frame: pd.DataFrame) -> pd.Series:
    """A design point's label, the same for the same (f, d, h, v) in every table."""
    return (frame["f"].round(4).map("{:.4f}".format) + "/" + frame["d_um"].round(3).map("{:.3f}".format) + "/"
            + frame["h_um"].round(3).map("{:.3f}".format) + "/" + frame["v_mm_s"].round(4).map("{:.4f}".format))


def with_pd_count(cases: pd.DataFrame) -> pd.DataFrame:
    """`n_pd` where a table lacks it, from the stated PD SD and the c the row stated with (the c of
    its MFR SD: both SDs of a case use one c): n_pd = (c x PD / pd_sd)^2."""
    if "n_pd" in cases and cases["n_pd"].notna().all():
        return cases
    out = cases.copy()
    c = out["mfr_sd"] / out["mfr"] * np.sqrt(out["n_passed"])
    derived = (c * out["pd"] / out["pd_sd"]) ** 2
    out["n_pd"] = out["n_pd"].fillna(derived) if "n_pd" in out else derived
    return out


def seed_cells(cases: pd.DataFrame) -> pd.DataFrame:
    """One row per (cell, target) from cases with `source` and `variant` columns: the usable cases
    grouped by design point and scene variant. A cell whose cases come from several tables names
    them all in `source` (joined by '+')."""
    cases = with_pd_count(usable(cases))
    cases = cases.assign(point=point_key(cases))
    rows = []
    for (point, var), cell in cases.groupby(["point", "variant"], sort=True):
        k = len(cell)
        if k < 2:  # one seed says nothing of the spread
            continue
        first = cell.iloc[0]
        source = "+".join(dict.fromkeys(cell["source"]))
        for target, count in COUNT.items():
            values = cell[target].to_numpy(float)
            rows.append({"source": source, "variant": var, "point": point, "target": target,
                         **{p: float(first[p]) for p in NAMES}, "h_over_d": float(h_over_d(first)),
                         "seeds": k, "dof": k - 1, "mean": float(values.mean()), "s2": float(values.var(ddof=1)),
                         # each seed's deviation from the cell mean, scaled to the SD of one case
                         "dev": tuple((values - values.mean()) * math.sqrt(k / (k - 1))),
                         "n": float(cell[count].mean()),
                         "stated_rms": float(math.sqrt(np.mean(cell[f"{target}_sd"].to_numpy(float) ** 2)))})
    return pd.DataFrame(rows)


def pooled_cases(tables: list[tuple[pd.DataFrame, str, str]]) -> pd.DataFrame:
    """The cases of several tables, each (table, source, variant column or a variant name), with
    the variants' aliases resolved and each case (point, variant, seed) once: the same scene, point
    and seed is the same case, whichever table published it (YADE runs repeat exactly)."""
    frames = []
    for table, source, variant in tables:
        frame = table.copy()
        frame["variant"] = frame[variant].astype(str) if variant in frame else variant
        frames.append(frame.assign(source=source))
    cases = pd.concat(frames, ignore_index=True)
    cases["variant"] = cases["variant"].replace(ALIASES)
    cases = cases.assign(point=point_key(cases)).drop_duplicates(["point", "variant", "seed"])
    # and no case twice under two names: identical results at the same point and seed
    twins = cases.duplicated(["point", "seed", "mfr", "pd"], keep=False)
    if twins.any():
        raise ValueError("the same case under two scene variants: "
                         f"{sorted(set(cases.loc[twins, 'variant']))} at {sorted(set(cases.loc[twins, 'point']))}")
    return cases.drop(columns="point")


def study_repeats(study: Path, name: str) -> pd.DataFrame:
    """The study's seed repeats `name` (seeds 2-4) with each point's seed-1 case from the LDS sweep
    or the loop."""
    repeats = pd.read_csv(study / name)
    firsts = pd.concat([pd.read_csv(study / "cases_lds.csv"), pd.read_csv(study / "cases_converge.csv")])
    firsts = firsts[(firsts["seed"] == 1) & point_key(firsts).isin(set(point_key(repeats)))].drop_duplicates("case_id")
    return pd.concat([repeats, firsts], ignore_index=True)


# Names of one scene: docs/precision's `shipped` arm is the `default` preset as it ships (its seeds
# 1-3 at the fidelity points are the fidelity study's default cases), and the fidelity knob
# target_cv 0.06 is the re-tuned `fast` preset (the same cases).
ALIASES = {"shipped": "default", "default_target_cv_0p06": "fast"}

# Scenes other than the shipped one, in docs/precision: checked against the law, never fitted.
OTHER_ARMS = {"precision": "rough floor, a 226-sphere window (c 0.45), cheaper settle, no standing reserve",
              "precision_slow_settle": "`precision` with the old settle and relax",
              "physics": "rough floor, the old fixed 8 d window on a 5 d bed, old settle",
              "today": "flat floor, the old fixed 8 d window on a 5 d bed"}


def published_cells(docs: Path) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(cells of the shipped scene, cells of the other scenes) from the published tables.

    Parameters
    ----------
    docs : pathlib.Path
        The repository's docs/ folder (its study/, fidelity/ and precision/ tables are read).

    Returns
    -------
    shipped : pandas.DataFrame
        The seed-repeat cells (``seed_cells``: one row per cell and target) of the shipped scene.
    other : pandas.DataFrame
        The cells of the arms of other scenes (``OTHER_ARMS``), to check the law against.

    Raises
    ------
    FileNotFoundError
        If a published table is missing.
    ValueError
        If the same case appears under two scene variants (``pooled_cases``).
    """
    docs = Path(docs)
    study, fidelity = docs / "study", docs / "fidelity"
    knobs = pd.read_csv(fidelity / "cases_knobs.csv")
    precision = pd.read_csv(docs / "precision" / "cases.csv")
    shipped = pooled_cases([
        (pd.read_csv(study / "cases_heldout.csv"), "study_heldout", "default"),
        (pd.read_csv(study / "cases_heldout2.csv"), "study_heldout2", "default"),
        (study_repeats(study, "thin_gap_seeds.csv"), "study_thin_gap", "default"),
        (study_repeats(study, "wide_gap_seeds.csv"), "study_wide_gap", "default"),
        (pd.read_csv(fidelity / "cases_presets.csv"), "fidelity_presets", "preset"),
        (knobs, "fidelity_knobs", "preset"),  # its base rows are the presets table's default cases
        (pd.read_csv(fidelity / "fast_density1e4.csv"), "fidelity_fast_density1e4", "fast_density1e4"),
        (precision[precision["arm"].isin(["window8", "shipped"])], "precision", "arm"),
    ])
    other = pooled_cases([(precision[precision["arm"].isin(list(OTHER_ARMS))], "precision", "arm")])
    return seed_cells(shipped), seed_cells(other)


# The adhesive default scene (issue 49, shipped since 2026-12-06): DMT adhesion, surface energy
# 1e-4 J/m^2 at the `default` preset's density x1000 (the surface energy scaled with it: the Bond
# number kept), rough floor, one size, the standing heap `scene.pile_reserve`. Its seed repeats, by
# published table: (path under docs/, source name, the arm of the shipped scene or None for a table
# whose scene is read from its columns, the pile reserve [h^2] the table's cases ran at or None where
# a column says). A table that is absent is skipped (docs/heap_size is appended by a benchmark).
ADHESIVE_TABLES = (
    ("adhesion/scaling_cases.csv", "adhesion_scaling", "adh_x1000", 4.7),
    ("size_distribution/cost_cases.csv", "psd_cost", "one_size", 4.7),
    ("heap_size/cases.csv", "heap_size", None, None),
)
ADHESIVE_VARIANT = "adhesive"
PRESET_PREFIX = "default-"  # a `default` case's id; another density scale is a preset of its own (`default_density_scale_100-`)


def adhesive_cases(docs: Path, *, pile_reserve: float, surface_energy: float, material: dict,
                   tables: dict | None = None) -> pd.DataFrame:
    """The published cases of the adhesive default scene, each case once (``pooled_cases``).

    A row is of the scene when: its arm is the table's shipped arm (`ADHESIVE_TABLES`; a table of
    one scene variant per arm), or, for docs/heap_size, its columns say rough floor and this
    `pile_reserve`; it ran the `default` preset (its case id), spheres of one size (``size_span`` 0
    where the table has it), and its recorded Bond number is that of `surface_energy` at its d
    (``spreadmap.case.powder.bond_number``, within 1e-4 relative; at another surface energy, or dry,
    it differs). A table run at another pile reserve is left out. The same point and seed published
    in two tables must have the same MFR and PD (YADE repeats a run exactly): otherwise the tables'
    scenes differ and a ValueError says where.

    Parameters
    ----------
    docs : pathlib.Path
        The repository's docs/ folder.
    pile_reserve : float
        The scene's standing heap, the config's ``scene.pile_reserve`` [h^2].
    surface_energy : float
        The scene's ``material.surface_energy_j_m2`` [J/m^2].
    material : dict
        The config's ``material`` (``density_kg_m3``, ``gravity_m_s2``).
    tables : dict or None, optional
        Paths that replace a table of `ADHESIVE_TABLES` (by its path under docs/), e.g. a
        benchmark's table before it is committed.

    Returns
    -------
    pandas.DataFrame
        The cases (usable or not: ``seed_cells`` keeps the usable ones), with ``source`` and
        ``variant`` (`ADHESIVE_VARIANT`).

    Raises
    ------
    ValueError
        If a shipped arm's rows are not of the scene (wrong preset, size or Bond number), or the
        same case reads differently in two tables.
    """
    from spreadmap.case.powder import bond_number

    tables = {k: Path(v) for k, v in (tables or {}).items()}
    picked = []
    for rel, source, arm, reserve in ADHESIVE_TABLES:
        path = tables.get(rel, Path(docs) / rel)
        if not path.exists() or (reserve is not None and not math.isclose(reserve, pile_reserve)):
            continue
        table = pd.read_csv(path)
        if arm is not None:
            rows = table[table["arm"] == arm]
        else:
            rows = table[(table["floor"] == "rough") & np.isclose(table["pile_reserve"], pile_reserve)]
        rows = rows[rows["case_id"].str.startswith(PRESET_PREFIX)]
        expected = np.array([bond_number(surface_energy, material["density_kg_m3"], material["gravity_m_s2"], d * 1e-6)
                             for d in rows["d_um"]])
        scene = np.isclose(rows["bond_number"].to_numpy(float), expected, rtol=1e-4)
        if "size_span" in rows:
            scene &= (rows["size_span"] == 0).to_numpy()
        if arm is not None and not scene.all():
            raise ValueError(f"{rel}: arm {arm} holds cases not of the adhesive default scene "
                             f"(surface energy {surface_energy:g} J/m^2, one size): {list(rows['case_id'][~scene])}")
        if scene.any():
            picked.append(rows[scene].assign(source=source, variant=ADHESIVE_VARIANT))
    if not picked:
        return pd.DataFrame()
    cases = pd.concat(picked, ignore_index=True)
    cases["point"] = point_key(cases)
    twins = cases[cases.duplicated(["point", "seed"], keep=False)]
    for (point, seed), same in twins.groupby(["point", "seed"]):
        if not (np.allclose(same["mfr"], same["mfr"].iloc[0], rtol=0, atol=1e-12)
                and np.allclose(same["pd"], same["pd"].iloc[0], rtol=0, atol=1e-12)):
            raise ValueError(f"point {point} seed {seed} reads differently in {list(same['source'])}: not one scene")
    # one row per case, its source naming every table that published it
    sources = cases.groupby(["point", "seed"], sort=False)["source"].agg(lambda s: "+".join(dict.fromkeys(s)))
    cases = cases.drop_duplicates(["point", "seed"]).drop(columns="source")
    return cases.join(sources, on=["point", "seed"]).drop(columns="point").reset_index(drop=True)


def adhesive_cells(docs: Path, **kwargs) -> pd.DataFrame:
    """The seed-repeat cells of the adhesive default scene.

    Parameters
    ----------
    docs : pathlib.Path
        The repository's docs/ folder.
    **kwargs : dict
        ``adhesive_cases``'s keyword arguments (pile_reserve, surface_energy, material, tables).

    Returns
    -------
    pandas.DataFrame
        ``seed_cells`` of ``adhesive_cases`` (one row per cell and target); empty without cases.
    """
    cases = adhesive_cases(docs, **kwargs)
    return seed_cells(cases) if len(cases) else pd.DataFrame()
