"""Bad and hostile inputs through the command line.

Every case must end with exit status 2, exactly one line on stderr naming
what is wrong (no traceback), and no file written or changed. The cases are
grouped by kind: data, parameters, model files, outputs, configs, sweep
(``test_the_table_covers_every_kind`` prints the counts).

The whole table runs in this process (``groupfit.cli.main``), with the
warnings Python shows by default (``UserWarning``, ``RuntimeWarning``,
``FutureWarning``) raised as errors, since a subprocess would print them as
more lines on stderr. One case in ``PROCESS_STRIDE`` of each kind (the first
of each among them) also runs as ``python -m groupfit …`` in its own process,
two at a time (``WORKERS``), for what only a real process shows: the exit
status the shell sees and the interpreter's own output; that part is marked
``slow``.
"""

from __future__ import annotations

import copy
import json
import os
import shutil
import subprocess
import sys
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from test_switching_models import SYNTHETIC, synthetic_model

from groupfit.screw import BallScrewModel
from groupfit.screw.modelfile import model_to_dict
from groupfit.screw.runs import load_screw_run

SCREW_RUN = SYNTHETIC.parent / "screw_A.csv"

WORKERS = 2
PROCESS_STRIDE = 12
KINDS = ("data", "parameters", "model files", "outputs", "configs", "sweep")
ROOT_USER = hasattr(os, "geteuid") and os.geteuid() == 0
"""The superuser writes into read-only folders: those cases are skipped for it."""


@dataclass(frozen=True)
class Case:
    kind: str
    label: str
    argv: tuple[str, ...]
    """Arguments after ``python -m groupfit``; ``{in}`` is the shared input folder, ``{out}`` the case's own."""
    expect: str
    """A fragment the stderr line must hold."""
    needs_permissions: bool = False
    """The case relies on a read-only path (skipped for the superuser)."""
    prepare: str | None = None
    """Something to create in the case's folder before the run: 'file', 'readonly-dir', 'readonly-file',
    'dir:PATH' (a folder where an output would go) or 'file:PATH' (a small CSV there)."""


def fit(*args):
    return ("fit", "--quiet", "--out", "{out}/result", *args)


def data_fit(name, *args):
    return fit("--data", f"{{in}}/{name}", "--temps", "T1,T2,T3,T4", "--p", "1", *args)


def position_fit(name, *args):
    return fit("--data", f"{{in}}/{name}", "--temps", "T1,T2", "--p", "0", "--position", "P_mm", *args)


def screw_predict(model, *args):
    return ("screw", "predict", f"{{in}}/{model}", "--data", "{in}/screw.csv", "--json", "{out}/p.json", *args)


def configured(verb, name):
    return (verb, f"{{in}}/{name}", "--quiet", "--out", "{out}/r")


def swept(name):
    return ("sweep", f"{{in}}/{name}", "--db", "{out}/s.sqlite", "--quiet")


def compared(*args):
    return ("compare", "--quiet", "--data", "{in}/good.csv", "--temps", "T1,T2", *args, "--out", "{out}/r")


def diagnose(*args):
    return ("diagnose", "{in}/model.json", "--data", "{in}/good.csv", "--out", "{out}/d", *args)


