"""Reading and writing SLAM logs: GTSAM's ``load2D`` text format and firefleet's own.

Both are line-oriented text, one record per line, whitespace-separated, ``#`` starting a
comment. The reader accepts the union of the two:

``ODOMETRY i j dx dy dtheta c11 c12 c13 c22 c23 c33``
    Relative motion from pose ``i`` to pose ``j`` in pose ``i``'s frame [m, m, rad] and
    the upper triangle of its covariance (GTSAM ``load2D``; the Victoria Park file).
    The lines must form one chain: each line's ``i`` is the previous line's ``j``.
``LANDMARK i l dx dy c11 c12 c22``
    Landmark ``l`` seen from pose ``i`` at ``(dx, dy)`` in pose ``i``'s frame, with a
    2 x 2 covariance (GTSAM ``load2D``; Victoria Park). Converted to range and bearing
    as GTSAM converts it: when ``c11 == c22`` and ``c12 == 0`` the bearing and range
    standard deviations are ``sqrt(c11 / 10)`` [rad] and ``sqrt(c11)`` [m] (``load2D``
    takes the Cartesian figure as the uncertainty at 10 m); otherwise the Cartesian
    covariance is propagated through the polar Jacobian.
``BR i l bearing range bearing_std range_std``
    A bearing-range observation (GTSAM ``load2D``). firefleet writes ``l = -1`` for a
    detection whose landmark is not known (a spurious one in simulation): a filter with
    given association skips it, one with unknown association uses it.

firefleet's simulated logs (:func:`firefleet.sim.world.simulate_drive` writes them) add
lines of their own:

``FIREFLEET-SLAM-LOG 1``
    The format and its version, on the first line.
``SENSOR fov_rad max_range_m``
    The sensor's field of view [rad] and range [m] (for removing landmarks that should
    have been seen and were not).
``TRUTH_POSE i t x y theta``
    Ground truth of pose ``i`` at time ``t`` [s].
``TRUTH_LANDMARK l x y``
    Ground-truth position of landmark ``l`` [m].

Observations are stored internally as (range [m], bearing [rad]).

GTSAM's ``load2D`` cannot read firefleet's own files: it stops at their first line, and
an unknown landmark ``-1`` is not a valid key. :func:`gtsam_text` writes the part it
reads (the odometry chain and the observations of known landmarks); load it with
``gtsam.load2D(path, noiseFormat=gtsam.NoiseFormat.NoiseFormatCOV)``, since the
odometry's covariances are full and ``load2D``'s default only recognises diagonal ones.
"""

from __future__ import annotations

import gzip
import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from firefleet._typing import FloatArray, IntArray
from firefleet.errors import InputError

__all__ = ["FORMAT_TAG", "SlamLog", "format_log", "gtsam_text", "read_log"]


FORMAT_TAG = "FIREFLEET-SLAM-LOG"
"""First word of firefleet's own log files (then the version number)."""
FORMAT_VERSION = 1

_FIELDS = {
    "ODOMETRY": 11,
    "LANDMARK": 7,
    "BR": 6,
    "SENSOR": 2,
    "TRUTH_POSE": 5,
    "TRUTH_LANDMARK": 3,
    FORMAT_TAG: 1,
}
MAX_ABS_VALUE = 1e12
"""Largest magnitude of a number in a log (metres, radians, their variances, seconds):
the filter squares and multiplies them, and 1e308 would overflow to inf silently."""
_INT_FIELDS = {"ODOMETRY": 2, "LANDMARK": 2, "BR": 2, "TRUTH_POSE": 1, "TRUTH_LANDMARK": 1}


