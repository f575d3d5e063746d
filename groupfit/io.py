"""Writing results: a file written completely or not at all, and the JSON form of results.

Every file groupfit writes goes through :func:`atomic_write_text` (or
:func:`atomic_write_files` for a set of files that belong together, or
:func:`atomic_output` for a writer that wants a path, such as a figure): the
text goes to a temporary file in the target's folder, which is then renamed
over the target, so a reader never sees a half-written file. Files get the
mode a plain ``open`` would give them (``0o666`` less the umask), not the
``0o600`` of a temporary file. :func:`check_output_file` and
:func:`check_output_dir` check a target before any work starts, without
creating anything. :func:`file_sha256` names a file by its contents (a sweep's
data sets, the modelling files a model file remembers).
"""

from __future__ import annotations

import contextlib
import contextvars
import hashlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any, Iterator, Mapping

from groupfit.errors import InputError

MAX_INTEGER_DIGITS = 300
"""A JSON integer of more digits is read as a float: beyond 308 it overflows ``math.isfinite``, beyond 4300 ``int``."""

STAGE: contextvars.ContextVar = contextvars.ContextVar("groupfit_output_stage", default=None)
"""The active output plan (:class:`groupfit.outputs.OutputPlan`), or None: while one is active, the writers
below leave each file as a complete temporary file beside its target and hand it to the plan (``stage``), which
renames them all together when it commits; every file read is noted with it (``note_read``)."""


def note_read(path: str | Path) -> None:
    """Tell the active output plan (if any) that ``path`` was read: no output of the command may replace it."""
    plan = STAGE.get()
    if plan is not None:
        plan.read(path)


def _make_folder(folder: Path) -> None:
    """Create ``folder`` and its missing parents; the active plan removes them again if it does not commit."""
    missing = [f for f in (folder, *folder.parents) if not f.exists()]
    folder.mkdir(parents=True, exist_ok=True)
    plan = STAGE.get()
    if plan is not None:
        plan.made.extend(missing)


def _file_mode() -> int:
    """``0o666`` less the process umask: the mode ``open(path, "w")`` creates files with."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def _reason(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def _creatable(path: Path) -> tuple[Path | None, str | None]:
    """The nearest existing ancestor of ``path`` and, when ``path`` cannot be created below it, why."""
    ancestor = path.absolute()
    while not ancestor.exists():
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        return ancestor, f"{ancestor} is not a folder"
    if not os.access(ancestor, os.W_OK | os.X_OK):
        return ancestor, f"{ancestor} is not writable"
    return ancestor, None


def check_output_dir(path: str | Path, option: str = "--out") -> Path:
    """Check before any work that files can be written into the folder ``path``; one line when not.

    The folder must be a writable folder, or not exist yet below a writable
    one (it is created when the first file is written, so a refused run
    leaves nothing behind).
    """
    path = Path(path)
    _check_folder(
        path,
        option,
        not_folder=f"{path}: output path exists and is not a folder",
        not_writable=f"{path}: the output folder is not writable",
        not_creatable=f"{path}: cannot create the output folder ({{why}})",
    )
    return path


def check_output_file(path: str | Path, option: str) -> Path:
    """Check before any work that a file can be written at ``path``; one line naming the path when not.

    An existing target must be a file (it is replaced); its folder must be
    writable, or not exist yet below a writable folder.
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path}: is a folder; {option} needs a file name")
    if path.exists() and not path.is_file():
        raise InputError(
            f"{path}: not a regular file (a device or a pipe), which a result would replace; {option} needs a file name"
        )
    if path.exists() and not os.access(path, os.W_OK):
        raise InputError(f"{path}: the file is read-only; choose another {option}")
    folder = path.parent
    _check_folder(
        folder,
        option,
        not_folder=f"{path}: {folder} is not a folder",
        not_writable=f"{path}: the folder {folder} is not writable",
        not_creatable=f"{path}: cannot create its folder {folder} ({{why}})",
    )
    return path


def _check_folder(folder: Path, option: str, *, not_folder: str, not_writable: str, not_creatable: str) -> None:
    """Refuse ``folder`` unless it is a writable folder or can be created below one: the message that applies
    (``{why}`` in ``not_creatable`` says why it cannot be created) and ``; choose another {option}``."""
    if folder.exists():
        if not folder.is_dir():
            problem = not_folder
        elif not os.access(folder, os.W_OK | os.X_OK):
            problem = not_writable
        else:
            return
    else:
        _, why = _creatable(folder)
        if not why:
            return
        problem = not_creatable.format(why=why)
    raise InputError(f"{problem}; choose another {option}")


def landing(path: str | Path) -> Path:
    """Where a file written at ``path`` lands: a symbolic link's target (the link stays a link), else ``path``.

    Refused when something other than a regular file is there (a device or a pipe: renaming a result over it
    would remove it)."""
    path = Path(path)
    if path.is_symlink():
        path = Path(os.path.realpath(path))
    if path.exists() and not path.is_file() and not path.is_dir():
        raise InputError(f"{path}: not a regular file (a device or a pipe); it was left as it was")
    return path


def _temporary_for(path: Path) -> Path:
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(handle)
    return Path(temporary)


