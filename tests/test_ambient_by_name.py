"""The run's ambient found by its name when it is not called T_amb: the same default reference, with a note."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.default_columns import ambient_columns

DATASETS = Path(__file__).resolve().parents[1] / "datasets"


def fitted(tmp_path: Path, name: str, frame: pd.DataFrame, *args) -> tuple[dict, str]:
    path = tmp_path / f"{name}.csv"
    frame.to_csv(path, index=False)
    out = tmp_path / f"{name}.json"
    code = main(["fit", "--data", str(path), "--quiet", "--json", str(out), "--out", str(tmp_path / name), *args])
    assert code == 0
    return json.loads(out.read_text()), name


@pytest.fixture(scope="module")
def shipped() -> pd.DataFrame:
    return pd.read_csv(DATASETS / "paper_cycle.csv")


@pytest.mark.parametrize(
    "name", ["Room [°C]", "Ambient", "T_air", "hall temp", "room_degC", "Umgebung [°C]", "Raumtemperatur", "T_Umgebung"]
)
def test_an_ambient_of_another_name_is_the_reference_t_amb_would_be(tmp_path, shipped, name, capsys):
    reference, _ = fitted(tmp_path, "t_amb", shipped)
    assert reference["reference"] == "T_amb"
    renamed, _ = fitted(tmp_path, "renamed", shipped.rename(columns={"T_amb": name}))
    assert f"note    reference '{name}': the run's ambient, found by its name" in capsys.readouterr().out
    assert renamed["reference"] == name
    assert renamed["temps"] == [t.replace("T_amb", name) for t in reference["temps"]]
    assert renamed["p"] == reference["p"]
    assert np.allclose(renamed["coefficients"], reference["coefficients"], rtol=0, atol=1e-12)


def test_a_named_reference_and_none_are_kept_and_no_note_is_printed(tmp_path, shipped, capsys):
    frame = shipped.rename(columns={"T_amb": "Room [°C]"})
    absolute, _ = fitted(tmp_path, "none", frame, "--reference", "none")
    start, _ = fitted(tmp_path, "start", frame, "--reference", "start")
    assert absolute.get("reference") is None and start["reference"] == "start"
    assert "found by its name" not in capsys.readouterr().out


def test_several_ambients_leave_the_inputs_absolute_and_are_named(tmp_path, shipped, capsys):
    frame = shipped.rename(columns={"T_amb": "Room [°C]"})
    frame["Ambient rear [°C]"] = frame["Room [°C]"] + 0.3
    model, _ = fitted(tmp_path, "two", frame)
    assert model.get("reference") is None
    out = capsys.readouterr().out
    assert "several columns are named as the air's temperature (Room [°C], Ambient rear [°C])" in out
    named, _ = fitted(tmp_path, "named", frame, "--ambient", "Ambient rear [°C]")
    assert named["reference"] == "Ambient rear [°C]"


def test_what_is_not_the_air_temperature_is_not_taken():
    n = 5
    frame = pd.DataFrame(
        {
            "T1": np.arange(n, dtype=float),
            "air_pressure_bar": np.full(n, 6.0),
            "room humidity %": np.full(n, 40.0),
            "hall_fan_speed_rpm": np.full(n, 900.0),
            "airflow": np.full(n, 2.0),
            "Umgebungsfeuchte [%]": np.full(n, 40.0),
            "Arbeitsraum [°C]": np.linspace(22.0, 25.0, n),  # inside the machine's enclosure, not the air outside
            "Room [°C]": [20.0, 20.1, np.nan, 20.2, 20.2],  # a reading missed: not a reference for every row
        }
    )
    assert ambient_columns(frame) == []
    frame["ambient"] = 21.0
    assert ambient_columns(frame) == ["ambient"]
    assert ambient_columns(frame, inputs=["ambient"]) == []  # an input is never its own reference