@dataclass(frozen=True)
class SlamLog:
    """A SLAM log: an odometry chain of T poses and M landmark observations.

    Attributes
    ----------
    name : str
        Where it came from (the file name).
    pose_ids : ndarray of int64, shape (T,)
        The log's pose ids in chain order.
    odometry : ndarray, shape (T - 1, 3)
        Motion from pose k to k + 1 in pose k's frame: dx, dy [m], dtheta [rad].
    odometry_cov : ndarray, shape (T - 1, 3, 3)
    obs_step : ndarray of int64, shape (M,)
        Index (0..T-1) into ``pose_ids`` of the pose each observation was made from,
        non-decreasing.
    obs_landmark : ndarray of int64, shape (M,)
        Landmark id, -1 when the log gives no association.
    obs_z : ndarray, shape (M, 2)
        Range [m], bearing [rad].
    obs_cov : ndarray, shape (M, 2, 2)
        Covariance of (range, bearing).
    sensor_fov_rad, sensor_max_range_m : float or None
        The sensor's field of view and range when the log says them.
    truth_time_s : ndarray, shape (T,) or None
    truth_pose : ndarray, shape (T, 3) or None
    truth_landmark_ids : ndarray of int64, shape (L,) or None
    truth_landmarks : ndarray, shape (L, 2) or None

    Examples
    --------
    >>> from firefleet.estimation.logs import parse_log
    >>> log = parse_log(["ODOMETRY 0 1 1 0 0 1e-4 0 0 1e-4 0 1e-6", "LANDMARK 1 7 3 4 0.01 0 0.01"])
    >>> log.n_poses, log.n_observations, log.landmark_ids.tolist(), log.obs_z.round(4).tolist()
    (2, 1, [7], [[5.0, 0.9273]])
    >>> log.dead_reckoning().tolist()
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
    """

    name: str
    pose_ids: IntArray
    odometry: FloatArray
    odometry_cov: FloatArray
    obs_step: IntArray
    obs_landmark: IntArray
    obs_z: FloatArray
    obs_cov: FloatArray
    sensor_fov_rad: float | None = None
    sensor_max_range_m: float | None = None
    truth_time_s: FloatArray | None = None
    truth_pose: FloatArray | None = None
    truth_landmark_ids: IntArray | None = None
    truth_landmarks: FloatArray | None = None

    @property
    def n_poses(self) -> int:
        """Number of poses T."""
        return int(self.pose_ids.shape[0])

    @property
    def n_observations(self) -> int:
        """Number of observations M."""
        return int(self.obs_step.shape[0])

    @property
    def landmark_ids(self) -> IntArray:
        """The distinct landmark ids observed (sorted, without -1)."""
        ids = np.unique(self.obs_landmark)
        return np.asarray(ids[ids >= 0], dtype=np.int64)

    def dead_reckoning(self) -> FloatArray:
        """Poses ``(T, 3)`` from composing the odometry from the origin."""
        from firefleet.estimation.particle_filter import compose

        out = np.zeros((self.n_poses, 3))
        for k in range(self.n_poses - 1):
            out[k + 1] = compose(out[k], self.odometry[k])
        return out


def _upper3(c: list[float]) -> FloatArray:
    c11, c12, c13, c22, c23, c33 = c
    return np.array([[c11, c12, c13], [c12, c22, c23], [c13, c23, c33]])


_FIELD_NO = {("ODOMETRY", "c11"): 6, ("ODOMETRY", "c22"): 9, ("ODOMETRY", "c33"): 11}
_FIELD_NO |= {("LANDMARK", "c11"): 5, ("LANDMARK", "c22"): 7}


def _check_variances(
    where: str, tag: str, variances: dict[str, float], *, strict: bool = False
) -> None:
    """A variance (a covariance's diagonal) must be >= 0 (> 0 with ``strict``)."""
    for name, value in variances.items():
        if value < 0.0 or (strict and value == 0.0):
            bound = "> 0" if strict else ">= 0"
            raise InputError(
                f"{where}: {tag} variance {name} (field {_FIELD_NO[tag, name]}) must be "
                f"{bound}, got {value:g}"
            )


def _landmark_to_polar(
    dx: float, dy: float, c11: float, c12: float, c22: float
) -> tuple[float, float, FloatArray]:
    """Range, bearing and their covariance of a LANDMARK line (see the module notes)."""
    rng = math.hypot(dx, dy)
    bearing = math.atan2(dy, dx)
    if abs(c11 - c22) < 1e-4 and c12 == 0.0:  # GTSAM load2D's reading (dataset.cpp)
        return rng, bearing, np.diag([c11, c11 / 10.0])
    jac = np.array([[dx / rng, dy / rng], [-dy / rng**2, dx / rng**2]])
    cov = jac @ np.array([[c11, c12], [c12, c22]]) @ jac.T
    return rng, bearing, cov