def _write_failed(path: Path, exc: OSError) -> InputError:
    return InputError(f"{path}: cannot write ({_reason(exc)}); that file was left as it was")


def atomic_write_text(path: str | Path, text: str) -> None:
    """Write a file completely or not at all, with the umask's mode."""
    atomic_write_files({Path(path): text})


def atomic_write_files(files: Mapping[str | Path, str]) -> list[Path]:
    """Write several files all or none: every temporary file first, then the renames.

    When a temporary file cannot be written, none of the targets is touched.
    The renames themselves do not fail in practice (same folder, checked
    writable); should one fail, the files already renamed are left as they are
    (complete files), the rest untouched.
    """
    mode = _file_mode()
    staged: list[tuple[Path, Path]] = []
    try:
        for target, text in files.items():
            target = landing(target)
            try:
                _make_folder(target.parent)
                temporary = _temporary_for(target)
            except OSError as exc:
                raise _write_failed(target, exc) from None
            staged.append((temporary, target))
            try:
                with open(temporary, "w", encoding="utf-8") as stream:
                    stream.write(text)
                os.chmod(temporary, mode)
            except OSError as exc:
                raise _write_failed(target, exc) from None
        plan = STAGE.get()
        if plan is not None:
            for temporary, target in staged:
                plan.stage(temporary, target)
            return [target for _, target in staged]
        for temporary, target in staged:
            try:
                os.replace(temporary, target)
            except OSError as exc:
                raise _write_failed(target, exc) from None
    except BaseException:
        for temporary, _ in staged:
            temporary.unlink(missing_ok=True)
        raise
    return [target for _, target in staged]


@contextlib.contextmanager
def atomic_output(path: str | Path) -> Iterator[Path]:
    """A temporary path to write ``path`` through (e.g. ``figure.savefig``), renamed over it on success.

    The temporary name keeps the target's suffix, so writers that choose a
    format by suffix still do.
    """
    path = landing(path)
    try:
        _make_folder(path.parent)
        handle, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}")
        os.close(handle)
    except OSError as exc:
        raise _write_failed(path, exc) from None
    temporary = Path(name)
    plan = STAGE.get()
    try:
        yield temporary
        os.chmod(temporary, _file_mode())
        if plan is not None:
            plan.stage(temporary, path)
            temporary = None
        else:
            os.replace(temporary, path)
    except OSError as exc:
        raise _write_failed(path, exc) from None
    finally:
        if temporary is not None:
            temporary.unlink(missing_ok=True)


def to_json(obj: Any) -> str:
    """Indented JSON with a final newline; NaN and infinities are refused."""
    return json.dumps(obj, indent=2, allow_nan=False) + "\n"


def save_figure(figure, path: str | Path, **options) -> None:
    """``figure.savefig(path, **options)``, written completely or not at all."""
    with atomic_output(path) as temporary:
        figure.savefig(temporary, **options)


def read_input_text(path: str | Path, what: str) -> str:
    """The UTF-8 text of the input file ``path``, noted as read; one line naming the file when it is missing.

    A UnicodeDecodeError is left to the caller, which says what the file should have been.
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path}: is a folder; give the {what} itself")
    if path.exists() and not path.is_file():
        raise InputError(f"{path}: not a regular file (a device or a pipe); give the {what}")
    if not path.is_file():
        raise InputError(f"{path}: {what} not found")
    note_read(path)
    return path.read_text(encoding="utf-8")


def read_json_file(path: str | Path, what: str = "model file") -> Any:
    """The JSON value in ``path``; one line naming the file when it is missing or not JSON."""
    path = Path(path)
    try:
        return json.loads(read_input_text(path, what), parse_int=json_integer)
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: not a JSON {what} ({exc})") from None
    except RecursionError:
        raise InputError(f"{path}: not a {what} (its JSON is nested too deeply to read)") from None


def json_integer(text: str) -> int | float:
    """A JSON integer; one of more digits than a float can hold is read as a float (infinite beyond its range),
    which the checks then refuse by its key, as they refuse ``1e400``."""
    return int(text) if len(text.lstrip("-")) <= MAX_INTEGER_DIGITS else float(text)


def file_sha256(path: str | Path) -> str:
    """The SHA-256 of a file's bytes, as hex (read in blocks of 1 MiB)."""
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def refuse_repeated(paths, what: str) -> None:
    """Refuse a file named twice among ``paths``, through a link or as a copy of the same bytes (``what``: how
    the message names the role it was given in): a run held out against itself scores nothing."""
    files = [path for path in paths if isinstance(path, (str, Path)) and Path(path).is_file()]
    seen: dict[Path, str] = {}
    contents: dict[str, str] = {}
    for path in files if len(files) > 1 else ():  # one file is no repeat: not read for it
        key = Path(path).resolve()
        if key in seen:
            raise InputError(f"{path}: given twice {what}; name each run once")
        digest = file_sha256(path)
        if digest in contents:
            raise InputError(
                f"{path}: holds the same bytes as {contents[digest]}, given {what} too: one run twice; name "
                "each run once"
            )
        seen[key] = str(path)
        contents[digest] = str(path)