NEW_CASES = [
    # data: files that are not tables, tables read wrongly, cells beyond any plausible value
    Case("data", "a folder as --data", data_fit("."), "is a folder"),
    Case("data", "/dev/null as --data", fit("--data", "/dev/null", "--temps", "T1"), "not a regular file"),
    Case("data", "Parquet column named twice", data_fit("duplicate.parquet"), "appears twice (columns 2 and 4)"),
    Case("data", "time of 1e300", data_fit("time_huge.csv"), "row 41, column 'time_s'"),
    Case("data", "time in ns read as s", data_fit("time_ns.csv"), "steps 1e-07 s from row to row"),
    Case(
        "data",
        "one measured error",
        fit("--data", "{in}/one_error.csv", "--temps", "T1,T2,T3,T4", "--p", "0"),
        "1 row(s) with a measured error",
    ),
    Case("data", "position of 1e300", position_fit("position_huge.csv"), "row 31, column 'P_mm'"),
    Case("data", "--position an input", position_fit("position.csv", "--position", "T1"), "also a temperature input"),
    Case("data", "wide column without a position", position_fit("wide_abc.csv"), "err_Pabc"),
    # a column in a role it cannot play: the error as the reference or the heat, the clock as a temperature
    Case("data", "--reference the error", data_fit("good.csv", "--reference", "error_um"), "is the run's error"),
    Case("data", "--reference the time", data_fit("good.csv", "--reference", "time_s"), "is the run's time"),
    Case("data", "--ambient the error", data_fit("good.csv", "--ambient", "error_um"), "--ambient column 'error_um'"),
    Case("data", "diagnose --ambient the error", diagnose("--ambient", "error_um"), "is the run's error"),
    Case(
        "data",
        "compare --heat the error",
        compared("--pmax", "1", "--heat", "error_um"),
        "heat column 'error_um' is the run's error",
    ),
    Case(
        "data",
        "a heat level below 0 in a validation run",
        compared("--validate", "{in}/reversed.csv", "--pmax", "1", "--heat", "spindle_on"),
        "column 'spindle_on' = -1",
    ),
    Case(
        "data",
        "--dead-band-ref the error",
        position_fit("position.csv", "--dead-band", "1", "--dead-band-ref", "error_um"),
        "the run's error",
    ),
    Case("data", "two wide columns at one position", position_fit("wide_twin.csv"), "both at 100 mm"),
    # parameters that mean nothing
    Case("parameters", "--seed -1", data_fit("good.csv", "--seed", "-1"), "invalid seed"),
    Case(
        "parameters",
        "bootstrap block as long as the run",
        data_fit("good.csv", "--intervals", "bootstrap", "--block", "300"),
        "--block 300",
    ),
    Case("parameters", "diagnose --min-score 2", diagnose("--min-score", "2"), "--min-score"),
    Case("parameters", "diagnose --min-effect -1", diagnose("--min-effect", "-1"), "--min-effect"),
    Case("parameters", "diagnose --heat-exponent -5", diagnose("--heat-exponent", "-5"), "--heat-exponent"),
    Case(
        "parameters",
        "--dead-band-ref an input",
        position_fit("position.csv", "--dead-band", "1", "--dead-band-ref", "T2"),
        "a model input",
    ),
    Case(
        "parameters",
        "--position-ref far outside the travel",
        position_fit("position.csv", "--position-ref", "1e9"),
        "far outside the measured travel",
    ),
    Case(
        "parameters",
        "reserved word as the block name",
        ("export", "{in}/model.json", "--target", "st", "--name", "END_FUNCTION_BLOCK", "--out", "{out}/e"),
        "reserved word",
    ),
    Case(
        "parameters",
        "screw --probe-x off the screw",
        screw_predict("screw_model.json", "--probe-x=-1"),
        "off the screw",
    ),
    # model files
    *[
        Case("model files", f"JSON nested 100 000 deep ({verb})", argv, "nested too deeply")
        for verb, argv in [
            ("replay", ("replay", "{in}/deep.json", "--data", "{in}/good.csv")),
            ("export", ("export", "{in}/deep.json", "--target", "all", "--out", "{out}/e")),
        ]
    ],
    Case(
        "model files",
        "hold beyond a 32-bit counter",
        ("export", "{in}/hold_huge.json", "--target", "st", "--out", "{out}/e"),
        "32-bit counter",
    ),
    *[
        Case("model files", f"screw model: {label}", screw_predict(f"screw_{name}.json"), expect)
        for label, name, expect in [
            ("NaN lambda", "lambda_nan", "lambda_1_m"),
            ("negative lambda", "lambda_negative", "lambda_1_m"),
            ("negative source offset", "offset_negative", "source_offset_m"),
            ("negative h", "h_negative", "h_W_m2K"),
            ("C1 missing", "c1_missing", "C1 and C2"),
        ]
    ],
    # outputs that would lose data or be half-written
    Case("outputs", "fit --json the run", data_fit("good.csv", "--json", "{in}/good.csv"), "a file this command reads"),
    Case(
        "outputs",
        "diagnose --json the run",
        diagnose("--json", "{in}/good.csv"),
        "a file this command reads",
    ),
    Case(
        "outputs",
        "replay --json the model",
        ("replay", "{in}/model.json", "--data", "{in}/good.csv", "--json", "{in}/model.json"),
        "a file this command reads",
    ),
    Case(
        "outputs",
        "simulate --out its own config",
        ("simulate", "{in}/lumped.toml", "--out", "{in}/lumped.toml"),
        "a file this command reads",
    ),
    Case(
        "outputs",
        "simulate --out an existing run",
        ("simulate", "{in}/lumped.toml", "--out", "{out}/run.csv"),
        "--force",
        prepare="file:run.csv",
    ),
    Case("outputs", "fit --out ''", data_fit("good.csv", "--out", ""), "empty path"),
    Case(
        "outputs",
        "export: one of the files is a folder",
        ("export", "{in}/model.json", "--target", "all", "--out", "{out}/e"),
        "groupfit_model.c",
        prepare="dir:e/groupfit_model.c",
    ),
    Case("outputs", "fit: fit.png is a folder", data_fit("good.csv"), "fit.png", prepare="dir:result/fit.png"),
    # configs
    Case("configs", "seed -1 in the config", configured("fit", "seed_negative.toml"), "seed"),
    Case("configs", "temps = [] in the config", configured("fit", "temps_empty.toml"), "temps"),
    Case("configs", "heat_exponent = -5 in the config", configured("compare", "heat_negative.toml"), "heat_exponent"),
    Case("configs", "a population of none", configured("fit", "population_0.toml"), "'search.population_size'"),
    Case("configs", "generations -5", configured("fit", "generations_negative.toml"), "'search.max_generations'"),
    Case("configs", "pmax -2 in the config", configured("fit", "model_pmax_negative.toml"), "'model.pmax'"),
    Case("configs", "tolerance -5 in the config", configured("fit", "tolerance_negative.toml"), "'data.period_tol"),
    Case("configs", "an empty data path", configured("fit", "path_empty.toml"), "'data.path': an empty path"),
    Case("configs", "p_rule misspelt", configured("fit", "p_rule_misspelt.toml"), "must be one of next-run, bic"),
    Case("sweep", "the error as a sensor", swept("sweep_error_sensor.toml"), "'error_um' is no input column"),
    Case(
        "model files", "a folder as the model", ("replay", "{in}", "--data", "{in}/good.csv"), "is a folder; give the"
    ),
    # values a config or an option took without effect or with a traceback
    Case("data", "--error the time", data_fit("good.csv", "--error", "time_s"), "'time_s' is the run's time"),
    Case("data", "an empty --reference", data_fit("good.csv", "--reference", ""), "--reference is empty"),
    Case("configs", "an empty reference", configured("fit", "reference_empty.toml"), "[model] reference is empty"),
    Case("configs", "c of 1e300", configured("fit", "c_huge.toml"), "'model.c': the spacing coefficient"),
    Case("configs", "p of -1", configured("fit", "p_negative.toml"), "'model.p': expected a whole number ≥ 0"),
    Case("configs", "objective in capitals", configured("fit", "objective_upper.toml"), "'model.objective'"),
    Case("configs", "search method in capitals", configured("fit", "method_upper.toml"), "'search.method'"),
    Case("configs", "a structural gain of 1e300", configured("compare", "gain_huge.toml"), "'compare.structural_g"),
    Case("configs", "a gain without its sensor", configured("compare", "gain_alone.toml"), "without structural_se"),
    Case("configs", "a rise sensor unused", configured("compare", "rise_unused.toml"), "'compare.rise_sensor'"),
    Case("sweep", "the time as the error", swept("sweep_error_time.toml"), "'time_s' is the run's time"),
    Case("sweep", "a seed beyond 64 bits", swept("sweep_seed_huge.toml"), "from 0 to 9223372036854775807"),
    Case("sweep", "a period tolerance of -1", swept("sweep_tolerance.toml"), "'data.period_tolerance'"),
    Case("sweep", "a grid c of 1e300", swept("sweep_c_huge.toml"), "must be a number from 0 to 1e+06"),
    Case("sweep", "the error as a named sensor", swept("sweep_error_named.toml"), "is the thermal error"),
    Case(
        "parameters",
        "screw run given twice as a copy",
        ("screw", "identify", "{in}/screw.csv", "{in}/screw_copy.csv", "--out", "{out}/s"),
        "screw.csv, given as screw runs too",
    ),
    Case(
        "parameters",
        "screw diameter inf",
        ("screw", "identify", "{in}/screw.csv", "--diameter", "inf", "--out", "{out}/s"),
        "--diameter inf",
    ),
    Case(
        "parameters",
        "screw expansion nan",
        ("screw", "identify", "{in}/screw.csv", "--expansion", "nan", "--out", "{out}/s"),
        "--expansion nan",
    ),
    Case(
        "parameters",
        "--probe-x beside a probe column",
        ("screw", "predict", "{in}/screw_model.json", "--data", "{in}/screw_probe.csv", "--probe-x", "0.05"),
        "leave out one of the two",
    ),
    Case(
        "configs", "a sensor without a name", ("simulate", "{in}/sensor_unnamed.toml", "-o", "{out}/r.csv"), "needs a"
    ),
    # sweep
    Case("sweep", "a million runs", swept("sweep_million.toml"), "100000"),
    Case("sweep", "mostly infeasible", swept("sweep_mostly_infeasible.toml"), "cannot fit their breaks"),
    Case("sweep", "exact searches over the budget", (*swept("sweep_slow.toml"), "--workers", "1"), "over the budget"),
]


