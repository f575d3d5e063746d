"""Structured Text export: parses with blark and tree-sitter, and behaves like the C build.

No IEC 61131-3 compiler installs here, so the block's behaviour is checked by
a small evaluator over blark's syntax tree (below): REAL arithmetic in IEEE
single precision, LREAL in double, integers range-checked, both operands of
AND / OR always evaluated (ST does not short-circuit), and every array index
bounds-checked, so an unguarded index fails the test instead of passing by luck.
An LREAL is never narrowed to REAL implicitly (only ``TO_REAL`` rounds it, as a
strict IEC 61131-3 compiler requires); ``EXPT`` of LREALs is the C library's
``pow`` (:func:`math.pow`), with the errors IEC 61131-3 defines for it.
"""

from __future__ import annotations

import math
import shutil
from functools import lru_cache

import numpy as np
import pytest

blark_parse = pytest.importorskip("blark.parse")
import blark.transform as tf  # noqa: E402
import tree_sitter  # noqa: E402
import tree_sitter_iec61131_3_st  # noqa: E402
from test_switching_models import (  # noqa: E402
    augmented_model,
    derived_streams,
    eight_sensor_model,
    streams_for,
    synthetic_model,
)

from groupfit.export import render, write  # noqa: E402
from groupfit.export.harness import build_driver, run_driver  # noqa: E402
from groupfit.runtime import FAULT_PERIOD, RETURN_PERIOD_FAULT, RETURN_SENSOR_FAULT, SwitchingRule  # noqa: E402

INTEGER_RANGES = {"INT": (-(2**15), 2**15 - 1), "DINT": (-(2**31), 2**31 - 1)}
FLOATS = {"REAL": np.float32, "LREAL": np.float64}


class STError(Exception):
    """The block did something a PLC would reject or trap on."""


class STArray:
    def __init__(self, base: str, bounds: list[tuple[int, int]]):
        self.base, self.bounds = base, bounds
        self.values = {}

    def offsets(self, index: tuple[int, ...]) -> tuple[int, ...]:
        if len(index) != len(self.bounds):
            raise STError(f"{len(index)} subscripts for a {len(self.bounds)}-dimensional array")
        for i, (low, high) in zip(index, self.bounds):
            if not low <= i <= high:
                raise STError(f"index {i} outside [{low}..{high}]")
        return index

    def get(self, index):
        return self.values[self.offsets(index)]

    def set(self, index, value):
        self.values[self.offsets(index)] = value

    def all_indices(self):
        return [tuple(ix) for ix in np.ndindex(*[high - low + 1 for low, high in self.bounds])]


def convert(value, base: str):
    if base in FLOATS:
        if isinstance(value, bool):
            raise STError("BOOL assigned to a real")
        if base == "REAL" and isinstance(value, np.float64):
            raise STError("LREAL assigned to REAL (narrowing needs TO_REAL)")
        return FLOATS[base](value)
    if base in INTEGER_RANGES:
        if isinstance(value, (float, np.floating)):
            raise STError(f"real value assigned to {base}")
        low, high = INTEGER_RANGES[base]
        value = int(value)
        if not low <= value <= high:
            raise STError(f"{value} overflows {base}")
        return value
    if base == "BOOL":
        if not isinstance(value, (bool, np.bool_)):
            raise STError("non-BOOL assigned to BOOL")
        return bool(value)
    raise STError(f"type {base} not supported by the evaluator")


def flatten(initialisation) -> list:
    out = []
    for element in initialisation.elements:
        inner = element.element
        items = flatten(inner) if isinstance(inner, tf.ArrayInitialization) else [inner]
        count = 1 if element.count is None else int(str(element.count.value))
        out.extend(items * count)
    return out


@lru_cache(maxsize=None)
def blark_result(source: str):
    """blark's parse of a source text (parsing takes seconds: each text is parsed once)."""
    return blark_parse.parse_source_code(source)


