"""The MLP ensemble's maps beside the map model's (rule maps_mlp, scripts/maps_mlp.py): drawn from a
small synthetic table with a real MLP ensemble and a real validation, each labelled with the MLP's
cross-validated RMSE over the noise SD from the validation table."""
import runpy
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
import synthetic_cases as syn
from conftest import ROOT
from figure_text import pdf_text

from spreadmap.maps import validation_note
from spreadmap.surrogate import fit_map_model, save_model, validate_surrogate

# a small, quick surrogate config: one MLP size and penalty (no inner choice), 4 members, one repeat
SMALL = {"model": "gp", "cv_repeats": 1, "ensemble_members": 4, "mlp_sizes": [4], "mlp_alphas": [1.0],
         "neurons": [4], "seeds": [0], "learning_curve": False}


def validation_table(rows):
    cols = ["target", "model", "n_cases", "repeats", "rmse", "noise_sd", "rmse_over_noise"]
    return pd.DataFrame(rows, columns=cols)


def test_the_note_reads_each_targets_ratio_from_the_table():
    val = validation_table([
        ("mfr", "gp", 96, 3, 0.016, 0.0125, 1.28), ("mfr", "mlp", 96, 3, 0.030, 0.0125, 2.40),
        ("pd", "gp", 96, 3, 0.020, 0.0100, 2.00), ("pd", "mlp", 96, 3, 0.031, 0.0100, 3.10)])
    note = validation_note(val, "mlp", ["mfr", "pd"], n_cases=96, other="gp")
    assert note == ("Drawn from the MLP ensemble: its CV RMSE / one run's noise SD over 96 cases (k-fold, 3 repeats):\n"
                    "MFR 2.40 (0.03 / 0.0125), PD 3.10 (0.031 / 0.01); the GP's 1.28, 2.00")
    assert validation_note(val, "gp", ["pd"]).endswith("PD 2.00 (0.02 / 0.01)")


def test_the_note_refuses_another_tables_validation():
    val = validation_table([("mfr", "gp", 96, 3, 0.016, 0.0125, 1.28), ("mfr", "mlp", 96, 3, 0.03, 0.0125, 2.4)])
    with pytest.raises(ValueError, match="0 rows of model 'mlp' for target 'pd'"):
        validation_note(val, "mlp", ["mfr", "pd"])
    with pytest.raises(ValueError, match="not this table's validation"):
        validation_note(val, "mlp", ["mfr"], n_cases=125)


@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    """scripts/maps_mlp.py run as rule maps_mlp runs it, on a 40-case synthetic table: the MLP map
    model (scripts/surrogate.py's fit with model_kind mlp) and the table's validation."""
    tmp = tmp_path_factory.mktemp("mlp_maps")
    table = syn.table(40, 0.07, seed=5)
    table.to_csv(tmp / "table.csv", index=False)
    model = fit_map_model(table, {**SMALL, "model": "mlp"}, log=lambda *a: None)
    save_model(model, tmp / "model_mlp.joblib")
    val = validate_surrogate(table, SMALL, log=lambda *a: None).validation
    val.to_csv(tmp / "surrogate_metrics.csv", index=False)
    smk = SimpleNamespace(
        input=SimpleNamespace(model=str(tmp / "model_mlp.joblib"), table=str(tmp / "table.csv"),
                              validation=str(tmp / "surrogate_metrics.csv")),
        output=SimpleNamespace(machine_map=str(tmp / "maps" / "machine_map_mlp.png"),
                               powder_band_map=str(tmp / "maps" / "powder_band_map_mlp.png")),
        params=SimpleNamespace(maps={"machine": {"n_h": 3, "n_v": 3}}, floor="test floor", ranges=None,
                               noise_model=None, noise_calibration=[], counting_c=0.37),
        log=[])
    runpy.run_path(str(ROOT / "scripts" / "maps_mlp.py"), init_globals={"snakemake": smk})
    return tmp, model, val


def test_the_mlp_maps_are_drawn_from_the_mlp_with_its_validation_on_them(drawn):
    tmp, model, val = drawn
    assert set(model.metadata["map_model"].values()) == {"mlp"}
    mlp = val[val["model"] == "mlp"].set_index("target")
    gp = val[val["model"] == "gp"].set_index("target")
    for name in ("machine_map_mlp", "powder_band_map_mlp"):
        for ext in ("png", "pdf", "csv"):
            assert (tmp / "maps" / f"{name}.{ext}").stat().st_size > 0
        text = " ".join(pdf_text(tmp / "maps" / f"{name}.pdf").split())
        assert "Drawn from the MLP ensemble: its CV RMSE / one run's noise SD over 40 cases" in text, text[:2000]
        for t, label in (("mfr", "MFR"), ("pd", "PD")):  # the table's numbers, RMSE / noise SD
            ratio = mlp.loc[t, "rmse"] / mlp.loc[t, "noise_sd"]
            assert f"{label} {ratio:.2f} ({mlp.loc[t, 'rmse']:.3g} / {mlp.loc[t, 'noise_sd']:.3g})" in text
        assert f"the GP's {gp.loc['mfr', 'rmse_over_noise']:.2f}, {gp.loc['pd', 'rmse_over_noise']:.2f}" in text
    # the machine map's numbers are the MLP ensemble's: its members' mean at each setting (y: pd, the
    # table having no layer measure)
    grid = pd.read_csv(tmp / "maps" / "machine_map_mlp.csv")
    X = grid[["f", "d_um", "h_um", "v_mm_s"]].to_numpy()
    members = model.models["pd"]._members(X)
    np.testing.assert_allclose(grid["pd"], members.mean(axis=0), rtol=1e-9)
    np.testing.assert_allclose(grid["pd_model_sd"], members.std(axis=0, ddof=1), rtol=1e-9)
    assert len(grid) == 9 and set(grid["floor"]) == {"test floor"}