CASES = [
    # ------------------------------------------------------------------ data
    Case("data", "duplicate column name", data_fit("duplicate.csv"), "appears twice (columns 2 and 4)"),
    Case(
        "data",
        "duplicate column, compare",
        ("compare", "--quiet", "--data", "{in}/duplicate.csv", "--temps", "T1,T2", "--out", "{out}/r"),
        "appears twice",
    ),
    Case(
        "data",
        "duplicate column, replay",
        ("replay", "{in}/model.json", "--data", "{in}/duplicate.csv"),
        "appears twice",
    ),
    Case("data", "temperature of 1e300", data_fit("hot.csv"), "row 51, column 'T2'"),
    Case("data", "temperature of -273 °C", data_fit("cold.csv"), "row 11, column 'T1'"),
    Case("data", "error of 1e300", data_fit("huge_error.csv"), "row 21, column 'error_um'"),
    Case(
        "data",
        "temperature above a narrowed range",
        data_fit("good.csv", "--range-temp", "0,25"),
        "outside the plausible range 0…25",
    ),
    Case("data", "error above a narrowed limit", data_fit("good.csv", "--range-error", "1"), "--range-error"),
    Case("data", "--range-temp not two numbers", data_fit("good.csv", "--range-temp", "abc"), "--range-temp"),
    Case("data", "--range-temp reversed", data_fit("good.csv", "--range-temp", "200,-50"), "LOW < HIGH"),
    Case("data", "--range-error negative", data_fit("good.csv", "--range-error", "-5"), "--range-error"),
    Case("data", "empty file", data_fit("empty.csv"), "empty"),
    Case("data", "header without rows", data_fit("header_only.csv"), "no rows"),
    Case("data", "time going backwards", data_fit("backwards.csv"), "not strictly increasing"),
    Case("data", "NaN temperature", data_fit("nan.csv"), "row 6, column 'T3'"),
    Case("data", "missing temperature column", data_fit("good.csv", "--temps", "T1,T9"), "column 'T9' not found"),
    Case(
        "data",
        "no sensor columns and no --temps",
        fit("--data", "{in}/no_sensors.csv", "--p", "1"),
        "The columns are: time_s, a, b, error_um",
    ),
    Case("data", "constant temperature", data_fit("constant.csv"), "is constant"),
    Case("data", "constant error", data_fit("constant_error.csv"), "error column 'error_um' is constant"),
    Case("data", "data file not found", data_fit("missing.csv"), "not found"),
    Case("data", "position column missing", data_fit("good.csv", "--position", "P_mm"), "'P_mm' not found"),
    Case("data", "position not a number", position_fit("position_text.csv"), "column 'P_mm'"),
    Case("data", "one position only", position_fit("position_one.csv"), "one position only"),
    # ------------------------------------------------------------------ parameters
    Case("parameters", "--pmax -1 with --p auto", data_fit("good.csv", "--p", "auto", "--pmax", "-1"), "--pmax -1"),
    Case(
        "parameters",
        "compare --pmax -1",
        compared("--pmax", "-1"),
        "--pmax -1",
    ),
    Case("parameters", "--p -1", data_fit("good.csv", "--p", "-1"), "p = -1"),
    Case("parameters", "--p not a number", data_fit("good.csv", "--p", "three"), "invalid p"),
    Case("parameters", "--c negative", data_fit("good.csv", "--c", "-1"), "c = -1"),
    Case("parameters", "--c nan", data_fit("good.csv", "--c", "nan"), "c = nan"),
    Case(
        "parameters",
        "--c 0 with p = 200 (groups not over-determined)",
        data_fit("good.csv", "--c", "0", "--n", "0", "--p", "200", "--search", "exact"),
        "largest feasible p is 49",
    ),
    Case(
        "parameters",
        "--n larger than a hard group",
        data_fit("good.csv", "--n", "200", "--p", "3"),
        "at least 201 samples",
    ),
    Case("parameters", "--n negative", data_fit("good.csv", "--n", "-1"), "n = -1"),
    Case("parameters", "--objective unknown", data_fit("good.csv", "--objective", "mad"), "invalid choice"),
    Case("parameters", "--search unknown", data_fit("good.csv", "--search", "anneal"), "invalid choice"),
    Case("parameters", "--criterion not an input", data_fit("good.csv", "--criterion", "T7"), "criterion 'T7'"),
    Case("parameters", "--sensors without --select", data_fit("good.csv", "--sensors", "2"), "--select"),
    Case("parameters", "--position-order without --position", data_fit("good.csv", "--position-order", "2"), "needs"),
    Case("parameters", "--position-order 0", position_fit("position.csv", "--position-order", "0"), "choose 1"),
    Case(
        "parameters",
        "--position-order above the positions",
        position_fit("position.csv", "--position-order", "3"),
        "at most order 2",
    ),
    Case(
        "parameters",
        "--position-ref not a position",
        position_fit("position.csv", "--position-ref", "left"),
        "--position-ref",
    ),
    Case("parameters", "--dead-band negative", position_fit("position.csv", "--dead-band", "-1"), "--dead-band -1"),
    Case("parameters", "--resample 1e-300", data_fit("good.csv", "--resample", "1e-300"), "at most 5e+06"),
    Case("parameters", "--c 1e308", data_fit("good.csv", "--c", "1e308"), "from 0 to 1e+06"),
    Case(
        "parameters",
        "--probe-first 1e300",
        ("replay", "{in}/model.json", "--data", "{in}/good.csv", "--probe-every", "600", "--probe-first", "1e300"),
        "--probe-first 1e+300",
    ),
    Case(
        "parameters",
        "compare --probe-every 1e300",
        compared("--probe-every", "1e300"),
        "longer than 1e+09 s",
    ),
    Case(
        "parameters",
        "--resolution-um 1e-300",
        ("export", "{in}/model.json", "--target", "sheet", "--resolution-um", "1e-300", "--out", "{out}/e"),
        "integer resolution 1e-300",
    ),
    Case(
        "parameters",
        "--counts-limit beyond 32 bits",
        (
            "export",
            "{in}/model.json",
            "--target",
            "sheet",
            "--counts-limit",
            "99999999999999999999",
            "--out",
            "{out}/e",
        ),
        "a 32-bit register",
    ),
    Case("parameters", "--dead-band without --position", data_fit("good.csv", "--dead-band", "1"), "needs --position"),
    Case(
        "parameters",
        "--dead-band without its reference",
        position_fit("position.csv", "--dead-band", "1"),
        "--dead-band-ref",
    ),
    Case(
        "parameters",
        "replay with a faster sampled run",
        ("replay", "{in}/model.json", "--data", "{in}/fast.csv", "--json", "{out}/r.json"),
        "sampling period",
    ),
    # ------------------------------------------------------------------ model files (replay and export)
    *[
        Case("model files", f"{label} ({verb})", argv, expect)
        for label, name, expect in [
            ("breaks out of order", "breaks_order.json", "strictly increasing"),
            ("equal breaks", "breaks_equal.json", "strictly increasing"),
            ("break beyond N", "breaks_beyond.json", "strictly between"),
            ("negative n", "n_negative.json", "n = -1"),
            ("n larger than a hard group", "n_large.json", "n = 200"),
            ("windows reversed", "windows_reversed.json", "switching.windows"),
            ("negative sampling period", "period_negative.json", "sampling_period_s"),
            ("zero sampling period", "period_zero.json", "sampling_period_s"),
            ("p as a string", "p_string.json", "p = '3'"),
            ("breaks a bare integer", "breaks_int.json", "'breaks' must be a list"),
            ("coefficient 1e308", "coefficient_huge.json", "exceeds the limit"),
            ("non-string input name", "temps_number.json", "temps[1]"),
            ("repeated input name", "temps_repeated.json", "listed twice"),
            ("threshold not the criterion's", "threshold.json", "thresholds_c[0]"),
            ("truncated file", "truncated.json", "not a JSON model file"),
            ("foreign JSON", "foreign.json", "not a groupfit-model/1"),
            ("position order 0", "position_order.json", "position.order"),
            ("position travel reversed", "position_travel.json", "position.travel_mm"),
            ("position column an input", "position_input.json", "also a model input"),
            ("dead band of 0 °C", "dead_band_zero.json", "dead_band.threshold_c"),
            ("input span a number", "span_number.json", "training.input_span.T1"),
            ("spacing coefficient 1e308", "c_huge.json", "c = 1e+308"),
        ]
        for verb, argv in [
            ("replay", ("replay", f"{{in}}/{name}", "--data", "{in}/good.csv", "--json", "{out}/r.json")),
            ("export", ("export", f"{{in}}/{name}", "--target", "all", "--out", "{out}/exported")),
        ]
    ],
    Case(
        "model files",
        "model file not found",
        ("export", "{in}/nothing.json", "--target", "c", "--out", "{out}/e"),
        "model file not found",
    ),
    # ------------------------------------------------------------------ outputs
    Case(
        "outputs",
        "fit --out is a file",
        fit("--data", "{in}/good.csv", "--temps", "T1,T2", "--p", "1", "--out", "{out}/file"),
        "not a folder",
        prepare="file",
    ),
    Case(
        "outputs",
        "fit --json inside a file",
        data_fit("good.csv", "--json", "{out}/file/r.json"),
        "not a folder",
        prepare="file",
    ),
    Case("outputs", "fit --json is a folder", data_fit("good.csv", "--json", "{out}"), "needs a file name"),
    Case(
        "outputs",
        "compare --out is a file",
        ("compare", "--quiet", "--data", "{in}/good.csv", "--temps", "T1,T2", "--out", "{out}/file"),
        "not a folder",
        prepare="file",
    ),
    Case(
        "outputs",
        "compare --json inside a file",
        (
            "compare",
            "--quiet",
            "--data",
            "{in}/good.csv",
            "--temps",
            "T1,T2",
            "--json",
            "{out}/file/c.json",
            "--out",
            "{out}/r",
        ),
        "not a folder",
        prepare="file",
    ),
    Case(
        "outputs",
        "replay --json inside a file",
        ("replay", "{in}/model.json", "--data", "{in}/good.csv", "--json", "{out}/file/deeper/r.json"),
        "not a folder",
        prepare="file",
    ),
    Case(
        "outputs",
        "replay --out is a file",
        ("replay", "{in}/model.json", "--data", "{in}/good.csv", "--out", "{out}/file"),
        "not a folder",
        prepare="file",
    ),
    Case(
        "outputs",
        "export --out is a file",
        ("export", "{in}/model.json", "--target", "all", "--out", "{out}/file"),
        "not a folder",
        prepare="file",
    ),
    Case("outputs", "simulate -o is a folder", ("simulate", "{in}/lumped.toml", "-o", "{out}"), "needs a file name"),
    Case(
        "outputs",
        "simulate -o inside a file",
        ("simulate", "{in}/lumped.toml", "-o", "{out}/file/run.csv"),
        "not a folder",
        prepare="file",
    ),
    Case(
        "outputs",
        "sweep --out inside a file",
        ("sweep", "{in}/sweep_ok.toml", "--db", "{out}/s.sqlite", "--out", "{out}/file/report", "--quiet"),
        "not a folder",
        prepare="file",
    ),
    Case(
        "outputs",
        "sweep --db inside a file",
        ("sweep", "{in}/sweep_ok.toml", "--db", "{out}/file/s.sqlite", "--quiet"),
        "not a folder",
        prepare="file",
    ),
    Case(
        "outputs",
        "sweep --json is a folder",
        ("sweep", "{in}/sweep_ok.toml", "--db", "{out}/s.sqlite", "--json", "{out}", "--quiet"),
        "needs a file name",
    ),
    Case(
        "outputs",
        "diagnose --json is a folder",
        ("diagnose", "{in}/model.json", "--data", "{in}/good.csv", "--json", "{out}", "--out", "{out}/d"),
        "needs a file name",
    ),
    Case(
        "outputs",
        "read-only --out folder",
        data_fit("good.csv", "--out", "{out}/readonly"),
        "not writable",
        needs_permissions=True,
        prepare="readonly-dir",
    ),
    Case(
        "outputs",
        "read-only --json file",
        data_fit("good.csv", "--json", "{out}/readonly.json"),
        "read-only",
        needs_permissions=True,
        prepare="readonly-file",
    ),
    Case(
        "outputs",
        "export into a read-only folder",
        ("export", "{in}/model.json", "--target", "all", "--out", "{out}/readonly"),
        "not writable",
        needs_permissions=True,
        prepare="readonly-dir",
    ),
    # ------------------------------------------------------------------ configs
    Case("configs", "unknown key", ("fit", "{in}/unknown_key.toml", "--quiet", "--out", "{out}/r"), "colour"),
    Case("configs", "unknown table", ("fit", "{in}/unknown_table.toml", "--quiet", "--out", "{out}/r"), "plot"),
    Case("configs", "value of the wrong type", ("fit", "{in}/wrong_type.toml", "--quiet", "--out", "{out}/r"), "p"),
    Case("configs", "not TOML", ("fit", "{in}/not_toml.toml", "--quiet", "--out", "{out}/r"), "not_toml.toml"),
    Case("configs", "configuration not found", ("fit", "{in}/none.toml", "--quiet", "--out", "{out}/r"), "none.toml"),
    Case(
        "configs",
        "data file of the config missing",
        ("fit", "{in}/missing_data.toml", "--quiet", "--out", "{out}/r"),
        "not found",
    ),
    Case(
        "configs",
        "temp_range reversed in the config",
        ("fit", "{in}/range_reversed.toml", "--quiet", "--out", "{out}/r"),
        "data.temp_range",
    ),
    Case(
        "configs",
        "reading outside the config's temp_range",
        ("fit", "{in}/range_narrow.toml", "--quiet", "--out", "{out}/r"),
        "outside the plausible range 0…25",
    ),
    Case(
        "configs",
        "negative pmax in the config",
        ("compare", "{in}/pmax_negative.toml", "--quiet", "--out", "{out}/r"),
        "config key 'compare.pmax': must be at least 0, got -1",
    ),
    Case(
        "configs",
        "simulate scenario with an unknown key",
        ("simulate", "{in}/scenario_unknown.toml", "-o", "{out}/run.csv"),
        "scenario_unknown.toml",
    ),
    # ------------------------------------------------------------------ sweep
    Case(
        "sweep",
        "every run infeasible",
        ("sweep", "{in}/sweep_infeasible.toml", "--db", "{out}/s.sqlite", "--quiet"),
        "none of the 1 runs can fit",
    ),
    Case(
        "sweep",
        "unknown key in the grid",
        ("sweep", "{in}/sweep_unknown.toml", "--db", "{out}/s.sqlite", "--quiet"),
        "sweep_unknown.toml",
    ),
    Case(
        "sweep",
        "sensor not in the data",
        ("sweep", "{in}/sweep_sensor.toml", "--db", "{out}/s.sqlite", "--quiet"),
        "T9",
    ),
    Case(
        "sweep", "study not found", ("sweep", "{in}/nothing.toml", "--db", "{out}/s.sqlite", "--quiet"), "nothing.toml"
    ),
    Case(
        "sweep",
        "--workers 0",
        ("sweep", "{in}/sweep_ok.toml", "--db", "{out}/s.sqlite", "--workers", "0", "--quiet"),
        "--workers 0",
    ),
    *NEW_CASES,
]


