"""An evaluator of the exported Structured Text block, and the two parsers' verdicts on a source text.

No IEC 61131-3 compiler installs here, so the block's behaviour is checked by
a small evaluator over tree-sitter's syntax tree: REAL arithmetic in IEEE single
precision, LREAL in double, integers range-checked, both operands of AND / OR
always evaluated (ST does not short-circuit), and every array index
bounds-checked, so an unguarded index fails the test instead of passing by luck.
An LREAL is never narrowed to REAL implicitly (only ``TO_REAL`` rounds it, as a
strict IEC 61131-3 compiler requires); ``EXPT`` of LREALs is the C library's
``pow`` (:func:`math.pow`), with the errors IEC 61131-3 defines for it. A text
tree-sitter does not parse cannot be evaluated. blark, whose parser takes seconds
per block, gives only its verdict on a text (:func:`blark_accepts`).

Importing this module skips the importing test when blark or tree-sitter is not installed (the ``toolchain`` marker).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import pytest

blark_parse = pytest.importorskip("blark.parse")
tree_sitter = pytest.importorskip("tree_sitter")
tree_sitter_iec61131_3_st = pytest.importorskip("tree_sitter_iec61131_3_st")

from groupfit.export import render  # noqa: E402

from .replay import python_replay  # noqa: E402

INTEGER_RANGES = {"INT": (-(2**15), 2**15 - 1), "DINT": (-(2**31), 2**31 - 1)}
FLOATS = {"REAL": np.float32, "LREAL": np.float64}
VAR_SECTIONS = {"var_input", "var_output", "var_in_out", "var_block", "var_temp"}
"""The declaration sections of a FUNCTION_BLOCK the evaluator declares variables from."""
SKIPPED = {"comment", "pragma"}
"""Nodes of tree-sitter's tree the evaluator leaves out wherever they stand."""


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


class Syntax:
    """A node of tree-sitter's tree, copied once into Python objects (walking tree-sitter's own nodes is slow).

    ``children`` are the named children, ``fields`` the named children by field name, ``operator`` the
    text of the child in the field ``operator`` (an unnamed token), if any.
    """

    __slots__ = ("type", "text", "children", "fields", "operator")

    def __init__(self, node):
        self.type, self.text = node.type, node.text.decode("ascii")
        self.children, self.fields, self.operator = [], {}, None
        cursor = node.walk()
        more = cursor.goto_first_child()
        while more:
            child, name = cursor.node, cursor.field_name
            if child.is_named and child.type not in SKIPPED:
                copy = Syntax(child)
                self.children.append(copy)
                if name is not None:
                    self.fields.setdefault(name, []).append(copy)
            elif name == "operator":
                self.operator = child.text.decode("ascii").upper()
            more = cursor.goto_next_sibling()

    def field(self, name: str) -> Syntax | None:
        found = self.fields.get(name)
        return found[0] if found else None

    def all(self, name: str) -> list[Syntax]:
        return self.fields.get(name, [])


def first_error(node):
    """The first node of tree-sitter's tree that is an error or a missing token (``node`` has an error)."""
    for child in node.children:
        if child.is_error or child.is_missing:
            return child
        if child.has_error:
            return first_error(child)
    return node


def parse_error(root) -> STError:
    """Where tree-sitter's parse of a text fails: its first error or missing token."""
    error = first_error(root)
    row, column = error.start_point
    if error.is_missing:
        return STError(f"tree-sitter rejects the block: missing {error.type} at line {row + 1}, column {column + 1}")
    text = error.text.decode("ascii").partition("\n")[0][:40]
    return STError(f"tree-sitter rejects the block: cannot parse {text!r} at line {row + 1}, column {column + 1}")


