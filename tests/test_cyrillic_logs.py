"""Logs written on a Russian or Ukrainian Windows: Windows-1251 bytes, names in Cyrillic (the log read on the columns
its names mark: ``test_east_asian_logs.py``)."""

import numpy as np
import pandas as pd
import pytest

from groupfit.columns import is_ambient_name
from groupfit.data import load_run
from groupfit.textencoding import decode

TEMPS = ["T1", "T2", "T3", "T4"]


def header(names) -> str:
    return ",".join(names) + "\n1,2,3\n"


@pytest.mark.parametrize(
    "names, encoding",
    [
        (["Время", "Температура 1", "Смещение"], "cp1251"),
        (["Время (с)", "Т1", "Т2", "Ошибка (мкм)"], "cp1251"),
        (["Темп", "Датчик"], "cp1251"),  # every word of even length: pairs of bytes, as GBK writes them
        (["Дата", "Темп"], "cp1251"),
        (["Температура", "°C", "Ёмкость"], "cp1251"),
        (["Час", "Температура"], "cp1251"),  # Ukrainian
        (["Température (°C)", "Größe T2 [°C]", "Verlagerung [µm]"], "cp1252"),
        (["Außentemperatur ÄÖÜ (°C)", "Öl ÖÄ", "T1 °C"], "cp1252"),
        (["时间(s)", "温度1(℃)", "Z向热误差(μm)"], "gbk"),
        (["经过时间", "主轴温度", "床身温度"], "gbk"),
        (["経過時間", "主軸温度(℃)", "変位(μm)"], "cp932"),
    ],
)
def test_a_log_is_read_in_the_encoding_that_wrote_it(names, encoding):
    text = header(names)
    assert decode(text.encode(encoding)) == text


def test_a_russian_date_column_is_the_time(tmp_path, synthetic):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    stamps = pd.Timestamp("2026-03-02 08:00:00") + pd.to_timedelta(frame["time_s"], unit="s")
    frame.assign(time_s=stamps.dt.strftime("%d.%m.%Y %H:%M:%S")).rename(columns={"time_s": "Дата и время"}).to_csv(
        path, index=False, encoding="cp1251"
    )
    run = load_run(path, temps=TEMPS, time_is_default=True)
    assert run.time_name == "Дата и время"
    np.testing.assert_allclose(run.time, plain.time - plain.time[0], atol=1e-9)


def test_the_air_named_in_russian_is_the_ambient():
    assert all(is_ambient_name(name) for name in ("Температура воздуха", "Температура в цехе", "Окружающая среда"))
    assert not any(is_ambient_name(name) for name in ("Температура шпинделя", "Температура станины"))
