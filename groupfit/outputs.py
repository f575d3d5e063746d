"""An output plan: what a command writes, checked against what it reads before anything is written.

Every verb declares its inputs (:meth:`OutputPlan.read`) and its outputs
(:meth:`OutputPlan.file`, :meth:`OutputPlan.folder`) before it starts its
work; each output is checked at once against the file system and against
every input, so a run that would lose data stops in one line before it
begins. While the plan is active (``with plan.active():``, which the command
line opens around every verb), the writers of :mod:`groupfit.io` leave each
file complete under a temporary name beside its target; :meth:`commit`
checks every target once more against every file the command read and then
renames them all together. A refused or failed command leaves none of its
outputs behind.

The rules:

* an output that resolves to an input (same path after following symbolic
  links, each before the ``..`` after it, or the same file under another
  name) is refused;
* an existing data file named as an output (CSV, TSV, Excel, OpenDocument, Parquet, MATLAB, TOML,
  or the data set of ``simulate --out``) is replaced only with ``--force``;
* a file a verb writes into its ``--out`` folder replaces one of that name
  there only when that one is an earlier output of its kind (otherwise only
  with ``--force``): a table (``sweep``'s ``runs.csv``) whose header line is
  the one written in its place (checked before the work where the verb
  declares the header, :meth:`OutputPlan.folder`), a PNG image, a JSON
  document (a model file only by a model file of its format), any other file
  (an exported routine, a sheet, a report) one that names groupfit in its
  first lines or starts with the line written in its place. A hand-written
  ``groupfit_model.c`` or notes saved as ``model.json`` are the user's;
* an existing model file (JSON whose ``format`` is a groupfit model's:
  ``groupfit-model/1``, ``groupfit-ballscrew/1``) named as an output file
  (``--json``) of a report (``replay``, ``compare`` …) is replaced only with
  ``--force``: it may be the only copy of a model on a machine (a verb whose
  ``--json`` is a model itself, ``fit`` or ``screw identify``, replaces one
  of its own kind as it replaces its own output on every run, not another's);
* an existing file named as a ``--json`` output that is not a JSON document
  (a compressed log, a ``.dat`` run, a database, notes) is replaced only with
  ``--force``: only an earlier JSON result (or an empty file) is replaced;
* an empty path (``--out ""``) is refused instead of meaning the current folder;
* two outputs may not name one file (``--json DIR/model.json`` beside ``--out DIR``).
"""

from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path
from typing import Iterable, Iterator

from groupfit.errors import InputError
from groupfit.io import STAGE, check_output_dir, check_output_file

DATA_SUFFIXES = frozenset({".csv", ".tsv", ".xlsx", ".xlsm", ".xls", ".ods", ".parquet", ".pq", ".mat", ".toml"})
"""Files an output named on the command line replaces only with ``--force``: the kinds a run or a
configuration is read from (the files a verb writes into its ``--out`` folder are its own and replaced)."""
GROUPED_MODELS = "groupfit-model/"
"""The ``format`` prefix of the model files ``fit`` writes (grouped, global and AR(1) models)."""
SCREW_MODELS = "groupfit-ballscrew/"
"""The ``format`` prefix of the ball-screw model files ``screw identify`` writes."""
MODEL_FORMATS = (GROUPED_MODELS, SCREW_MODELS)
"""The ``format`` of the model files an output file named on the command line replaces only with ``--force``."""
MODEL_SNIFF_BYTES = 64 * 1024 * 1024
"""A JSON file larger than this is not read to tell whether it is a model file (none is that large)."""
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
"""The first bytes of every PNG image."""
OWN_MARK = b"groupfit"
"""A text output names groupfit in its first :data:`HEAD_BYTES` (the exported routines, the controller sheet)."""
HEAD_BYTES = 1024


