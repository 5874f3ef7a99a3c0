"""Writing a command's outputs all or nothing.

Files are written into a staging folder beside the destination and moved into place
(``os.replace``, atomic on one file system) only when every one of them is complete,
so an error or an interruption leaves no half-written output behind.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from firefleet.errors import InputError

__all__ = ["json_text", "staged_dir", "write_text_atomic"]


def _finite_or_none(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite_or_none(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite_or_none(v) for v in value]
    return value


def json_text(document: Any) -> str:
    """JSON text of ``document`` with non-finite numbers written as ``null``.

    Examples
    --------
    >>> from firefleet.outputs import json_text
    >>> print(json_text({"rise_time_s": float("inf"), "robots": [1.0, float("nan")]}), end="")
    {
      "rise_time_s": null,
      "robots": [
        1.0,
        null
      ]
    }
    """
    return json.dumps(_finite_or_none(document), indent=2, allow_nan=False) + "\n"


@contextmanager
def staged_dir(destination: str | Path) -> Iterator[Path]:
    """Stage files for ``destination`` and move them there when the block succeeds.

    Yields a temporary folder; write the outputs into it (subfolders allowed). On a
    clean exit each file replaces its namesake in ``destination`` (created if needed;
    other files there are kept); on an exception nothing in ``destination`` changes.

    Raises
    ------
    InputError
        If ``destination`` exists and is not a folder, or cannot be created.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from firefleet.outputs import staged_dir
    >>> folder = tempfile.TemporaryDirectory()
    >>> out = pathlib.Path(folder.name) / "run"
    >>> with staged_dir(out) as stage:
    ...     _ = (stage / "metrics.json").write_text("{}")
    ...     print(out.exists())
    False
    >>> sorted(p.name for p in out.iterdir())
    ['metrics.json']
    >>> folder.cleanup()
    """
    dest = Path(destination)
    if dest.exists() and not dest.is_dir():
        raise InputError(f"--out {dest}: exists and is not a folder")
    parent = dest.resolve().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        stage = Path(tempfile.mkdtemp(prefix=f".{dest.name}.staging-", dir=parent))
    except OSError as exc:
        raise InputError(f"--out {dest}: cannot create: {exc.strerror}") from None
    try:
        yield stage
        dest.mkdir(parents=True, exist_ok=True)
        for path in sorted(stage.rglob("*")):
            if path.is_file():
                target = dest / path.relative_to(stage)
                target.parent.mkdir(parents=True, exist_ok=True)
                os.replace(path, target)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def write_text_atomic(dest: str | Path, text: str) -> None:
    """Write ``text`` to a temporary file beside ``dest``, then rename it into place.

    Raises
    ------
    InputError
        If the folder cannot be written to.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from firefleet.outputs import write_text_atomic
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = pathlib.Path(folder.name) / "note.txt"
    >>> write_text_atomic(path, "hello")
    >>> path.read_text(), [p.name for p in path.parent.iterdir()]
    ('hello', ['note.txt'])
    >>> folder.cleanup()
    """
    dest = Path(dest)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".tmp", dir=dest.parent)
    except OSError as exc:
        raise InputError(f"{dest}: cannot write: {exc.strerror}") from None
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as handle:
            handle.write(text)
        os.replace(tmp, dest)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