def with_position(model: dict) -> dict:
    """A valid position section for ``model`` (zero slopes), for the mutations to break."""
    width = len(model["temps"]) + int(model["intercept"])
    rows = [[[0.0] * width] for _ in model["coefficients"]]
    return {"column": "P_mm", "p0_mm": 0.0, "order": 1, "travel_mm": [0.0, 100.0], "coefficients": rows}


def _write_inputs(folder: Path) -> None:
    good = pd.read_csv(SYNTHETIC)
    good.to_csv(folder / "good.csv", index=False)
    text = (folder / "good.csv").read_text().splitlines()
    header = text[0].split(",")
    header[3] = "T1"  # time_s,T1,T2,T1,…: pandas would read the second T1 as T1.1
    (folder / "duplicate.csv").write_text("\n".join([",".join(header), *text[1:]]) + "\n")

    def changed(name, column, row, value):
        frame = good.copy()
        frame[column] = frame[column].astype(float)
        frame.loc[row, column] = value
        frame.to_csv(folder / name, index=False)

    changed("hot.csv", "T2", 50, 1e300)
    changed("cold.csv", "T1", 10, -273.0)
    changed("huge_error.csv", "error_um", 20, 1e300)
    changed("nan.csv", "T3", 5, float("nan"))
    changed("backwards.csv", "time_s", 30, 100.0)
    good.assign(spindle_on=-good["spindle_on"]).to_csv(folder / "reversed.csv", index=False)
    good.assign(time_s=good["time_s"] * 1e-9).to_csv(folder / "time_ns.csv", index=False)
    good.assign(error_um=np.where(np.arange(len(good)) == 50, 1.0, np.nan)).to_csv(
        folder / "one_error.csv", index=False
    )
    good.assign(T4=21.0).to_csv(folder / "constant.csv", index=False)
    good.assign(error_um=0.0).to_csv(folder / "constant_error.csv", index=False)
    good.assign(time_s=good["time_s"] * 0.6).to_csv(folder / "fast.csv", index=False)
    # neither named as a temperature nor reading like one (°C within -40...200)
    pd.DataFrame(
        {"time_s": good["time_s"], "a": good["T1"] * 100, "b": good["T2"] * 100, "error_um": good["error_um"]}
    ).to_csv(folder / "no_sensors.csv", index=False)
    (folder / "empty.csv").write_text("")
    (folder / "header_only.csv").write_text(text[0] + "\n")
    positions = pd.concat([good.assign(P_mm=p, error_um=good["error_um"] + 0.01 * p) for p in (0.0, 100.0, 200.0)])
    positions = positions.sort_values("time_s", kind="stable")
    positions.to_csv(folder / "position.csv", index=False)
    text_position = positions.astype({"P_mm": object}).reset_index(drop=True)
    text_position.loc[7, "P_mm"] = "left"
    text_position.to_csv(folder / "position_text.csv", index=False)
    positions[positions.P_mm == 0.0].to_csv(folder / "position_one.csv", index=False)

    changed("time_huge.csv", "time_s", 40, 1e300)
    long = pd.concat([good] * 17, ignore_index=True)  # 5100 samples: each exact search some 7 min by the estimate
    long.assign(time_s=good["time_s"].iloc[0] + 100.0 * np.arange(len(long))).to_csv(folder / "long.csv", index=False)
    huge_position = positions.reset_index(drop=True)
    huge_position.loc[30, "P_mm"] = 1e300
    huge_position.to_csv(folder / "position_huge.csv", index=False)
    wide = good.drop(columns="error_um").assign(err_P0000=good["error_um"], err_P0100=good["error_um"] + 1)
    wide.assign(err_Pabc=good["error_um"]).to_csv(folder / "wide_abc.csv", index=False)
    wide.assign(err_P100=good["error_um"]).to_csv(folder / "wide_twin.csv", index=False)
    columns = [pa.array(good[c]) for c in ("time_s", "T1", "T2", "T1", "error_um")]
    pq.write_table(pa.table(columns, names=["time_s", "T1", "T2", "T1", "error_um"]), folder / "duplicate.parquet")
    (folder / "deep.json").write_text("[" * 100_000 + "]" * 100_000)
    _write_screw_inputs(folder)

    model, _ = synthetic_model(p=3, n=3)
    (folder / "model.json").write_text(json.dumps(model))
    (folder / "hold_huge.json").write_text(
        json.dumps({**model, "switching": {**model["switching"], "hold_samples": 2**31}})
    )
    b = model["breaks"]
    mutations = {
        "breaks_order": lambda m: m.update(breaks=[b[1], b[0], b[2]]),
        "breaks_equal": lambda m: m.update(breaks=[b[0], b[0], b[2]]),
        "breaks_beyond": lambda m: m.update(breaks=[b[0], b[1], 400]),
        "n_negative": lambda m: m.update(n=-1),
        "n_large": lambda m: m.update(n=200),
        "windows_reversed": lambda m: m["switching"].update(windows=[w[::-1] for w in m["switching"]["windows"]]),
        "period_negative": lambda m: m.update(sampling_period_s=-100.0),
        "period_zero": lambda m: m.update(sampling_period_s=0),
        "p_string": lambda m: m.update(p="3"),
        "breaks_int": lambda m: m.update(breaks=93),
        "coefficient_huge": lambda m: m["coefficients"][1].__setitem__(2, 1e308),
        "temps_number": lambda m: m["temps"].__setitem__(1, 7),
        "temps_repeated": lambda m: m["temps"].__setitem__(1, "T1"),
        "threshold": lambda m: m["switching"]["thresholds_c"].__setitem__(0, 99.0),
        "position_order": lambda m: m.update(position={**with_position(m), "order": 0}),
        "position_travel": lambda m: m.update(position={**with_position(m), "travel_mm": [100.0, 0.0]}),
        "position_input": lambda m: m.update(position={**with_position(m), "column": "T1"}),
        "dead_band_zero": lambda m: m.update(dead_band={"reference": "T_amb", "threshold_c": 0.0}),
        "span_number": lambda m: m.update(training={**m.get("training", {}), "input_span": {"T1": 5.0}}),
        "c_huge": lambda m: m.update(c=1e308),
    }
    for name, mutate in mutations.items():
        mutated = copy.deepcopy(model)
        mutate(mutated)
        (folder / f"{name}.json").write_text(json.dumps(mutated))
    (folder / "truncated.json").write_text(json.dumps(model)[:500])
    (folder / "foreign.json").write_text(json.dumps({"name": "a model", "coefficients": [1, 2]}))

    data = f'path = "{(folder / "good.csv").as_posix()}"'
    configs = {
        "unknown_key.toml": f"[data]\n{data}\n[model]\ncolour = 'red'\n",
        "unknown_table.toml": f"[data]\n{data}\n[plot]\ndpi = 90\n",
        "wrong_type.toml": f"[data]\n{data}\n[model]\np = 'three'\n",
        "not_toml.toml": "[data\npath = \n",
        "missing_data.toml": '[data]\npath = "nowhere.csv"\ntemps = ["T1"]\n',
        "range_reversed.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\ntemp_range = [30, 25]\n',
        "range_narrow.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\ntemp_range = [0, 25]\n',
        "pmax_negative.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[compare]\npmax = -1\n',
        "scenario_unknown.toml": 'kind = "lumped"\nwobble = 3\n',
        "lumped.toml": 'kind = "lumped"\n',
        "sweep_ok.toml": f"[data]\n{data}\n[grid]\np = [1]\n",
        "sweep_infeasible.toml": f"[data]\n{data}\n[grid]\np = [200]\n",
        "sweep_unknown.toml": f"[data]\n{data}\n[grid]\np = [1]\nlayers = [2]\n",
        "sweep_sensor.toml": f'[data]\n{data}\n[grid]\np = [1]\nsensors = [["T1", "T9"]]\n',
        "sweep_million.toml": f"[data]\n{data}\n[grid]\np = {{start = 0, stop = 1000000}}\n",
        "sweep_slow.toml": f'[data]\npath = "{(folder / "long.csv").as_posix()}"\n[grid]\np = [1, 2, 3]\n'
        'search = ["exact"]\n',
        "sweep_mostly_infeasible.toml": f"[data]\n{data}\n[grid]\np = {{start = 0, stop = 2000}}\n",
        "seed_negative.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[search]\nseed = -1\n',
        "temps_empty.toml": f"[data]\n{data}\ntemps = []\n",
        "heat_negative.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[compare]\nheat_exponent = -5\n',
        "population_0.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[search]\npopulation_size = 0\n',
        "generations_negative.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[search]\nmax_generations = -5\n',
        "model_pmax_negative.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[model]\npmax = -2\n',
        "tolerance_negative.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\nperiod_tolerance = -5\n',
        "path_empty.toml": '[data]\npath = ""\n',
        "p_rule_misspelt.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[model]\np_rule = "nextrun"\n',
        "sweep_error_sensor.toml": f'[data]\n{data}\n[grid]\np = [1]\nsensors = [["error_um"]]\n',
        "reference_empty.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[model]\nreference = ""\n',
        "c_huge.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[model]\nc = 1e300\n',
        "p_negative.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[model]\np = -1\n',
        "objective_upper.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[model]\nobjective = "SAE"\n',
        "method_upper.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[search]\nmethod = "Exact"\n',
        "gain_huge.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[compare]\nstructural_sensor = "T1"\n'
        "structural_gain_um_per_K = 1e300\n",
        "gain_alone.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[compare]\nstructural_gain_um_per_K = 3.2\n',
        "rise_unused.toml": f'[data]\n{data}\ntemps = ["T1", "T2"]\n[compare]\nrise_sensor = "T2"\n',
        "sweep_error_time.toml": f'[data]\n{data}\nerror = "time_s"\n[grid]\np = [1]\n',
        "sweep_seed_huge.toml": f'[data]\n{data}\n[grid]\np = [1]\nsearch = ["ga"]\n[ga]\nseed = [{2**63}]\n',
        "sweep_tolerance.toml": f"[data]\n{data}\nperiod_tolerance = -1\n[grid]\np = [1]\n",
        "sweep_c_huge.toml": f"[data]\n{data}\n[grid]\np = [1]\nc = [1e300]\n",
        "sweep_error_named.toml": f'[data]\n{data}\nerror = "T1"\ntemps = ["T1", "T2"]\n[grid]\np = [1]\n',
        "sensor_unnamed.toml": 'kind = "lumped"\n[sensors]\n"" = [600.0, 1.0]\n',
    }
    for name, text in configs.items():
        (folder / name).write_text(text)