class FunctionBlock:
    """One instance of a FUNCTION_BLOCK, evaluated from blark's tree."""

    def __init__(self, source: str):
        result = blark_result(source)
        if result.exception is not None:
            raise result.exception
        blocks = [item for item in result.transform().items if isinstance(item, tf.FunctionBlock)]
        assert len(blocks) == 1
        self.block = blocks[0]
        self.types: dict[str, str] = {}
        self.vars: dict = {}
        self.constants: set[str] = set()
        for declarations in self.block.declarations:
            constant = "CONSTANT" in str(getattr(declarations, "attrs", "") or "")
            for declaration in declarations.items:
                self.declare(declaration, constant)

    def declare(self, declaration, constant: bool) -> None:
        names = [str(v.variable.name) for v in declaration.variables]
        init = declaration.init
        if isinstance(declaration, tf.ArrayVariableInitDeclaration):
            bounds = [(int(self.evaluate(r.start)), int(self.evaluate(r.stop))) for r in init.spec.subranges]
            base = str(init.spec.type.type_name)
            for name in names:
                array = STArray(base, bounds)
                indices = array.all_indices()
                values = [self.evaluate(v) for v in flatten(init.value)] if init.value is not None else []
                if values and len(values) != len(indices):
                    raise STError(f"{name}: {len(values)} initial values for {len(indices)} elements")
                default = False if base == "BOOL" else 0
                for k, index in enumerate(indices):
                    offset = tuple(low + i for (low, _), i in zip(bounds, index))
                    array.set(offset, convert(values[k] if values else default, base))
                self.vars[name], self.types[name] = array, base
        else:
            base = str(init.spec.type)
            for name in names:
                value = self.evaluate(init.value) if init.value is not None else (False if base == "BOOL" else 0)
                self.vars[name], self.types[name] = convert(value, base), base
        if constant:
            self.constants.update(names)

    # statements -----------------------------------------------------------
    def call(self, **inputs):
        for name, value in inputs.items():
            target = self.vars[name]
            if isinstance(target, STArray):
                for k, v in enumerate(value, start=target.bounds[0][0]):
                    target.set((k,), convert(v, target.base))
            else:
                self.vars[name] = convert(value, self.types[name])
        self.execute(self.block.body)

    def execute(self, node) -> None:
        if isinstance(node, tf.StatementList):
            for statement in node.statements:
                self.execute(statement)
        elif isinstance(node, tf.AssignmentStatement):
            value = self.evaluate(node.expression)
            for variable in node.variables:
                self.assign(variable, value)
        elif isinstance(node, tf.IfStatement):
            if self.condition(node.if_expression):
                self.execute(node.statements)
                return
            for clause in node.else_ifs or []:
                if self.condition(clause.if_expression):
                    self.execute(clause.statements)
                    return
            if node.else_clause is not None:
                self.execute(node.else_clause.statements)
        elif isinstance(node, tf.ForStatement):
            if node.step is not None:
                raise STError("FOR ... BY is not used by the export")
            name = str(node.control.name)
            value, stop = self.evaluate(node.from_), self.evaluate(node.to)
            while value <= stop:
                self.vars[name] = convert(value, self.types[name])
                self.execute(node.statements)
                value = self.vars[name] + 1
            self.vars[name] = convert(value, self.types[name])
        else:
            raise STError(f"statement {type(node).__name__} not supported")

    def condition(self, expression) -> bool:
        value = self.evaluate(expression)
        if not isinstance(value, (bool, np.bool_)):
            raise STError("condition is not BOOL")
        return bool(value)

    def assign(self, variable, value) -> None:
        if isinstance(variable, tf.SimpleVariable):
            name = str(variable.name)
            if name in self.constants:
                raise STError(f"assignment to constant {name}")
            self.vars[name] = convert(value, self.types[name])
        elif isinstance(variable, tf.MultiElementVariable):
            name = str(variable.name.name)
            if name in self.constants:
                raise STError(f"assignment to constant {name}")
            array = self.vars[name]
            array.set(self.subscripts(variable), convert(value, array.base))
        else:
            raise STError(f"assignment target {type(variable).__name__} not supported")

    # expressions ----------------------------------------------------------
    def subscripts(self, variable) -> tuple[int, ...]:
        (subscript_list,) = variable.elements
        index = tuple(self.evaluate(s) for s in subscript_list.subscripts)
        if not all(isinstance(i, int) for i in index):
            raise STError("array subscript is not an integer")
        return index

    def evaluate(self, node):
        if isinstance(node, tf.Integer):
            return int(str(node.value))
        if isinstance(node, tf.Real):
            return float(str(node.value))
        if isinstance(node, tf.Boolean):
            return str(node.value).upper() == "TRUE"
        if isinstance(node, tf.SimpleVariable):
            return self.vars[str(node.name)]
        if isinstance(node, tf.MultiElementVariable):
            return self.vars[str(node.name.name)].get(self.subscripts(node))
        if isinstance(node, tf.ParenthesizedExpression):
            return self.evaluate(node.expr)
        if isinstance(node, tf.UnaryOperation):
            operand = self.evaluate(node.expr)
            op = str(node.op).upper()
            if op == "-":
                return -operand
            if op == "NOT":
                return not operand
            raise STError(f"unary {op}")
        if isinstance(node, tf.BinaryOperation):
            return self.binary(str(node.op).upper(), self.evaluate(node.left), self.evaluate(node.right))
        if isinstance(node, tf.FunctionCall):
            name = str(node.name.name).upper()
            arguments = [self.evaluate(p.value) for p in node.parameters]
            if name == "ABS" and len(arguments) == 1:
                return abs(arguments[0])
            if name in ("TO_REAL", "TO_LREAL") and len(arguments) == 1:
                if not isinstance(arguments[0], (float, np.floating)):
                    raise STError(f"{name} of a {type(arguments[0]).__name__}")
                return FLOATS[name[3:]](arguments[0])  # IEEE rounding to nearest
            if name == "EXPT" and len(arguments) == 2:
                return expt(*arguments)
            raise STError(f"function {name} not supported")
        raise STError(f"expression {type(node).__name__} not supported")

    @staticmethod
    def binary(op: str, left, right):
        if op in ("AND", "OR", "XOR"):  # both operands already evaluated: no short circuit
            if not (isinstance(left, (bool, np.bool_)) and isinstance(right, (bool, np.bool_))):
                raise STError(f"{op} on non-BOOL operands")
            return {"AND": left and right, "OR": left or right, "XOR": left != right}[op]
        real = isinstance(left, np.floating) or isinstance(right, np.floating)
        if real and type(left) is not type(right):
            raise STError(f"mixed operand types {type(left).__name__} {op} {type(right).__name__}")
        if not real and not (isinstance(left, int) and isinstance(right, int)):
            raise STError(f"operands of {op} must both be numbers of one type")
        if op == "+":
            return left + right
        if op == "-":
            return left - right
        if op == "*":
            return left * right
        if op == "/":
            return left / right
        comparisons = {
            "<": np.less,
            "<=": np.less_equal,
            ">": np.greater,
            ">=": np.greater_equal,
            "=": np.equal,
            "<>": np.not_equal,
        }
        if op in comparisons:
            return bool(comparisons[op](left, right))
        raise STError(f"operator {op} not supported")