@lru_cache(maxsize=None)
def function_block(source: str) -> Syntax:
    """The FUNCTION_BLOCK of a source text, from tree-sitter's parse (each text is copied once)."""
    root = tree_sitter_tree(source).root_node
    if root.has_error:
        raise parse_error(root)
    blocks = [child for child in root.named_children if child.type == "function_block_declaration"]
    assert len(blocks) == 1
    return Syntax(blocks[0])


def integer(text: str) -> int:
    """An integer literal: decimal, or ``base#digits`` (``16#FF``), ``_`` between digits."""
    text = text.replace("_", "")
    if "#" not in text:
        return int(text)
    base, digits = text.split("#", 1)
    sign = -1 if base.startswith("-") else 1
    return sign * int(digits, int(base.lstrip("+-")))


def flatten(values: list[Syntax]) -> list[Syntax]:
    """The elements of an array's initial value, ``n(x)`` repeated ``n`` times."""
    out = []
    for value in values:
        if value.type == "array_repetition":
            count = value.field("count")
            items = [child for child in value.children if child is not count]
            out.extend(flatten(items) * integer(count.text))
        else:
            out.append(value)
    return out


class FunctionBlock:
    """One instance of a FUNCTION_BLOCK, evaluated from tree-sitter's tree."""

    def __init__(self, source: str):
        self.block = function_block(source)
        self.types: dict[str, str] = {}
        self.vars: dict = {}
        self.constants: set[str] = set()
        self.statements = {
            "assignment_statement": self.assignment,
            "if_statement": self.if_statement,
            "for_statement": self.for_statement,
            "empty_statement": lambda node: None,
        }
        self.expressions = {
            "integer_literal": lambda node: integer(node.text),
            "real_literal": lambda node: float(node.text.replace("_", "")),
            "boolean_literal": lambda node: node.text.upper() == "TRUE",
            "typed_literal": lambda node: self.evaluate(node.field("value")),
            "identifier": lambda node: self.vars[node.text],
            "index_expression": lambda node: self.array(node).get(self.subscripts(node)),
            "parenthesized_expression": lambda node: self.evaluate(node.children[0]),
            "unary_expression": self.unary,
            "binary_expression": lambda node: self.binary(
                node.operator, self.evaluate(node.field("left")), self.evaluate(node.field("right"))
            ),
            "call_expression": self.function_call,
        }
        for section in self.block.children:
            if section.type in VAR_SECTIONS:
                qualifiers = [
                    q.text.upper() for c in section.children if c.type == "var_qualifier_list" for q in c.children
                ]
                for declaration in section.children:
                    if declaration.type == "variable_declaration":
                        self.declare(declaration, "CONSTANT" in qualifiers)

    def declare(self, declaration: Syntax, constant: bool) -> None:
        names = [name.text for name in declaration.all("names")]
        spec, initial = declaration.field("type"), declaration.all("initial_value")
        if spec.type == "array_type":
            bounds = [
                (int(self.evaluate(r.field("lower"))), int(self.evaluate(r.field("upper")))) for r in spec.all("range")
            ]
            base = spec.field("element_type").text
            for name in names:
                array = STArray(base, bounds)
                indices = array.all_indices()
                values = [self.evaluate(v) for v in flatten(initial)]
                if values and len(values) != len(indices):
                    raise STError(f"{name}: {len(values)} initial values for {len(indices)} elements")
                default = False if base == "BOOL" else 0
                for k, index in enumerate(indices):
                    offset = tuple(low + i for (low, _), i in zip(bounds, index))
                    array.set(offset, convert(values[k] if values else default, base))
                self.vars[name], self.types[name] = array, base
        else:
            base = spec.text
            for name in names:
                value = self.evaluate(initial[0]) if initial else (False if base == "BOOL" else 0)
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
        self.execute(self.block.all("body"))

    def execute(self, statements: list[Syntax]) -> None:
        for statement in statements:
            run = self.statements.get(statement.type)
            if run is None:
                raise STError(f"statement {statement.type} not supported")
            run(statement)

    def assignment(self, node: Syntax) -> None:
        self.assign(node.field("left"), self.evaluate(node.field("right")))

    def if_statement(self, node: Syntax) -> None:
        if self.condition(node.field("condition")):
            self.execute(node.all("consequence"))
            return
        for clause in node.children:
            if clause.type == "elsif_clause" and self.condition(clause.field("condition")):
                self.execute(clause.all("body"))
                return
        for clause in node.children:
            if clause.type == "else_clause":
                self.execute(clause.all("body"))

    def for_statement(self, node: Syntax) -> None:
        if node.field("step") is not None:
            raise STError("FOR ... BY is not used by the export")
        name = node.field("control").text
        value, stop = self.evaluate(node.field("start")), self.evaluate(node.field("end"))
        body = node.all("body")
        while value <= stop:
            self.vars[name] = convert(value, self.types[name])
            self.execute(body)
            value = self.vars[name] + 1
        self.vars[name] = convert(value, self.types[name])

    def condition(self, expression: Syntax) -> bool:
        value = self.evaluate(expression)
        if not isinstance(value, (bool, np.bool_)):
            raise STError("condition is not BOOL")
        return bool(value)

    def assign(self, variable: Syntax, value) -> None:
        if variable.type == "identifier":
            name = variable.text
            if name in self.constants:
                raise STError(f"assignment to constant {name}")
            self.vars[name] = convert(value, self.types[name])
        elif variable.type == "index_expression":
            name = variable.field("object").text
            if name in self.constants:
                raise STError(f"assignment to constant {name}")
            array = self.array(variable)
            array.set(self.subscripts(variable), convert(value, array.base))
        else:
            raise STError(f"assignment target {variable.type} not supported")

    # expressions ----------------------------------------------------------
    def array(self, variable: Syntax) -> STArray:
        target = variable.field("object")
        if target.type != "identifier":
            raise STError(f"subscripted {target.type} not supported")
        return self.vars[target.text]

    def subscripts(self, variable: Syntax) -> tuple[int, ...]:
        index = tuple(self.evaluate(s) for s in variable.all("index"))
        if not all(isinstance(i, int) for i in index):
            raise STError("array subscript is not an integer")
        return index

    def evaluate(self, node: Syntax):
        kind = self.expressions.get(node.type)
        if kind is None:
            raise STError(f"expression {node.type} not supported")
        return kind(node)

    def unary(self, node: Syntax):
        operand = self.evaluate(node.field("operand"))
        if node.operator == "-":
            return -operand
        if node.operator == "NOT":
            return not operand
        raise STError(f"unary {node.operator}")

    def function_call(self, node: Syntax):
        name = node.field("function").text.upper()
        parameters = node.field("arguments").children
        arguments = [self.evaluate(p.field("value") if p.type == "named_argument" else p) for p in parameters]
        if name == "ABS" and len(arguments) == 1:
            return abs(arguments[0])
        if name in ("TO_REAL", "TO_LREAL") and len(arguments) == 1:
            if not isinstance(arguments[0], (float, np.floating)):
                raise STError(f"{name} of a {type(arguments[0]).__name__}")
            return FLOATS[name[3:]](arguments[0])  # IEEE rounding to nearest
        if name == "EXPT" and len(arguments) == 2:
            return expt(*arguments)
        raise STError(f"function {name} not supported")

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


@lru_cache(maxsize=1)
def tree_sitter_parser():
    return tree_sitter.Parser(tree_sitter.Language(tree_sitter_iec61131_3_st.language()))


def tree_sitter_tree(source: str):
    return tree_sitter_parser().parse(source.encode("ascii"))


def tree_sitter_errors(source: str) -> bool:
    return tree_sitter_tree(source).root_node.has_error


@lru_cache(maxsize=None)
def blark_result(source: str):
    """blark's parse of a source text (parsing takes seconds: each text is parsed once)."""
    return blark_parse.parse_source_code(source)


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