def _write_screw_inputs(folder: Path) -> None:
    """A ball-screw run (the shipped run's first 1000 s without its probe column), the model file identified on
    the whole run, and that file broken five ways."""
    frame = pd.read_csv(SCREW_RUN)
    frame = frame[frame["time_s"] <= 1000]
    frame.to_csv(folder / "screw_probe.csv", index=False)
    frame = frame.drop(columns="probe_x_m")
    frame.to_csv(folder / "screw.csv", index=False)
    frame.to_csv(folder / "screw_copy.csv", index=False)
    model = BallScrewModel()
    run = load_screw_run(SCREW_RUN)
    model.fit(run.rises, run.time, run.positions, source=run.name, label=run.source)
    good = model_to_dict(model)
    (folder / "screw_model.json").write_text(json.dumps(good))
    mutations = {
        "lambda_nan": {"lambda_1_m": float("nan")},
        "lambda_negative": {"lambda_1_m": -8.0},
        "offset_negative": {"source_offset_m": -0.1},
        "h_negative": {"h_W_m2K": -3.0},
        "c1_missing": {"sources": [{"name": "screw", "C2": 0.05}]},
    }
    for name, change in mutations.items():
        (folder / f"screw_{name}.json").write_text(json.dumps({**good, **change}))


def _snapshot(folder: Path) -> dict[str, tuple[int, int]]:
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime_ns) for p in folder.rglob("*")}