def _open_text(path: Path) -> str:
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a folder, not a log file") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read: {exc.strerror}") from None
    if raw[:2] == b"\x1f\x8b":
        try:
            raw = gzip.decompress(raw)
        except (OSError, EOFError) as exc:
            raise InputError(f"{path}: corrupt gzip file: {exc}") from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a text file (byte {exc.start} is not UTF-8)") from None


def read_log(path: str | Path) -> SlamLog:
    """Read a SLAM log (GTSAM ``load2D`` text, firefleet's own, or either gzipped).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    SlamLog

    Raises
    ------
    InputError
        If the file is missing, empty, or a line is malformed: the message starts with
        ``path:line:`` and says what is wrong.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from firefleet.estimation import read_log
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = pathlib.Path(folder.name) / "tiny.txt"
    >>> _ = path.write_text("ODOMETRY 0 1 1 0 0 1e-4 0 0 1e-4 0 1e-6")
    >>> read_log(path).odometry.tolist()
    [[1.0, 0.0, 0.0]]
    >>> folder.cleanup()
    """
    p = Path(path)
    return parse_log(_open_text(p).splitlines(), name=str(p))


def parse_log(lines: Iterable[str], *, name: str = "<log>") -> SlamLog:
    """Parse the lines of a SLAM log (see :func:`read_log`)."""
    pose_ids: list[int] = []
    odo: list[list[float]] = []
    odo_cov: list[FloatArray] = []
    obs: list[tuple[int, int, float, float, FloatArray, int]] = []
    truth: dict[int, tuple[float, float, float, float]] = {}
    truth_lm: dict[int, tuple[float, float]] = {}
    sensor: tuple[float, float] | None = None
    n_lines = 0
    for lineno, raw in enumerate(lines, start=1):
        n_lines = lineno
        text = raw.split("#", 1)[0].strip()
        if not text:
            continue
        words = text.split()
        tag = words[0]
        where = f"{name}:{lineno}"
        if tag not in _FIELDS:
            raise InputError(f"{where}: unknown record {tag!r} (expected one of {sorted(_FIELDS)})")
        if len(words) - 1 != _FIELDS[tag]:
            raise InputError(f"{where}: {tag} needs {_FIELDS[tag]} fields, got {len(words) - 1}")
        n_int = _INT_FIELDS.get(tag, 0)
        try:
            ints = [int(w) for w in words[1 : 1 + n_int]]
        except ValueError:
            raise InputError(
                f"{where}: {tag} ids must be integers, got {words[1 : 1 + n_int]}"
            ) from None
        try:
            nums = [float(w) for w in words[1 + n_int :]]
        except ValueError:
            raise InputError(f"{where}: {tag} has a field that is not a number: {text!r}") from None
        if not all(math.isfinite(v) for v in nums):
            raise InputError(f"{where}: {tag} has a non-finite number: {text!r}")
        big = next((k for k, v in enumerate(nums) if abs(v) > MAX_ABS_VALUE), None)
        if big is not None:
            raise InputError(
                f"{where}: {tag} field {1 + n_int + big} is {words[1 + n_int + big]}: beyond "
                f"{MAX_ABS_VALUE:g}, not a measurement (its squares would overflow)"
            )
        if tag == FORMAT_TAG:
            if int(nums[0]) != FORMAT_VERSION:
                raise InputError(f"{where}: unsupported {FORMAT_TAG} version {words[1]}")
        elif tag == "ODOMETRY":
            i, j = ints
            if not pose_ids:
                pose_ids.append(i)
            elif i != pose_ids[-1]:
                raise InputError(
                    f"{where}: ODOMETRY from pose {i}, but the chain is at pose {pose_ids[-1]}"
                )
            _check_variances(where, tag, {"c11": nums[3], "c22": nums[6], "c33": nums[8]})
            cov = _upper3(nums[3:])
            if np.any(np.linalg.eigvalsh(cov) < -1e-12):
                raise InputError(f"{where}: ODOMETRY covariance is not positive semi-definite")
            pose_ids.append(j)
            odo.append(nums[:3])
            odo_cov.append(cov)
        elif tag == "LANDMARK":
            dx, dy, c11, c12, c22 = nums
            if dx == 0.0 and dy == 0.0:
                raise InputError(f"{where}: LANDMARK at zero range")
            _check_variances(where, tag, {"c11": c11, "c22": c22}, strict=True)
            if c12 * c12 >= c11 * c22:
                raise InputError(
                    f"{where}: LANDMARK covariance is not positive definite: "
                    f"c12 = {c12:g} needs c12^2 < c11 c22 = {c11 * c22:g}"
                )
            r, b, cov = _landmark_to_polar(dx, dy, c11, c12, c22)
            obs.append((ints[0], ints[1], r, b, cov, lineno))
        elif tag == "BR":
            bearing, r, sb, sr = nums
            if r <= 0.0 or sb <= 0.0 or sr <= 0.0:
                raise InputError(f"{where}: BR range and standard deviations must be > 0")
            obs.append((ints[0], ints[1], r, bearing, np.diag([sr * sr, sb * sb]), lineno))
        elif tag == "SENSOR":
            if nums[0] <= 0.0 or nums[1] <= 0.0:
                raise InputError(f"{where}: SENSOR fov_rad and max_range_m must be > 0")
            sensor = (nums[0], nums[1])
        elif tag == "TRUTH_POSE":
            truth[ints[0]] = (nums[0], nums[1], nums[2], nums[3])
        else:  # TRUTH_LANDMARK
            truth_lm[ints[0]] = (nums[0], nums[1])
    if n_lines == 0 or not pose_ids:
        raise InputError(f"{name}: no ODOMETRY lines: not a SLAM log (or an empty file)")
    index = {pid: k for k, pid in enumerate(pose_ids)}
    if len(index) != len(pose_ids):
        raise InputError(f"{name}: the ODOMETRY chain visits a pose id twice")
    obs_step = np.empty(len(obs), dtype=np.int64)
    for n, (pid, _, _, _, _, lineno) in enumerate(obs):
        if pid not in index:
            raise InputError(f"{name}:{lineno}: observation from pose {pid}, not in the chain")
        obs_step[n] = index[pid]
    order = np.argsort(obs_step, kind="stable")
    truth_time = truth_pose = None
    if truth:
        missing = [pid for pid in pose_ids if pid not in truth]
        if missing:
            raise InputError(f"{name}: TRUTH_POSE missing for pose(s) {missing[:5]}")
        arr = np.array([truth[pid] for pid in pose_ids])
        truth_time, truth_pose = arr[:, 0], arr[:, 1:]
    lm_ids = lm_xy = None
    if truth_lm:
        lm_ids = np.array(sorted(truth_lm), dtype=np.int64)
        lm_xy = np.array([truth_lm[int(i)] for i in lm_ids]).reshape(-1, 2)
    return SlamLog(
        name=name,
        pose_ids=np.array(pose_ids, dtype=np.int64),
        odometry=np.array(odo, dtype=np.float64).reshape(-1, 3),
        odometry_cov=np.array(odo_cov, dtype=np.float64).reshape(-1, 3, 3),
        obs_step=obs_step[order],
        obs_landmark=np.array([o[1] for o in obs], dtype=np.int64)[order],
        obs_z=np.array([[o[2], o[3]] for o in obs], dtype=np.float64).reshape(-1, 2)[order],
        obs_cov=np.array([o[4] for o in obs], dtype=np.float64).reshape(-1, 2, 2)[order],
        sensor_fov_rad=None if sensor is None else sensor[0],
        sensor_max_range_m=None if sensor is None else sensor[1],
        truth_time_s=truth_time,
        truth_pose=truth_pose,
        truth_landmark_ids=lm_ids,
        truth_landmarks=lm_xy,
    )


