"""Reading maps: a built-in name, or a ROS ``map_server`` YAML file and its image.

A ``map_server`` map is a YAML file::

    image: office.pgm          # PGM or PNG; a relative path is relative to this file
    resolution: 0.05           # m per cell
    origin: [0.0, 0.0, 0.0]    # x, y of the lower-left corner [m], yaw (must be 0)
    negate: 0                  # 1: white is occupied
    occupied_thresh: 0.65      # p above: occupied
    free_thresh: 0.196         # p below: free
    mode: trinary              # optional; trinary is the one supported

Each pixel's occupancy probability is ``p = (255 - v) / 255`` for grey level ``v``
(``v / 255`` with ``negate: 1``; colour pixels are averaged over their channels, a
fully transparent pixel is unknown), and the cell is occupied if ``p >
occupied_thresh``, free if ``p < free_thresh``, unknown otherwise. HouseExpo's PNG
floor plans (black walls on white) load the same way, with a YAML next to them.

References
----------
ROS ``map_server``: http://wiki.ros.org/map_server#Map_format
T. Li et al., "HouseExpo: A Large-scale 2D Indoor Layout Dataset", IROS 2019.
"""

from __future__ import annotations

import difflib
import io
import math
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.world._grid import OccupancyGrid

__all__ = ["BUILTIN_MAPS", "load_map", "parse_map"]

BUILTIN_MAPS = ("floor100", "maze", "office", "warehouse")
"""Names of the maps shipped in the package (``firefleet/world/maps/<name>.yaml``)."""

_REQUIRED = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")


def _builtin_files(name: str) -> tuple[str, str, bytes]:
    """The YAML text, image name and image bytes of a built-in map."""
    folder = resources.files("firefleet.world") / "maps"
    text = (folder / f"{name}.yaml").read_text(encoding="utf-8")
    meta = yaml.safe_load(text)
    return text, str(meta["image"]), (folder / str(meta["image"])).read_bytes()


def load_map(source: str | Path) -> OccupancyGrid:
    """An occupancy grid from a built-in map's name or a ``map_server`` YAML file.

    Parameters
    ----------
    source : str or Path
        ``"office"``, ``"warehouse"``, ``"maze"``, or the path of a YAML file (its image
        path, if relative, resolves against the YAML's folder).

    Returns
    -------
    OccupancyGrid
        Named after ``source``.

    Raises
    ------
    InputError
        An unknown name (with a suggestion), a missing file, a YAML without one of the
        keys, a value out of range, an image that cannot be read, or a map without a
        free cell; the message names the file and the key.

    Examples
    --------
    >>> from firefleet.world import load_map
    >>> grid = load_map("office")
    >>> grid.shape, grid.resolution_m, grid.width_m, grid.height_m
    ((200, 400), 0.05, 20.0, 10.0)
    >>> grid.occupied_at([[2.5, 5.0], [4.0, 2.0]]).tolist()  # the corridor, a wall
    [False, True]
    """
    text = str(source)
    if text in BUILTIN_MAPS:
        yaml_text, image, data = _builtin_files(text)
        return parse_map(yaml_text, {image: data}, name=text)
    path = Path(source)
    if path.suffix.lower() not in (".yaml", ".yml"):
        close = difflib.get_close_matches(text, BUILTIN_MAPS, n=1, cutoff=0.6)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise InputError(
            f"world.map: unknown map {text!r}{hint}; give a built-in name "
            f"({', '.join(BUILTIN_MAPS)}) or a map_server .yaml file"
        )
    try:
        yaml_text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{path}: no such map file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read: {exc}") from None
    meta = _read_yaml(yaml_text, str(path))
    image_key = meta.get("image")
    if not isinstance(image_key, str) or not image_key:
        raise InputError(f"{path}: key 'image' must be an image file name, got {image_key!r}")
    image_path = Path(image_key) if Path(image_key).is_absolute() else path.parent / image_key
    try:
        image_bytes = image_path.read_bytes()
    except OSError:
        raise InputError(f"{path}: image: no such file {str(image_path)!r}") from None
    return parse_map(yaml_text, {image_key: image_bytes}, name=str(path))


def _read_yaml(text: str, name: str) -> dict[str, Any]:
    try:
        meta = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise InputError(f"{name}: not valid YAML: {exc}".replace("\n", " ")) from None
    if not isinstance(meta, dict):
        raise InputError(f"{name}: a map_server YAML must be a mapping of keys")
    missing = [key for key in _REQUIRED if key not in meta]
    if missing:
        raise InputError(f"{name}: key {missing[0]!r} missing (map_server needs {_REQUIRED})")
    return meta


def _number(meta: dict[str, Any], key: str, name: str) -> float:
    value = meta[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"{name}: key {key!r} must be a number, got {value!r}")
    return float(value)