def expt(base, exponent):
    """IEC 61131-3 EXPT(IN1, IN2) = IN1 ** IN2, of the type of IN1; the evaluator knows it for LREAL IN1 only.

    An error when IN1 < 0 and IN2 is not a whole number, or IN1 = 0 and IN2 <= 0
    (the standard's error conditions); otherwise the C library's ``pow``.
    """
    if not isinstance(base, np.float64):
        raise STError(f"EXPT of a {type(base).__name__}: the export raises LREALs only")
    if isinstance(exponent, np.float32) or not isinstance(exponent, (int, float, np.float64)):
        raise STError(f"EXPT exponent of type {type(exponent).__name__}")
    if (base < 0 and float(exponent) != int(exponent)) or (base == 0 and exponent <= 0):
        raise STError(f"EXPT({float(base)!r}, {float(exponent)!r}) is an error in IEC 61131-3")
    return np.float64(math.pow(float(base), float(exponent)))


def run_block(source: str, streams, period_s: float, real: str) -> list[dict[str, np.ndarray]]:
    block = FunctionBlock(source)
    cast = FLOATS[real]
    outputs = []
    for temps in streams:
        rows = []
        for k, row in enumerate(temps):
            with np.errstate(over="ignore", invalid="ignore"):
                block.call(Temps=[cast(v) for v in row], SamplePeriodS=period_s, Reset=(k == 0))
            v = block.vars
            rows.append((v["Group"], v["Fault"], v["Switched"], float(v["ErrorUm"]), float(v["CompUm"])))
        code, fault, switched, prediction, compensation = map(np.array, zip(*rows))
        outputs.append(
            dict(code=code, fault=fault, switched=switched, prediction_um=prediction, compensation_um=compensation)
        )
    return outputs


# parsing ------------------------------------------------------------------


