"""An evaluator of the exported Structured Text block, and the two parsers' verdicts on a source text.

No IEC 61131-3 compiler installs here, so the block's behaviour is checked by
a small evaluator over blark's syntax tree: REAL arithmetic in IEEE single
precision, LREAL in double, integers range-checked, both operands of AND / OR
always evaluated (ST does not short-circuit), and every array index
bounds-checked, so an unguarded index fails the test instead of passing by luck.
An LREAL is never narrowed to REAL implicitly (only ``TO_REAL`` rounds it, as a
strict IEC 61131-3 compiler requires); ``EXPT`` of LREALs is the C library's
``pow`` (:func:`math.pow`), with the errors IEC 61131-3 defines for it.

Importing this module skips the importing test when blark is not installed (the ``toolchain`` marker).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import pytest

blark_parse = pytest.importorskip("blark.parse")
import blark.transform as tf  # noqa: E402
import tree_sitter  # noqa: E402
import tree_sitter_iec61131_3_st  # noqa: E402

from groupfit.export import render  # noqa: E402

from .replay import python_replay  # noqa: E402

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
