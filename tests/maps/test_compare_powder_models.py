"""tools/compare_powder_models.py on two synthetic band maps of known means and SDs: the change at a
diameter is adhesive - dry, its SD the two SDs in quadrature, and the recommendations side by side."""

import numpy as np
import pandas as pd
import pytest
from conftest import script_module

tool = script_module("tools/compare_powder_models.py")


def band(offset: float, sd: float) -> pd.DataFrame:
    rows = []
    for f in (0.15, 0.45):
        for d in np.linspace(10, 50, 41):
            rows.append({"f": f, "d_um": d, "h_um": 57.0, "v_mm_s": 6.1, "mfr": 0.01 * d + f + offset, "mfr_model_sd": sd,
                         "pd": 0.5 - 0.001 * d + offset, "pd_model_sd": sd, "supported": d > 12})
    return pd.DataFrame(rows)


def results(tmp_path, name, offset, sd, rec):
    (tmp_path / name / "maps").mkdir(parents=True)
    (tmp_path / name / "decisions").mkdir()
    band(offset, sd).to_csv(tmp_path / name / "maps" / "powder_band_map.csv", index=False)
    pd.DataFrame(rec).to_csv(tmp_path / name / "decisions" / "recommendations.csv", index=False)
    return tmp_path / name


def test_changes_and_recommendations(tmp_path):
    rec = [{"powder": "fine", "kind": "fastest", "status": "recommended", "recommended": True, "h_um": 65.0,
            "v_mm_s": 15.0, "probability": 0.99, "quality": 0.4}]
    dry = results(tmp_path, "dry", 0.0, 0.003, rec)
    adhesive = results(tmp_path, "adhesive", -0.05, 0.004, [{**rec[0], "h_um": 75.0, "probability": 0.91}])
    assert tool.main([str(dry), str(adhesive), "--out", str(tmp_path / "out")]) == 0
    changes = tool.at_diameters(tool.band_table(dry), tool.band_table(adhesive), ["mfr", "pd"])
    assert len(changes) == 2 * len(tool.DIAMETERS)
    assert changes["mfr_change"].to_numpy() == pytest.approx(-0.05)
    assert changes["pd_change_sd"].to_numpy() == pytest.approx(0.005)  # 3-4-5
    assert list(changes["supported_dry"][:2]) == [False, True]  # d 10 is beyond the data
    text = (tmp_path / "out" / "powder_models.md").read_text()
    assert "| fine | fastest | 65 um, 15 mm/s, P 0.99 | 75 um, 15 mm/s, P 0.91 |" in text
    assert (tmp_path / "out" / "powder_models.png").stat().st_size > 10_000


def test_names_label_the_two_runs(tmp_path):
    """--names labels the columns, the table and the change (second - first) of any two runs: one
    size against a size distribution, as issue 51's comparison runs it."""
    rec = [{"powder": "cut_15_45", "kind": "fastest", "status": "recommended", "recommended": True, "h_um": 70.0,
            "v_mm_s": 5.0, "probability": 0.95, "quality": 0.4}]
    one = results(tmp_path, "one", 0.0, 0.006, rec)
    psd = results(tmp_path, "psd", 0.02, 0.008, [{**rec[0], "status": "none meets", "recommended": False}])
    assert tool.main([str(one), str(psd), "--names", "one size", "span 1", "--title", "t", "--out",
                      str(tmp_path / "out")]) == 0
    changes = tool.at_diameters(tool.band_table(one), tool.band_table(psd), ["mfr"], ("one size", "span 1"))
    assert changes["mfr_change"].to_numpy() == pytest.approx(0.02)
    assert changes["mfr_change_sd"].to_numpy() == pytest.approx(0.010)  # 6-8-10
    text = (tmp_path / "out" / "powder_models.md").read_text()
    assert "change span 1 - one size" in text and "| mfr one size | mfr span 1 | change |" in text
    assert "| cut_15_45 | fastest | 70 um, 5 mm/s, P 0.95 | none |" in text
    with pytest.raises(SystemExit):
        tool.main([str(one), str(psd), "--names", "same", "same", "--out", str(tmp_path / "bad")])