def tree_sitter_errors(source: str) -> bool:
    parser = tree_sitter.Parser(tree_sitter.Language(tree_sitter_iec61131_3_st.language()))
    return parser.parse(source.encode("ascii")).root_node.has_error


def blark_accepts(source: str) -> bool:
    """What ``blark parse FILE.st`` decides (it calls the same parse function)."""
    return blark_result(source).exception is None


@lru_cache(maxsize=None)
def models():
    return {
        "synthetic p=3": synthetic_model()[0],
        "p=0": synthetic_model(p=0)[0],
        "8 temps p=6": eight_sensor_model()[0],
    }


def block_source(label: str, real: str) -> str:
    (text,) = render(models()[label], "st", real=real).values()
    return text


@pytest.mark.parametrize(
    "label, real",
    [
        ("synthetic p=3", "REAL"),
        ("synthetic p=3", "LREAL"),
        ("p=0", "REAL"),
        ("8 temps p=6", "REAL"),
    ],
)
@pytest.mark.slow
def test_generated_blocks_parse_with_both_parsers(tmp_path, label, real):
    model = models()[label]
    files = render(model, "st", real=real)
    (path,) = write(files, tmp_path)
    text = path.read_text(encoding="ascii")
    assert path.name == "FB_GroupfitComp.st" and f"ARRAY[1..{len(model['temps'])}] OF {real}" in text
    assert blark_accepts(text), f"blark rejects the {label} block"
    assert not tree_sitter_errors(text), f"tree-sitter rejects the {label} block"


BREAKAGES = {
    "unbalanced bracket in a declaration": lambda s: s.replace("ARRAY[1..4] OF REAL;", "ARRAY[1..4 OF REAL;", 1),
    "missing semicolon in a declaration": lambda s: s.replace("Reset : BOOL;", "Reset : BOOL", 1),
    "missing semicolon in the body": lambda s: s.replace("comp := comp + delta;", "comp := comp + delta", 1),
}
MORE_BREAKAGES = {
    "missing END_IF": lambda s: s.replace("END_IF;", "", 1),
    "misspelt END_FOR": lambda s: s.replace("END_FOR;", "END_FRO;", 1),
    "unbalanced bracket in the body": lambda s: s.replace("COEF_0[g]", "COEF_0[g", 1),
    "dangling operator": lambda s: s.replace("delta := target - comp;", "delta := target - ;", 1),
}


@pytest.mark.parametrize("breakage", sorted(BREAKAGES))
@pytest.mark.slow
def test_broken_copies_fail_both_parsers(breakage):
    text = block_source("p=0", "REAL")
    broken = BREAKAGES[breakage](text)
    assert broken != text
    assert not blark_accepts(broken)
    assert tree_sitter_errors(broken)


@pytest.mark.parametrize("breakage", sorted(MORE_BREAKAGES))
def test_tree_sitter_rejects_more_broken_copies(breakage):
    text = block_source("synthetic p=3", "REAL")
    broken = MORE_BREAKAGES[breakage](text)
    assert broken != text and tree_sitter_errors(broken)


# behaviour ------------------------------------------------------------------


@pytest.fixture(scope="module")
def single_driver(tmp_path_factory):
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed")
    built = {}

    def get(label, model):
        if label not in built:
            folder = tmp_path_factory.mktemp("c_" + label.replace(" ", "_").replace("=", ""))
            write(render(model, "c"), folder)
            built[label] = build_driver(folder, folder / "driver", single=True)
        return built[label]

    return get


def assert_same_decisions(st_out, c_out) -> None:
    """Every stream of the ST block and of the C build: the same codes, faults, switches, and the same bits."""
    assert len(st_out) == len(c_out)
    for st_stream, c_stream in zip(st_out, c_out):
        assert np.array_equal(st_stream["code"], c_stream.code)
        assert np.array_equal(st_stream["fault"], c_stream.fault)
        assert np.array_equal(st_stream["switched"], c_stream.switched)
        assert st_stream["prediction_um"].tobytes() == c_stream.prediction_um.tobytes()
        assert st_stream["compensation_um"].tobytes() == c_stream.compensation_um.tobytes()