def _prepare(folder: Path, what: str | None) -> None:
    if what and what.startswith("dir:"):
        (folder / what[4:]).mkdir(parents=True)
    elif what and what.startswith("file:"):
        (folder / what[5:]).write_text("time_s,T1\n0,20\n")
    elif what == "file":
        (folder / "file").write_text("not a folder\n")
    elif what == "readonly-dir":
        (folder / "readonly").mkdir()
        (folder / "readonly").chmod(0o555)
    elif what == "readonly-file":
        (folder / "readonly.json").write_text("{}\n")
        (folder / "readonly.json").chmod(0o444)


def _run(case: Case, inputs: Path, folder: Path) -> dict:
    folder.mkdir()
    _prepare(folder, case.prepare)
    argv = [a.replace("{in}", str(inputs)).replace("{out}", str(folder)) for a in case.argv]
    before, inputs_before = _snapshot(folder), _snapshot(inputs)
    env = {**os.environ, "MPLBACKEND": "Agg"}
    done = subprocess.run(
        [sys.executable, "-m", "groupfit", *argv], cwd=folder, env=env, capture_output=True, text=True, timeout=300
    )
    return {
        "status": done.returncode,
        "stderr": done.stderr,
        "changed": sorted(set(_snapshot(folder).items()) ^ set(before.items()))
        + sorted(set(_snapshot(inputs).items()) ^ set(inputs_before.items())),
    }


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory):
    """Every case run once, two processes at a time."""
    root = tmp_path_factory.mktemp("bad_inputs")
    inputs = root / "inputs"
    inputs.mkdir()
    _write_inputs(inputs)
    runnable = [c for c in SUBPROCESS_CASES if not (c.needs_permissions and ROOT_USER)]
    with ThreadPoolExecutor(WORKERS) as pool:
        futures = {c.label: pool.submit(_run, c, inputs, root / f"case{k}") for k, c in enumerate(runnable)}
        results = {label: future.result() for label, future in futures.items()}
    for path in root.rglob("readonly*"):
        path.chmod(0o755)
    yield results
    shutil.rmtree(root, ignore_errors=True)


