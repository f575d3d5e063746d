"""``--encoding NAME`` (``[data] encoding``): a log in an encoding the bytes do not give away, read as written."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groupfit.cli import main
from groupfit.model import ModelFile
from groupfit.textencoding import decode, misread

DATASETS = Path(__file__).resolve().parents[1] / "datasets"
CZECH = {"time_s": "Čas (s)", "error_um": "Posunutí Z (µm)", "T1": "Teplota vřetena", "T2": "Teplota lože"}
COLUMNS = ["--time", CZECH["time_s"], "--error", CZECH["error_um"], "--temps", f"{CZECH['T1']},{CZECH['T2']}"]


def czech_log(tmp_path: Path, encoding: str) -> Path:
    """paper_cycle with Czech names, written in ``encoding`` (Windows-1250: a Czech or Polish Windows)."""
    path = tmp_path / f"log_{encoding}.csv"
    pd.read_csv(DATASETS / "paper_cycle.csv").rename(columns=CZECH).to_csv(path, index=False, encoding=encoding)
    return path


def fitted(tmp_path: Path, log: Path, *extra: str) -> ModelFile:
    out = tmp_path / f"fit_{log.stem}_{len(extra)}"
    assert main(["fit", "--data", str(log), *COLUMNS, "--p", "0", *extra, "--out", str(out), "--quiet"]) == 0
    return ModelFile.load(out / "model.json")


def test_a_windows_1250_log_is_read_with_its_encoding_as_the_same_log_in_utf8(tmp_path, capsys):
    log = czech_log(tmp_path, "cp1250")
    code = main(["fit", "--data", str(log), *COLUMNS, "--p", "0", "--out", str(tmp_path / "guessed")])
    err = capsys.readouterr().err.strip()  # Windows-1252 is the guess: Č reads È, ř reads ø
    assert code == 2 and len(err.splitlines()) == 1 and "column 'Čas (s)' not found" in err
    assert "'Èas (s)' is 'Čas (s)' in cp1250: give --encoding cp1250" in err
    model = fitted(tmp_path, log, "--encoding", "cp1250")
    truth = fitted(tmp_path, czech_log(tmp_path, "utf-8"))
    assert model.temps == truth.temps and model.error == truth.error == CZECH["error_um"]
    np.testing.assert_array_equal(model.coefficients, truth.coefficients)
    replays = []
    for data, extra in ((log, ["--encoding", "cp1250"]), (czech_log(tmp_path, "utf-8"), [])):
        out = tmp_path / f"replay_{data.stem}.json"
        model_file = tmp_path / "fit_log_cp1250_2" / "model.json"
        assert main(["replay", str(model_file), "--data", str(data), *extra, "--json", str(out)]) == 0
        replays.append(json.loads(out.read_text())["rms_um"])
    assert replays[0] == replays[1]


def test_the_encoding_may_come_from_the_configuration(tmp_path):
    log = czech_log(tmp_path, "cp1250")
    config = tmp_path / "run.toml"
    config.write_text(
        f'[data]\npath = "{log.name}"\ntime = "{CZECH["time_s"]}"\nerror = "{CZECH["error_um"]}"\n'
        f'temps = ["{CZECH["T1"]}", "{CZECH["T2"]}"]\nencoding = "cp1250"\n[model]\np = 0\n',
        encoding="utf-8",
    )
    assert main(["fit", str(config), "--out", str(tmp_path / "o"), "--quiet"]) == 0
    assert ModelFile.load(tmp_path / "o" / "model.json").temps[:2] == (CZECH["T1"], CZECH["T2"])  # then its stage


@pytest.mark.parametrize(
    "encoding, says",
    [
        ("klingon", "--encoding 'klingon': not a text encoding"),
        ("ascii", "not a readable CSV table ('ascii' codec can't decode byte 0xc8 in position 0"),
    ],
)
def test_an_unknown_encoding_or_bytes_outside_it_are_refused_in_one_line(tmp_path, capsys, encoding, says):
    log = czech_log(tmp_path, "cp1250")
    out = tmp_path / "o"
    assert main(["fit", "--data", str(log), *COLUMNS, "--encoding", encoding, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and says in err and not out.exists()


def test_a_byte_order_mark_is_read_past_in_the_encoding_given():
    assert decode("\ufefftime_s,T1\n".encode("utf-8"), "utf-8") == "time_s,T1\n"
    assert decode("Čas,Teplota\n".encode("cp1250"), "cp1250") == "Čas,Teplota\n"


@pytest.mark.parametrize(
    "asked, written_in",
    [("Čas (s)", "cp1250"), ("Sıcaklık", "cp1254"), ("Время", "koi8-r"), ("Θερμοκρασία", "cp1253")],
)
def test_a_name_misread_by_the_detection_is_found_with_the_encoding_it_was_written_in(asked, written_in):
    read = decode(asked.encode(written_in))  # Windows-1252 or Windows-1251: what the bytes look like
    assert read != asked
    assert misread(asked, ["T1", read, "error_um"]) == (read, written_in)
    assert misread(asked, ["T1", asked + "x", "error_um"]) is None and misread("T1", [read]) is None