def assert_lreal_block_replays(model: dict, streams) -> None:
    """The LREAL block of ``model`` against the Python rule on every stream: the same decisions, bit for bit."""
    from test_export_c import python_replay

    streams = list(streams)
    (text,) = render(model, "st", real="LREAL").values()
    outputs = run_block(text, streams, model["sampling_period_s"], "LREAL")
    for temps, out in zip(streams, outputs):
        py = python_replay(model, temps)
        assert out["code"].tolist() == py["code"].tolist() and out["fault"].tolist() == py["fault"].tolist()
        assert out["switched"].tolist() == py["switched"].tolist()
        assert out["prediction_um"].tobytes() == py["prediction_um"].tobytes()
        assert out["compensation_um"].tobytes() == py["compensation_um"].tobytes()


def as_single(streams):
    with np.errstate(over="ignore", invalid="ignore"):
        return [np.asarray(s, dtype=np.float32).astype(float) for s in streams]


STREAMS = {"synthetic p=3": None, "p=0": ("modelling", "faults"), "8 temps p=6": ("modelling", "faults")}


@pytest.mark.parametrize("label", sorted(STREAMS))
def test_real_block_matches_the_single_precision_c_build_bit_for_bit(single_driver, label):
    model = models()[label]
    run = eight_sensor_model()[1] if len(model["temps"]) == 8 else synthetic_model()[1]
    chosen = STREAMS[label]
    streams = as_single([v for k, v in streams_for(model, run).items() if chosen is None or k in chosen])
    st_out = run_block(block_source(label, "REAL"), streams, model["sampling_period_s"], "REAL")
    c_out = run_driver(single_driver(label, model), streams)
    assert_same_decisions(st_out, c_out)


def test_lreal_block_matches_the_python_rule():
    model, run = synthetic_model()
    streams = list(streams_for(model, run).values())
    rule = SwitchingRule(model)
    outputs = run_block(block_source("synthetic p=3", "LREAL"), streams, model["sampling_period_s"], "LREAL")
    for temps, out in zip(streams, outputs):
        rule.reset()
        results = [rule.step(row) for row in temps]
        assert out["code"].tolist() == [r.code for r in results]
        assert out["fault"].tolist() == [r.fault for r in results]
        assert np.max(np.abs(out["prediction_um"] - [r.prediction_um for r in results])) <= 1e-9
        assert np.max(np.abs(out["compensation_um"] - [r.compensation_um for r in results])) <= 1e-9


def test_wrong_task_period_holds_a_period_fault_and_ramps_to_zero():
    model, run = synthetic_model()
    block = FunctionBlock(block_source("synthetic p=3", "LREAL"))
    for k in range(20):
        block.call(Temps=[np.float64(v) for v in run.temps[k]], SamplePeriodS=100.0, Reset=(k == 0))
    before = float(block.vars["CompUm"])
    assert block.vars["Group"] == 1 and before < 0
    rate = model["switching"]["rate_limit_um"]
    block.call(Temps=[np.float64(v) for v in run.temps[20]], SamplePeriodS=60.0, Reset=False)
    assert block.vars["Group"] == RETURN_PERIOD_FAULT and block.vars["Fault"] == FAULT_PERIOD
    assert float(block.vars["CompUm"]) == pytest.approx(min(0.0, before + rate))
    assert block.vars["sampleCount"] == 20  # the count stands still while the period is wrong
    block.call(Temps=[np.float64(v) for v in run.temps[20]], SamplePeriodS=100.0, Reset=False)
    assert block.vars["Group"] == 1 and block.vars["sampleCount"] == 21


def test_evaluator_traps_an_unguarded_index():
    source = """FUNCTION_BLOCK FB_Probe
VAR_INPUT
    k : INT;
END_VAR
VAR_OUTPUT
    ok : BOOL;
END_VAR
VAR CONSTANT
    LIMIT : ARRAY[1..2] OF INT := [5, 6];
END_VAR
ok := k <= 2 AND LIMIT[k] > 0;
END_FUNCTION_BLOCK
"""
    block = FunctionBlock(source)
    block.call(k=1)
    assert block.vars["ok"] is True
    with pytest.raises(STError, match="index 3 outside"):
        block.call(k=3)  # AND evaluates LIMIT[3] although k <= 2 is FALSE


# derived inputs ---------------------------------------------------------------


@lru_cache(maxsize=None)
def derived_block(label: str, real: str) -> str:
    (text,) = render(augmented_model(label)[0], "st", real=real).values()
    return text