def parse_map(yaml_text: str, images: dict[str, bytes], *, name: str = "map") -> OccupancyGrid:
    """An occupancy grid from a ``map_server`` YAML text and its image's bytes.

    Parameters
    ----------
    yaml_text : str
        The YAML (see the module notes).
    images : dict of str to bytes
        The image file's bytes under the name the YAML's ``image`` gives.
    name : str
        Named in error messages and kept as the grid's name.

    Returns
    -------
    OccupancyGrid

    Examples
    --------
    >>> from firefleet.world import parse_map
    >>> pgm = b"P5\\n3 2\\n255\\n" + bytes([0, 254, 205, 254, 254, 0])
    >>> yaml_text = ("image: m.pgm\\nresolution: 0.5\\norigin: [1.0, 2.0, 0.0]\\n"
    ...              "negate: 0\\noccupied_thresh: 0.65\\nfree_thresh: 0.196\\n")
    >>> grid = parse_map(yaml_text, {"m.pgm": pgm})
    >>> grid.occupied.astype(int).tolist(), grid.free.astype(int).tolist()
    ([[1, 0, 0], [0, 0, 1]], [[0, 1, 0], [1, 1, 0]])
    >>> grid.origin_m, grid.extent_m
    ((1.0, 2.0), (1.0, 2.5, 2.0, 3.0))
    """
    meta = _read_yaml(yaml_text, name)
    mode = meta.get("mode", "trinary")
    if mode != "trinary":
        raise InputError(f"{name}: key 'mode' must be 'trinary' (the one supported), got {mode!r}")
    resolution = _number(meta, "resolution", name)
    if resolution <= 0:
        raise InputError(f"{name}: key 'resolution' must be > 0 m per cell, got {resolution}")
    origin = meta["origin"]
    if (
        not isinstance(origin, list)
        or len(origin) not in (2, 3)
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in origin)
        or not all(math.isfinite(v) for v in origin)
    ):
        raise InputError(f"{name}: key 'origin' must be [x, y, yaw] numbers, got {origin!r}")
    if len(origin) == 3 and origin[2] != 0:
        raise InputError(f"{name}: key 'origin': a rotated map (yaw {origin[2]}) is not supported")
    negate = meta["negate"]
    if negate not in (0, 1) or isinstance(negate, float):
        raise InputError(f"{name}: key 'negate' must be 0 or 1, got {negate!r}")
    occ_t = _number(meta, "occupied_thresh", name)
    free_t = _number(meta, "free_thresh", name)
    if not 0.0 <= free_t < occ_t <= 1.0:
        raise InputError(
            f"{name}: keys 'free_thresh' ({free_t}) and 'occupied_thresh' ({occ_t}) must "
            "satisfy 0 <= free_thresh < occupied_thresh <= 1"
        )
    image = str(meta["image"])
    if image not in images:
        raise InputError(f"{name}: key 'image': no image {image!r} given")
    p = _occupancy_probability(images[image], bool(negate), f"{name}: image {image!r}")
    occupied = p > occ_t
    free = p < free_t
    if not np.any(free):
        raise InputError(
            f"{name}: image {image!r} has no free cell (p < free_thresh {free_t}): "
            "nowhere for a robot to stand"
        )
    return OccupancyGrid(
        occupied, free, resolution_m=resolution, origin_m=(origin[0], origin[1]), name=name
    )


def _occupancy_probability(data: bytes, negate: bool, what: str) -> FloatArray:
    """Each pixel's occupancy probability (H, W), NaN where transparent (unknown)."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(io.BytesIO(data)) as img:
            img.load()
            if img.mode in ("RGBA", "LA", "PA") or (img.mode == "P" and "transparency" in img.info):
                rgba = np.asarray(img.convert("RGBA"), dtype=np.float64)
                grey = rgba[..., :3].mean(axis=-1)
                alpha = rgba[..., 3]
            elif img.mode in ("L", "1", "P", "RGB", "CMYK", "YCbCr"):
                rgb = np.asarray(img.convert("RGB"), dtype=np.float64)
                grey = rgb.mean(axis=-1)
                alpha = None
            else:  # 16-bit and float greys: scale to 0..255
                raw = np.asarray(img, dtype=np.float64)
                top = 65535.0 if img.mode.startswith("I;16") else max(float(raw.max()), 1.0)
                grey = raw * (255.0 / top)
                alpha = None
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as exc:
        raise InputError(f"{what} is not a valid PGM or PNG image: {exc}") from None
    if grey.ndim != 2 or grey.size == 0:
        raise InputError(f"{what} is not a valid 2-D image (shape {grey.shape})")
    p: FloatArray = grey / 255.0 if negate else (255.0 - grey) / 255.0
    if alpha is not None:
        p = np.where(alpha == 0, np.nan, p)
    return p
