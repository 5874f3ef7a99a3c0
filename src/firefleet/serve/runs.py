"""The run folders a dashboard serves: finding them, and one run's summary.

A run folder is one a firefleet command wrote: it holds ``metrics.json``, ``result.npz``
or ``run.mcap`` (``firefleet run``, every scenario folder of ``firefleet reproduce``).
The dashboard knows each by an id made of its folder name (``formation-3``; a second
folder of the same name becomes ``formation-3-2``), never by a path a request names:
a request can reach the folders it was given and nothing else.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from firefleet.errors import InputError
from firefleet.outputs import MANIFEST

__all__ = ["RUN_FILES", "RunFolder", "find_runs", "read_json", "run_summary"]

RUN_FILES = ("metrics.json", "result.npz", "run.mcap")
"""A folder holding any of these is a run folder."""

_MAX_DEPTH = 4
"""How deep below a given folder runs are looked for."""


@dataclass(frozen=True)
class RunFolder:
    """A run the dashboard serves.

    Attributes
    ----------
    run_id : str
        Its id in URLs (letters, digits, ``.``, ``_``, ``-``).
    path : Path
        The folder (resolved).
    """

    run_id: str
    path: Path

    def file(self, name: str) -> Path | None:
        """The path of ``name`` in the folder if the folder holds such a regular file
        (no subfolder, no link out), else None."""
        if name in ("", ".", "..") or "/" in name or "\\" in name or "\0" in name:
            return None
        path = self.path / name
        if path.is_symlink() or not path.is_file():
            return None
        return path


def _is_run(folder: Path) -> bool:
    return any((folder / name).is_file() for name in RUN_FILES)


def _walk(root: Path) -> list[Path]:
    found: list[Path] = []
    for here, subdirs, _ in os.walk(root):
        depth = len(Path(here).relative_to(root).parts)
        subdirs[:] = (
            sorted(d for d in subdirs if not d.startswith(".")) if depth < _MAX_DEPTH else []
        )
        if _is_run(Path(here)):
            found.append(Path(here))
    return found


def find_runs(folders: Sequence[str | Path]) -> list[RunFolder]:
    """The runs in ``folders``: each a run folder, or a folder with run folders inside.

    Parameters
    ----------
    folders : sequence of str or Path
        What ``firefleet serve RUN_DIR ...`` was given.

    Returns
    -------
    list of RunFolder
        In the order given, each root's runs sorted by path; ids unique.

    Raises
    ------
    InputError
        If a folder does not exist or holds no run.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from firefleet.serve.runs import find_runs
    >>> root = tempfile.TemporaryDirectory()
    >>> for name in ("a/x", "b/x"):
    ...     (pathlib.Path(root.name) / name).mkdir(parents=True)
    ...     _ = (pathlib.Path(root.name) / name / "metrics.json").write_text("{}")
    >>> [run.run_id for run in find_runs([root.name])]
    ['x', 'x-2']
    >>> root.cleanup()
    """
    runs: list[RunFolder] = []
    seen_paths: set[Path] = set()
    ids: set[str] = set()
    for given in folders:
        root = Path(given)
        if not root.is_dir():
            raise InputError(f"RUN_DIR {given}: no such folder")
        inside = _walk(root.resolve())
        if not inside:
            raise InputError(
                f"RUN_DIR {given}: holds no run folder (one with {', '.join(RUN_FILES)})"
            )
        for path in inside:
            if path in seen_paths:
                continue
            seen_paths.add(path)
            base = re.sub(r"[^A-Za-z0-9._-]+", "-", path.name).strip(".-") or "run"
            run_id, k = base, 1
            while run_id in ids:
                k += 1
                run_id = f"{base}-{k}"
            ids.add(run_id)
            runs.append(RunFolder(run_id=run_id, path=path))
    return runs


def read_json(path: Path | None) -> dict[str, Any]:
    """A JSON object file's content; ``{}`` if absent or not a JSON object."""
    if path is None:
        return {}
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return document if isinstance(document, dict) else {}


def run_summary(run: RunFolder) -> dict[str, Any]:
    """The index's line for a run: name, scenario, date, seed, claims passed, what replays.

    Returns
    -------
    dict
        ``id``, ``name`` (folder), ``scenario``, ``date`` (ISO 8601, UTC, of the
        manifest or ``metrics.json``), ``seed`` (None if unknown), ``claims_passed``,
        ``claims_total``, ``replay`` (``"result.npz"``, ``"run.mcap"`` or None).
    """
    metrics_path = run.file("metrics.json")
    metrics = read_json(metrics_path)
    manifest_path = run.file(MANIFEST)
    manifest = read_json(manifest_path)
    provenance = metrics.get("provenance")
    provenance = provenance if isinstance(provenance, dict) else {}
    listed = metrics.get("claims")
    claims: list[Any] = listed if isinstance(listed, list) else []
    stamp_file = manifest_path or metrics_path or run.path
    date = dt.datetime.fromtimestamp(stamp_file.stat().st_mtime, tz=dt.UTC)
    replay = next((name for name in ("result.npz", "run.mcap") if run.file(name)), None)
    seed = provenance.get("seed", manifest.get("seed"))
    return {
        "id": run.run_id,
        "name": run.path.name,
        "scenario": str(metrics.get("scenario", run.path.name)),
        "date": date.isoformat(timespec="seconds").replace("+00:00", "Z"),
        "seed": seed if isinstance(seed, int) else None,
        "claims_passed": sum(1 for c in claims if isinstance(c, dict) and c.get("passed") is True),
        "claims_total": len(claims),
        "replay": replay,
    }