@pytest.mark.parametrize("label, real", [("all kinds p=2", "REAL"), ("on/off p=1", "LREAL")])
@pytest.mark.slow
def test_blocks_with_derived_inputs_parse_with_both_parsers(label, real):
    text = derived_block(label, real)
    assert text.isascii() and "derivedValue" in text and "LOWPASS_A_1" in text
    assert blark_accepts(text), f"blark rejects the {label} block"
    assert not tree_sitter_errors(text), f"tree-sitter rejects the {label} block"


def test_real_block_with_derived_inputs_matches_the_single_precision_c_build_bit_for_bit(single_driver):
    model, run = augmented_model("all kinds p=2")
    streams = as_single(list(derived_streams(model, run).values()))
    st_out = run_block(derived_block("all kinds p=2", "REAL"), streams, model["sampling_period_s"], "REAL")
    c_out = run_driver(single_driver("derived all kinds", model), streams)
    assert_same_decisions(st_out, c_out)


def test_lreal_block_with_derived_inputs_matches_the_python_rule():
    model, run = augmented_model("on/off p=1")
    streams = list(derived_streams(model, run).values())
    rule = SwitchingRule(model)
    outputs = run_block(derived_block("on/off p=1", "LREAL"), streams, model["sampling_period_s"], "LREAL")
    for temps, out in zip(streams, outputs):
        rule.reset()
        results = [rule.step(row) for row in temps]
        assert out["code"].tolist() == [r.code for r in results]
        assert out["fault"].tolist() == [r.fault for r in results]
        assert out["switched"].tolist() == [r.switched for r in results]
        assert np.max(np.abs(out["prediction_um"] - [r.prediction_um for r in results])) <= 1e-9
        assert np.max(np.abs(out["compensation_um"] - [r.compensation_um for r in results])) <= 1e-9


def test_reset_restarts_the_derived_inputs():
    model, run = augmented_model("on/off p=1")
    raw = derived_streams(model, run)["modelling"][:40]
    block = FunctionBlock(derived_block("on/off p=1", "LREAL"))
    first = []
    for k, row in enumerate(raw):
        block.call(Temps=[np.float64(v) for v in row], SamplePeriodS=100.0, Reset=(k == 0))
        first.append(float(block.vars["ErrorUm"]))
    again = []
    for k, row in enumerate(raw):
        block.call(Temps=[np.float64(v) for v in row], SamplePeriodS=100.0, Reset=(k == 0))
        again.append(float(block.vars["ErrorUm"]))
    assert again == first and block.vars["delayPos2"] == 40 % 10


def test_on_time_blocks_match_the_c_build_and_the_python_rule(single_driver):
    """REAL: bit for bit with the single-precision C build; LREAL: the Python rule's decisions."""
    model, run = augmented_model("on-time p=1")
    streams = derived_streams(model, run)
    text = derived_block("on-time p=1", "REAL")
    assert "ONTIME_STEP_1 : REAL := " in text and "derivedMemory[1] := derivedMemory[1] + ONTIME_ONE;" in text
    single = as_single(list(streams.values()))
    st_out = run_block(text, single, model["sampling_period_s"], "REAL")
    assert_same_decisions(st_out, run_driver(single_driver("derived on-time", model), single))
    rule = SwitchingRule(model)
    outputs = run_block(derived_block("on-time p=1", "LREAL"), list(streams.values()), 100.0, "LREAL")
    for temps, out in zip(streams.values(), outputs):
        rule.reset()
        results = [rule.step(row) for row in temps]
        assert out["code"].tolist() == [r.code for r in results]
        assert np.max(np.abs(out["prediction_um"] - [r.prediction_um for r in results])) <= 1e-9


@pytest.mark.slow
def test_on_time_blocks_parse_with_both_parsers():
    for real in ("REAL", "LREAL"):
        text = derived_block("on-time p=1", real)
        assert blark_accepts(text) and not tree_sitter_errors(text), f"a parser rejects the on-time {real} block"


# power stage and start from rest ------------------------------------------------


def heat_law_streams():
    model, run = augmented_model("heat law p=2")
    streams = derived_streams(model, run)
    r = 4  # speed_rpm, the source of the power stages
    late_start = streams["modelling"].copy()
    late_start[:6, r] = [np.nan, -1.0, np.inf, 1e12, -np.inf, np.nan]
    streams["speed faulty at the start"] = late_start
    return model, streams