def _check(case: Case, outcome: dict) -> None:
    lines = outcome["stderr"].strip().splitlines()
    assert outcome["status"] == 2, outcome["stderr"][-2000:]
    assert len(lines) == 1, outcome["stderr"][-2000:]
    assert "Traceback" not in outcome["stderr"]
    assert case.expect in lines[0], lines[0]
    assert outcome["changed"] == [], outcome["changed"]


IDS = [f"{c.kind}: {c.label}" for c in CASES]


def _every_kind_sampled(cases: list[Case]) -> list[Case]:
    """One case in ``PROCESS_STRIDE`` of each kind, in table order, starting with the kind's first."""
    seen: Counter = Counter()
    sampled = []
    for case in cases:
        if seen[case.kind] % PROCESS_STRIDE == 0:
            sampled.append(case)
        seen[case.kind] += 1
    return sampled


SUBPROCESS_CASES = _every_kind_sampled(CASES)


@pytest.mark.slow
@pytest.mark.cli
@pytest.mark.parametrize("case", SUBPROCESS_CASES, ids=[f"{c.kind}: {c.label}" for c in SUBPROCESS_CASES])
def test_bad_input_exits_2_with_one_line_and_writes_nothing(outcomes, case):
    if case.needs_permissions and ROOT_USER:
        pytest.skip("the superuser writes into read-only paths")
    _check(case, outcomes[case.label])