_G = ".17g"  # 17 significant digits: a float written and read back is the same float


def _chain_lines(log: SlamLog, *, firefleet: bool) -> Iterator[str]:
    """Per pose: its TRUTH_POSE (firefleet's own format), BR lines, then the ODOMETRY line.

    Without ``firefleet`` (GTSAM's subset) the truth and the observations of unknown
    landmarks (``-1``) are left out.
    """
    g = _G
    starts = np.searchsorted(log.obs_step, np.arange(log.n_poses + 1))
    for k, pid in enumerate(log.pose_ids):
        if firefleet and log.truth_pose is not None and log.truth_time_s is not None:
            x, y, th = log.truth_pose[k]
            yield f"TRUTH_POSE {pid} {log.truth_time_s[k]:{g}} {x:{g}} {y:{g}} {th:{g}}"
        for n in range(starts[k], starts[k + 1]):
            if not firefleet and log.obs_landmark[n] < 0:
                continue
            r, b = log.obs_z[n]
            sr, sb = np.sqrt(log.obs_cov[n, 0, 0]), np.sqrt(log.obs_cov[n, 1, 1])
            yield f"BR {pid} {log.obs_landmark[n]} {b:{g}} {r:{g}} {sb:{g}} {sr:{g}}"
        if k + 1 < log.n_poses:
            c = log.odometry_cov[k]
            vals = (*log.odometry[k], c[0, 0], c[0, 1], c[0, 2], c[1, 1], c[1, 2], c[2, 2])
            odo = " ".join(f"{v:{g}}" for v in vals)
            yield f"ODOMETRY {pid} {log.pose_ids[k + 1]} {odo}"