@pytest.mark.parametrize("real", ["REAL", "LREAL"])
def test_heat_law_blocks_parse_with_both_parsers(real):
    text = derived_block("heat law p=2", real)
    assert text.isascii() and "EXPT(ABS(" in text and "POWER_EXPONENT_1 : LREAL := 1.6666666666666667;" in text
    if real == "REAL":
        assert "sourceValue := TO_REAL(EXPT(ABS(TO_LREAL(lastGood[5])) / POWER_SCALE_1, POWER_EXPONENT_1));" in text
    else:
        assert "sourceValue := EXPT(ABS(lastGood[5]) / POWER_SCALE_1, POWER_EXPONENT_1);" in text
    assert "derivedMemory[1] := 0.0;" in text and "delayLine3[j] := 0.0;" in text  # from rest
    assert "derivedMemory[4] := sourceValue;" in text  # steady
    assert blark_accepts(text), f"blark rejects the heat-law {real} block"
    assert not tree_sitter_errors(text), f"tree-sitter rejects the heat-law {real} block"


def test_real_heat_law_block_matches_the_single_precision_c_build_bit_for_bit(single_driver):
    model, streams = heat_law_streams()
    streams = as_single(list(streams.values()))
    st_out = run_block(derived_block("heat law p=2", "REAL"), streams, model["sampling_period_s"], "REAL")
    c_out = run_driver(single_driver("heat law", model), streams)
    assert_same_decisions(st_out, c_out)
    for temps, st_stream in zip(streams, st_out):
        single = SwitchingRule(model, precision="single").replay(temps)  # and the float32 Python rule
        assert st_stream["prediction_um"].tobytes() == single.prediction_um.tobytes()


def test_lreal_heat_law_block_is_the_python_rule_bit_for_bit():
    model, streams = heat_law_streams()
    rule = SwitchingRule(model)
    chosen = [streams[k] for k in ("modelling", "source faults", "speed faulty at the start")]
    outputs = run_block(derived_block("heat law p=2", "LREAL"), chosen, model["sampling_period_s"], "LREAL")
    for temps, out in zip(chosen, outputs):
        replay = rule.replay(temps)
        assert out["code"].tolist() == [RETURN_SENSOR_FAULT if f & 2 else g for g, f in zip(replay.group, replay.fault)]
        assert out["fault"].tolist() == replay.fault.tolist()
        assert out["switched"].tolist() == replay.switched.tolist()
        assert out["prediction_um"].tobytes() == replay.prediction_um.tobytes()
        assert out["compensation_um"].tobytes() == replay.compensation_um.tobytes()


PROBE = """FUNCTION_BLOCK FB_Probe
VAR_INPUT
    x : LREAL;
    k : LREAL;
END_VAR
VAR_OUTPUT
    y : LREAL;
    r : REAL;
END_VAR
VAR CONSTANT
    SCALE : LREAL := 1000.0;
END_VAR
$body
END_FUNCTION_BLOCK
"""


def probe(body: str) -> FunctionBlock:
    return FunctionBlock(PROBE.replace("$body", body))


def test_evaluator_knows_expt_abs_and_the_conversions_as_iec_61131_3_defines_them():
    block = probe("y := EXPT(ABS(x) / SCALE, k);\nr := TO_REAL(y);")
    block.call(x=-2500.0, k=5 / 3)
    assert block.vars["y"] == math.pow(2.5, 5 / 3) and type(block.vars["y"]) is np.float64
    assert block.vars["r"] == np.float32(math.pow(2.5, 5 / 3)) and type(block.vars["r"]) is np.float32
    block.call(x=0.0, k=2.0)
    assert block.vars["y"] == 0.0
    with pytest.raises(STError, match="is an error"):
        probe("y := EXPT(x, k);").call(x=-2.0, k=0.5)  # a negative base needs a whole exponent
    with pytest.raises(STError, match="is an error"):
        probe("y := EXPT(x, k);").call(x=0.0, k=-1.0)
    with pytest.raises(STError, match="narrowing needs TO_REAL"):
        probe("r := x;").call(x=1.0, k=1.0)  # no implicit LREAL -> REAL
    with pytest.raises(STError, match="EXPT of a float32"):
        probe("r := EXPT(TO_REAL(x), TO_REAL(k));").call(x=2.0, k=2.0)