def resolved_path(path: str | Path) -> Path:
    """The file a path names: links followed before ``..`` is taken (``link/..`` is the parent of the link's
    target, as the file system reads it)."""
    return Path(os.path.realpath(Path(path).expanduser()))


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def _model_format(path: Path) -> str | None:
    """The groupfit model format ``path`` holds (one of :data:`MODEL_FORMATS`), or None."""
    try:
        if path.stat().st_size > MODEL_SNIFF_BYTES or not _holds_json(path):
            return None
        content = json.loads(path.read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    if not isinstance(content, dict):
        return None
    return next((kind for kind in MODEL_FORMATS if str(content.get("format", "")).startswith(kind)), None)


def _first_line(path: Path) -> bytes:
    """The first line of a file (its header, for a table); empty when it cannot be read."""
    try:
        with path.open("rb") as handle:
            return handle.readline(1 << 20).rstrip(b"\r\n")
    except OSError:
        return b""


def _head(path: Path) -> bytes:
    """The first :data:`HEAD_BYTES` of a file (empty when it cannot be read)."""
    try:
        with path.open("rb") as handle:
            return handle.read(HEAD_BYTES)
    except OSError:
        return b""


def foreign_output(existing: Path, written: Path | None = None) -> str | None:
    """What ``existing``, a file in an output folder, is when it is not an earlier output of the file that would
    replace it (``written``; None: not known yet, only what the name promises is checked); None when it is one.
    Tables are left to their header check (:meth:`OutputPlan.commit`)."""
    head = _head(existing)
    suffix = existing.suffix.lower()
    if not head.strip() or suffix in DATA_SUFFIXES:
        return None
    if suffix == ".png":
        return None if head.startswith(PNG_SIGNATURE) else "a file that is not a PNG image"
    if suffix == ".json":
        if not _holds_json(existing):
            return "a file that is not a JSON document"
        kind = _model_format(existing)
        if kind is None or written is None or _model_format(written) == kind:
            return None
        return f"a model file ({kind.rstrip('/')})"
    if OWN_MARK in head.lower():
        return None
    if written is not None and _first_line(existing) == _first_line(written):
        return None
    return "a file groupfit did not write" if written is not None else None


def _holds_json(path: Path) -> bool:
    """Whether ``path`` is empty or starts as a JSON document does (an object or an array)."""
    with open(path, "rb") as handle:
        head = handle.read(4096).removeprefix(b"\xef\xbb\xbf").lstrip()
    return not head or head[:1] in (b"{", b"[")


class OutputPlan:
    """The inputs and outputs of one command; see the module docstring.

    Parameters
    ----------
    force : bool
        Replace existing data files (``--force``).
    """

    def __init__(self, *, force: bool = False):
        self.force = force
        self.inputs: dict[Path, str] = {}
        self.staged: list[tuple[Path, Path]] = []
        self.outputs: dict[Path, str] = {}
        """Every declared output file and the option that names it: two options may not name one file."""
        self.made: list[Path] = []
        """Folders created for staged files (deepest first), removed again when the plan is discarded."""
        self.tables: dict[Path, str] = {}
        """Tables in an output folder that exist (and the option): replaced only by one with their header."""
        self.folders: dict[Path, str] = {}
        """Every declared output folder and the option that names it: no output file may be one of them, and a
        file written into one replaces only an earlier output of its kind (:func:`foreign_output`)."""

    # ------------------------------------------------------------ declaring
    def read(self, *paths) -> OutputPlan:
        """Note files the command reads (None, ``-``, folders and in-memory tables are skipped)."""
        for path in paths:
            if isinstance(path, (list, tuple)):
                self.read(*path)
            elif isinstance(path, (str, Path)) and str(path) not in ("", "-"):
                self.inputs.setdefault(resolved_path(path), str(path))
        return self

    def file(
        self, path: str | Path | None, option: str, *, data: bool = False, model: str | None = None, json: bool = False
    ) -> Path | None:
        """Check that ``path`` (an output file) may be written; None and ``-`` (stdout) pass.

        ``data`` marks a data set the command writes (``simulate --out``): an existing file there is
        replaced only with ``--force``, whatever its suffix. ``model``: the format of the model file written
        (``fit --json``), so it replaces a model of that format as a run of the same command replaces its own
        output. ``json``: the file written is a JSON document, so an existing file that is not one (a log, an
        archive, a database) is replaced only with ``--force``.
        """
        if path is None or str(path) == "-":
            return None
        target = self._target(path, option)
        self._check_input(target, option)
        self._claim(target, option)
        if target.is_file() and not self.force:
            self._check_replaced(target, option, data=data, model=model, json=json)
        return check_output_file(target, option)

    def _check_replaced(self, target: Path, option: str, *, data: bool, model: str | None, json: bool) -> None:
        """Refuse to replace, without ``--force``, a file that is not an earlier output of this kind."""
        if data or target.suffix.lower() in DATA_SUFFIXES:
            what = "an existing data file"
        elif json and not _holds_json(target):
            what = "an existing file that is not a JSON result (a log, an archive or a database?)"
        elif target.suffix.lower() == ".png" and foreign_output(target) is not None:
            what = "an existing file that is not a PNG image"
        else:
            kind = _model_format(target)
            if kind is None or kind == model:
                return
            what = "a model file" if model is None else f"a model file of another kind ({kind.rstrip('/')})"
        raise InputError(
            f"{target}: {option} would replace {what}; choose another {option}, or pass --force to replace it"
        )

    def folder(
        self, path: str | Path | None, option: str, files: Iterable[str] = (), headers: dict[str, str] | None = None
    ) -> Path | None:
        """Check that ``path`` (an output folder) may hold ``files``; None passes (no such output).

        ``headers``: for a table among ``files``, how the header line written there starts, so that a table of
        that name with another header (the user's) is refused now, before the work, not when it is done."""
        if path is None:
            return None
        if str(path) == "-":
            raise InputError(f"{option} -: names a folder of files, which cannot go to stdout; name a folder")
        folder = check_output_dir(self._target(path, option), option)
        self._claim_folder(folder, option)
        for name in files:
            target = folder / name
            self._check_input(target, option)
            self._claim(target, option)
            check_output_file(target, option)
            if not target.is_file() or self.force:
                continue
            if target.suffix.lower() in DATA_SUFFIXES:
                self.tables[resolved_path(target)] = option
                start = (headers or {}).get(name)
                if start is not None and _head(target).strip() and not _first_line(target).startswith(start.encode()):
                    raise self._foreign(target, option, "a table that is not an earlier output of this command")
            elif (what := foreign_output(target)) is not None:
                raise self._foreign(target, option, what)
        return folder

    @staticmethod
    def _foreign(target: Path, option: str, what: str, *, done: str = "") -> InputError:
        return InputError(
            f"{target}: {option} would replace {what}{done}; choose another {option}, or pass --force to replace it"
        )

    def _target(self, path: str | Path, option: str) -> Path:
        if not str(path).strip():
            raise InputError(f"{option} '': an empty path; name a file or folder (use . for the current folder)")
        return Path(path)

    def _claim(self, target: Path, option: str) -> None:
        """Refuse a file two outputs would both write (``--json DIR/model.json`` beside ``--out DIR``), or one
        that is (or would hold) an output folder (``--db X --out X``)."""
        resolved = resolved_path(target)
        other = self.outputs.setdefault(resolved, option)
        if other != option:
            raise InputError(f"{target}: {option} names a file {other} writes too; choose another {option}")
        for folder, named_by in self.folders.items():
            if folder == resolved or folder.is_relative_to(resolved):
                raise InputError(f"{target}: {option} names the folder {named_by} writes into; choose another {option}")

    def _claim_folder(self, folder: Path, option: str) -> None:
        resolved = resolved_path(folder)
        for output, named_by in self.outputs.items():
            if output == resolved or resolved.is_relative_to(output):
                raise InputError(f"{folder}: {option} names the file {named_by} writes; choose another {option}")
        self.folders.setdefault(resolved, option)

    def _check_input(self, target: Path, option: str | None) -> None:
        resolved = resolved_path(target)
        for source, given in self.inputs.items():
            if resolved == source or _same_file(resolved, source):
                if option is None:  # a file the plan did not claim: the verb's own name for it
                    raise InputError(
                        f"{target}: the output would replace a file this command reads ({given}); nothing was "
                        "written: write the output elsewhere"
                    )
                raise InputError(
                    f"{target}: {option} names a file this command reads ({given}); choose another {option}"
                )

    # ------------------------------------------------------------ writing
    @contextlib.contextmanager
    def active(self) -> Iterator[OutputPlan]:
        """Stage every file written inside the block; commit on success, discard on any exception."""
        token = STAGE.set(self)
        try:
            yield self
            self.commit()
        finally:
            STAGE.reset(token)
            self.discard()

    def stage(self, temporary: Path, target: Path) -> None:
        """A complete file at ``temporary`` to be renamed over ``target`` on :meth:`commit`."""
        self.staged = [(t, g) for t, g in self.staged if resolved_path(g) != resolved_path(target)] + [
            (temporary, target)
        ]

    def commit(self) -> list[Path]:
        """Check every staged target against every input, then rename them all; return the files written."""
        for _, target in self.staged:
            self._check_input(target, self.outputs.get(resolved_path(target)))
            if target.is_dir():
                raise InputError(f"{target}: is a folder; nothing was written (choose another output)")
        for temporary, target in self.staged:
            self._check_own(temporary, target)
        written = []
        try:
            for temporary, target in self.staged:
                os.replace(temporary, target)
                written.append(target)
            self.made = []  # the folders now hold the outputs
        except OSError as exc:
            done = f"; written before it: {', '.join(map(str, written))}" if written else "; nothing was written"
            raise InputError(f"{target}: cannot write ({exc.strerror or type(exc).__name__}){done}") from None
        finally:
            self.discard()
        return written

    def _check_own(self, temporary: Path, target: Path) -> None:
        """Refuse, before anything is renamed, to replace a file in an output folder that is not an earlier output
        of the file written in its place."""
        if self.force or not target.is_file():
            return
        option = self.tables.get(resolved_path(target))
        if option is not None:
            if _first_line(target) != _first_line(temporary):
                what = "a table that is not an earlier output of this command (its header differs)"
                raise self._foreign(target, option, what, done=f"; nothing was written to {option}")
            return
        option = self.folders.get(resolved_path(target.parent))
        if option is not None and (what := foreign_output(target, temporary)) is not None:
            raise self._foreign(target, option, what, done=f"; nothing was written to {option}")

    def discard(self) -> None:
        """Remove every staged file not yet renamed, and the folders made for them when left empty."""
        for temporary, _ in self.staged:
            temporary.unlink(missing_ok=True)
        self.staged = []
        for folder in sorted(set(self.made), key=lambda f: len(f.parts), reverse=True):
            with contextlib.suppress(OSError):
                folder.rmdir()  # only an empty folder goes
        self.made = []


def current_plan(*, force: bool = False) -> OutputPlan:
    """The active plan (the command line's), else a new one that only checks (files are then written at once)."""
    plan = STAGE.get()
    if plan is None:
        return OutputPlan(force=force)
    plan.force = plan.force or force
    return plan


def commit_outputs() -> list[Path]:
    """Write now every file staged so far (before a verb reports what it wrote); nothing when no plan is active."""
    plan = STAGE.get()
    return plan.commit() if plan is not None else []


__all__ = [
    "DATA_SUFFIXES",
    "foreign_output",
    "GROUPED_MODELS",
    "SCREW_MODELS",
    "OutputPlan",
    "commit_outputs",
    "current_plan",
    "resolved_path",
]
