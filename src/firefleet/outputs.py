"""Writing a command's outputs all or nothing.

A run's files are written into a staging folder beside the destination, which takes
the destination's place (``os.replace``, atomic on one file system) only when every
file is complete: an error or an interruption leaves no half-written output behind, a
run's folder holds that run and nothing else, and a folder holding files firefleet did
not write is refused, never emptied.
"""

from __future__ import annotations

import json
import math
import os
import secrets
import shlex
import shutil
import subprocess
import tempfile
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from firefleet.errors import InputError

__all__ = [
    "MANIFEST",
    "git_commit",
    "json_text",
    "run_record",
    "staged_dir",
    "write_text_atomic",
]


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


MANIFEST = ".firefleet-run.json"
"""The file in every output folder that names the files firefleet wrote there."""


def git_commit(root: str | Path | None = None) -> str | None:
    """The checkout's commit (with ``-dirty`` if tracked files changed), or None.

    ``root`` defaults to the folder firefleet's sources sit in (``src/..``); None when
    that is not a git checkout or git is not installed.
    """
    here = Path(root) if root is not None else Path(__file__).resolve().parents[2]
    if not (here / ".git").exists():
        return None
    git = ["git", "-C", str(here)]
    try:
        head = subprocess.run(
            [*git, "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10, check=True
        ).stdout.strip()
        changed = subprocess.run(
            [*git, "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return f"{head}-dirty" if changed else head


def run_record(command: Sequence[str], *, seed: int | None) -> dict[str, Any]:
    """What made a run: firefleet's version, the git commit, the seed and the command.

    Parameters
    ----------
    command : sequence of str
        The command line as typed, program name first.
    seed : int or None
        The run's random seed (None for a command that draws no random number).

    Returns
    -------
    dict
        ``firefleet_version``, ``git_commit`` (None outside a checkout), ``seed`` and
        ``command`` (one shell-quoted string).
    """
    from firefleet import __version__

    return {
        "firefleet_version": __version__,
        "git_commit": git_commit(),
        "seed": seed,
        "command": shlex.join(command),
    }


def _files(folder: Path) -> list[str]:
    return sorted(
        p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file() or p.is_symlink()
    )


def _check_ours(dest: Path) -> None:
    """Raise unless ``dest`` is absent, empty, or holds only files a run of ours wrote."""
    if not dest.exists():
        return
    if not dest.is_dir():
        raise InputError(f"--out {dest}: exists and is not a folder")
    if Path.cwd().resolve().is_relative_to(dest.resolve()):
        raise InputError(f"--out {dest}: is the current folder or holds it; name a new folder")
    present = _files(dest)
    if not present:
        return
    ours: set[str] = set()
    try:
        listed = json.loads((dest / MANIFEST).read_text(encoding="utf-8")).get("files", [])
        ours = {str(name) for name in listed} | {MANIFEST}
    except (OSError, ValueError, AttributeError):
        pass
    foreign = [name for name in present if name not in ours]
    if foreign:
        shown = ", ".join(foreign[:3]) + (
            f" and {len(foreign) - 3} more" if len(foreign) > 3 else ""
        )
        raise InputError(
            f"--out {dest}: holds files firefleet did not write ({shown}); "
            "name a new or empty folder, or move them"
        )


@contextmanager
def staged_dir(
    destination: str | Path, *, record: Mapping[str, Any] | None = None
) -> Iterator[Path]:
    """Stage a run's folder and put it in place of ``destination`` when the block succeeds.

    Yields a new folder beside ``destination``; write the outputs into it (subfolders
    allowed). On a clean exit the staged folder, with a manifest (``.firefleet-run.json``:
    ``record`` and the list of files), replaces ``destination`` as a whole, so the folder
    holds this run and nothing else. On an exception nothing in ``destination`` changes.

    Parameters
    ----------
    destination : str or Path
        The run's folder: absent, empty, or a previous run's folder.
    record : mapping, optional
        What made the run (see :func:`run_record`), written into the manifest.

    Raises
    ------
    InputError
        If ``destination`` is not a folder, holds a file no firefleet run wrote (checked
        before the block runs and again before the swap; such files are never deleted),
        or cannot be created.

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
    >>> sorted(p.name for p in out.iterdir())  # the outputs and the run's manifest
    ['.firefleet-run.json', 'metrics.json']
    >>> folder.cleanup()
    """
    dest = Path(destination)
    _check_ours(dest)
    parent = dest.resolve().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        stage = _new_folder(parent, f".{dest.name}.staging-")
    except OSError as exc:
        raise InputError(f"--out {dest}: cannot create: {exc.strerror}") from None
    try:
        yield stage
        manifest = {**(record or {}), "files": _files(stage)}
        (stage / MANIFEST).write_text(json_text(manifest), encoding="utf-8")
        _check_ours(dest)
        if dest.exists():
            old = _new_folder(parent, f".{dest.name}.previous-")
            os.replace(dest, old / "run")
            try:
                os.replace(stage, dest)
            except BaseException:
                os.replace(old / "run", dest)
                raise
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(stage, dest)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def _new_folder(parent: Path, prefix: str) -> Path:
    """A new empty folder ``parent/prefix<random>`` made with the user's umask."""
    while True:
        path = parent / f"{prefix}{secrets.token_hex(4)}"
        try:
            path.mkdir()
        except FileExistsError:
            continue
        return path


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