@pytest.fixture(scope="module")
def shared_inputs(tmp_path_factory):
    inputs = tmp_path_factory.mktemp("bad_inputs_in_process")
    _write_inputs(inputs)
    return inputs


@pytest.mark.filterwarnings("error::UserWarning", "error::RuntimeWarning", "error::FutureWarning")
@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_bad_input_in_process(shared_inputs, tmp_path, capsys, monkeypatch, case):
    """The whole table through ``main`` in this process.

    For the superuser, who may write anywhere, the read-only cases emulate
    what the permission check sees for an ordinary user.
    """
    from groupfit.cli import main

    if case.needs_permissions and ROOT_USER:
        access = os.access

        def as_ordinary_user(path, mode, **kwargs):
            if "readonly" in Path(path).name and mode & os.W_OK:
                return False
            return access(path, mode, **kwargs)

        monkeypatch.setattr(os, "access", as_ordinary_user)
    folder = tmp_path / "case"
    folder.mkdir()
    _prepare(folder, case.prepare)
    argv = [a.replace("{in}", str(shared_inputs)).replace("{out}", str(folder)) for a in case.argv]
    before, inputs_before = _snapshot(folder), _snapshot(shared_inputs)
    capsys.readouterr()
    try:
        status = main(argv)
    except SystemExit as exc:  # argparse usage errors
        status = exc.code
    finally:
        for path in folder.rglob("readonly*"):
            path.chmod(0o755)
    changed = sorted(set(_snapshot(folder).items()) ^ set(before.items())) + sorted(
        set(_snapshot(shared_inputs).items()) ^ set(inputs_before.items())
    )
    _check(case, {"status": status, "stderr": capsys.readouterr().err, "changed": changed})


def test_the_table_covers_every_kind(capsys):
    counts = Counter(c.kind for c in CASES)
    assert set(counts) == set(KINDS) and len({c.label for c in CASES}) == len(CASES)
    with capsys.disabled():
        print("\nbad-input cases by kind: " + ", ".join(f"{kind} {counts[kind]}" for kind in KINDS))
