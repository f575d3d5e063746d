"""Logs written on a Chinese, Japanese, Korean or Russian system: GBK, Shift-JIS, CP949 or Windows-1251 bytes, names
in their language."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from support import same_run

from groupfit.columns import is_ambient_name
from groupfit.data import load_run
from groupfit.textencoding import decode

TEMPS = ["T1", "T2", "T3", "T4"]
CHINESE = {"time_s": "时间(s)", "T1": "主轴温度1(℃)", "T2": "主轴温度2(℃)", "T3": "床身温度(℃)", "T4": "立柱温度(℃)"}
KOREAN = {"time_s": "경과시간(초)", "T1": "주축 온도1(℃)", "T2": "주축 온도2(℃)", "T3": "베드 온도", "T4": "칼럼 온도"}
JAPANESE = {"time_s": "経過時間[s]", "T1": "主軸温度1(℃)", "T2": "主軸温度2(℃)", "T3": "ベッド温度", "T4": "コラム温度"}


def header(names) -> str:
    return ",".join(names) + "\n1,2,3\n"


@pytest.mark.parametrize(
    "names, encoding",
    [
        (["时间(s)", "温度1(℃)", "Z向热误差(μm)"], "gbk"),
        (["时间(s)", "温度1(℃)", "Z向热误差(μm)"], "gb18030"),
        (["时间", "主轴温度", "位移（μm）"], "gbk"),
        (["T1(℃)", "T2(℃)"], "gbk"),  # no word in Chinese: the sign marks it
        (["経過時間", "主軸温度(℃)", "変位(μm)"], "cp932"),
        (["日時", "スピンドル温度", "ベッド温度"], "cp932"),
        (["時間(s)", "spindle(RPM)", "t1(°C)", "溫度1(°C)", "熱變位(um)"], "cp950"),
        (["时间", "溫度", "熱誤差"], "gbk"),  # traditional characters in GBK: beyond GB 2312
        (["时间(s)", "温度1(℃)"], "utf-8"),
        (["時間", "温度"], "utf-16"),
        (["시간(초)", "온도1(℃)", "Z축 열변위(μm)"], "cp949"),
        (["경과시간", "스핀들 온도", "베드 온도", "냉각수 온도", "실내온도"], "euc-kr"),
        (["일시", "모터 온도", "X축 변위"], "cp949"),
        (["传感器1", "传感器2"], "gbk"),  # reads as Hangul in EUC-KR (눈먁포), of syllables no Korean word uses
        (["长度", "编号", "测点"], "gbk"),  # the same
        (["Température (°C)", "Größe T2 [°C]", "Verlagerung [µm]"], "cp1252"),
        (["Außentemperatur ÄÖÜ (°C)", "Öl ÖÄ", "T1 °C"], "cp1252"),
        (["Temp. 1 [°F]", "ΔT"], "utf-8"),
    ],
)
def test_a_log_is_read_in_the_encoding_that_wrote_it(names, encoding):
    text = header(names)
    assert decode(text.encode(encoding)) == text


RUSSIAN = {
    "time_s": "Время (с)",
    "T1": "Температура шпинделя 1 (°C)",
    "T2": "Температура шпинделя 2 (°C)",
    "T3": "Температура станины",
    "T4": "Температура колонны",
}


@pytest.mark.parametrize(
    "names, error_name, encoding",
    [
        (CHINESE, "Z向热误差(μm)", "gbk"),
        (CHINESE, "Z向热误差(μm)", "utf-8-sig"),
        (KOREAN, "Z축 열변위(μm)", "cp949"),
        (RUSSIAN, "Тепловое смещение Z (мкм)", "cp1251"),
    ],
)
def test_a_log_is_read_on_the_columns_its_names_mark_and_gives_the_plain_run(
    tmp_path, synthetic, names, error_name, encoding
):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    frame.rename(columns={**names, "error_um": error_name}).to_csv(path, index=False, encoding=encoding)
    run = load_run(path, time_is_default=True, error_is_default=True)
    assert run.temp_names == tuple(names[t] for t in TEMPS)
    assert (run.time_name, run.error_name) == (names["time_s"], error_name)
    same_run(run, plain)


def test_a_japanese_log_in_shift_jis_with_its_stamps_gives_the_plain_run(tmp_path, synthetic):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    stamps = pd.Timestamp("2026-03-02 08:00:00") + pd.to_timedelta(frame["time_s"], unit="s")
    named = frame.rename(columns={**JAPANESE, "error_um": "Z軸変位(μm)"}).drop(columns="経過時間[s]")
    named.insert(0, "日時", stamps.dt.strftime("%Y/%m/%d %H:%M:%S"))
    named.to_csv(path, index=False, encoding="cp932")
    run = load_run(path, time_is_default=True, error_is_default=True)
    assert run.temp_names == tuple(JAPANESE[t] for t in TEMPS)
    assert (run.time_name, run.error_name) == ("日時", "Z軸変位(μm)")
    np.testing.assert_array_equal(run.temps, plain.temps)
    np.testing.assert_array_equal(run.error, plain.error)
    np.testing.assert_allclose(run.time, plain.time - plain.time[0], atol=1e-9)


@pytest.mark.parametrize(
    "error_name, per_um, time_name, per_second, encoding",
    [
        ("位移(mm)", 1e-3, "时间(分钟)", 1 / 60, "gbk"),
        ("位移（毫米）", 1e-3, "时间（秒）", 1.0, "gbk"),
        ("热漂移（nm）", 1e3, "采样时间(小时)", 1 / 3600, "gbk"),
        ("変位[μm]", 1.0, "時間(分)", 1 / 60, "cp932"),
        ("Смещение (мм)", 1e-3, "Время, мин", 1 / 60, "cp1251"),
        ("Погрешность, мкм", 1.0, "Время (ч)", 1 / 3600, "cp1251"),
    ],
)
def test_units_named_in_chinese_japanese_russian_or_in_full_width_brackets_are_read(
    tmp_path, synthetic, error_name, per_um, time_name, per_second, encoding
):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    frame.assign(error_um=frame["error_um"] * per_um, time_s=frame["time_s"] * per_second).rename(
        columns={"error_um": error_name, "time_s": time_name}
    ).to_csv(path, index=False, encoding=encoding)
    run = load_run(path, temps=TEMPS, time_is_default=True, error_is_default=True)
    assert (run.time_name, run.error_name) == (time_name, error_name)
    np.testing.assert_allclose(run.error, plain.error, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(run.time, plain.time, rtol=1e-12)


def test_a_chinese_date_and_a_temperature_in_fahrenheit_are_read(tmp_path, synthetic):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    stamps = pd.Timestamp("2026-03-02 08:00:00") + pd.to_timedelta(frame["time_s"], unit="s")
    written = frame.assign(T1=frame["T1"] * 9 / 5 + 32).rename(columns={"T1": "主轴温度(℉)"})
    written["time_s"] = [f"{s.year}年{s.month}月{s.day}日 {s.hour}:{s.minute:02d}:{s.second:02d}" for s in stamps]
    written.rename(columns={"time_s": "日期时间"}).to_csv(path, index=False, encoding="gbk")
    run = load_run(path, temps=["主轴温度(℉)", "T2", "T3", "T4"], time_is_default=True)
    np.testing.assert_allclose(run.temps, plain.temps, atol=1e-9)
    np.testing.assert_allclose(run.time, plain.time - plain.time[0], atol=1e-9)


def test_the_air_named_in_chinese_or_japanese_is_the_ambient():
    assert all(is_ambient_name(name) for name in ("环境温度", "室温(℃)", "気温", "雰囲気温度", "環境温度"))
    assert not any(is_ambient_name(name) for name in ("主轴温度", "床身温度", "ベッド温度"))


def test_a_graphtec_log_in_japanese_with_its_milliseconds_gives_the_plain_run(tmp_path, synthetic):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    stamps = pd.Timestamp("2026-03-02 08:00:00") + pd.to_timedelta(np.arange(len(frame)) * 0.5, unit="s")
    named = frame.drop(columns="time_s").rename(columns={**JAPANESE, "error_um": "サンプリング変位(μm)"})
    named.insert(0, "ms", stamps.microsecond // 1000)
    named.insert(0, "日付 時間", stamps.strftime("%Y/%m/%d %H:%M:%S"))
    named.insert(0, "番号", np.arange(1, len(frame) + 1))
    path.write_bytes(("測定器,GL840\n\n" + named.to_csv(index=False)).encode("cp932"))
    run = load_run(path, time_is_default=True, error_is_default=True)
    assert (run.time_name, run.error_name) == ("日付 時間", "サンプリング変位(μm)")
    np.testing.assert_array_equal(run.temps, plain.temps)
    np.testing.assert_allclose(run.time, np.arange(len(frame)) * 0.5, atol=1e-9)


def test_a_taiwanese_log_in_big5_named_as_its_program_names_it_gives_the_plain_run(tmp_path, synthetic):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    named = frame.rename(columns={"time_s": "時間(s)", **{t: f"t{k}(°C)" for k, t in enumerate(TEMPS, 1)}})
    named = named.rename(columns={"error_um": "ch3(um)"}).assign(**{"ch1(um)": frame["error_um"] / 2})
    named.to_csv(path, index=False, encoding="cp950")
    run = load_run(path, error="ch3(um)", time_is_default=True)
    assert run.time_name == "時間(s)" and run.temp_names == ("t1(°C)", "t2(°C)", "t3(°C)", "t4(°C)")
    same_run(run, plain)


@pytest.mark.parametrize("time_name, per_second", [("시간(분)", 1 / 60), ("경과 시간 [초]", 1.0)])
def test_a_korean_date_and_units_of_time_are_read(tmp_path, synthetic, time_name, per_second):
    frame, plain = synthetic
    path = tmp_path / "log.csv"
    frame.assign(time_s=frame["time_s"] * per_second).rename(columns={"time_s": time_name}).to_csv(
        path, index=False, encoding="cp949"
    )
    run = load_run(path, temps=TEMPS, time_is_default=True)
    assert run.time_name == time_name
    np.testing.assert_allclose(run.time, plain.time, rtol=1e-12)
    stamps = pd.Timestamp("2026-03-02 08:00:00") + pd.to_timedelta(frame["time_s"], unit="s")
    frame.assign(time_s=stamps.dt.strftime("%Y-%m-%d %H:%M:%S")).rename(columns={"time_s": "일시"}).to_csv(
        path, index=False, encoding="cp949"
    )
    run = load_run(path, temps=TEMPS, time_is_default=True)
    np.testing.assert_allclose(run.time, plain.time - plain.time[0], atol=1e-9)


def test_the_air_named_in_korean_is_the_ambient():
    assert all(is_ambient_name(name) for name in ("실온", "실내온도", "주변 온도(℃)", "외기온도"))
    assert not any(is_ambient_name(name) for name in ("주축 온도", "베드 온도", "모터 온도"))