def gtsam_text(log: SlamLog) -> str:
    """The part of ``log`` that GTSAM's ``load2D`` reads: ODOMETRY and BR lines.

    Observations without a landmark id (``-1``) are left out. The odometry's full
    covariance is written as ``c11 c12 c13 c22 c23 c33`` (``NoiseFormatCOV``).

    Examples
    --------
    >>> from firefleet.estimation.logs import gtsam_text, parse_log
    >>> log = parse_log(["ODOMETRY 0 1 1 0 0 1e-4 0 0 1e-4 0 1e-6", "LANDMARK 1 7 3 4 0.01 0 0.01"])
    >>> [line.split()[0] for line in gtsam_text(log).splitlines()]
    ['ODOMETRY', 'BR']
    """
    return "\n".join(_chain_lines(log, firefleet=False)) + "\n"


def format_log(log: SlamLog) -> str:
    """firefleet's text for ``log`` (read back by :func:`read_log` to the same arrays).

    Numbers are written with 17 significant digits, so a round trip is exact.
    Observations become ``BR`` lines with diagonal noise (the off-diagonal term of a
    non-diagonal observation covariance is dropped).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation.logs import format_log, parse_log
    >>> log = parse_log(["ODOMETRY 0 1 1 0 0 1e-4 0 0 1e-4 0 1e-6", "LANDMARK 1 7 3 4 0.01 0 0.01"])
    >>> text = format_log(log)
    >>> text.splitlines()[0], np.array_equal(parse_log(text.splitlines()).obs_z, log.obs_z)
    ('FIREFLEET-SLAM-LOG 1', True)
    """
    g = _G
    lines = [
        f"{FORMAT_TAG} {FORMAT_VERSION}",
        f"# {log.name}: {log.n_poses} poses, {log.n_observations} observations",
    ]
    if log.sensor_fov_rad is not None and log.sensor_max_range_m is not None:
        lines.append(f"SENSOR {log.sensor_fov_rad:{g}} {log.sensor_max_range_m:{g}}")
    if log.truth_landmark_ids is not None and log.truth_landmarks is not None:
        for lid, (x, y) in zip(log.truth_landmark_ids, log.truth_landmarks, strict=True):
            lines.append(f"TRUTH_LANDMARK {lid} {x:{g}} {y:{g}}")
    lines.extend(_chain_lines(log, firefleet=True))
    return "\n".join(lines) + "\n"
