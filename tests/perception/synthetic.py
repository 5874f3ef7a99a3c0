"""Synthetic stereo data with known ground truth: chessboards seen by a known camera pair.

A flat chessboard texture is mapped into each camera exactly: for every pixel of the
distorted image, ``cv2.undistortPoints`` gives its ideal pinhole position, the board
plane's homography gives the board point seen there, and ``cv2.remap`` samples the
texture at it. So the images obey the pinhole-plus-distortion model whose parameters
the calibration must recover.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

SIZE = (640, 480)
"""(width, height) of the synthetic webcams [px] (the deliverable's webcams)."""
PATTERN = (9, 6)
"""Inner corners (columns, rows) of the board."""
SQUARE_M = 0.03
"""Side of a board square [m]."""
TEXEL_PER_SQUARE = 40
"""Texture pixels per board square."""


@dataclass(frozen=True)
class Rig:
    """A known stereo rig: X_right = R X_left + t."""

    k_left: FloatArray
    dist_left: FloatArray
    k_right: FloatArray
    dist_right: FloatArray
    rotation: FloatArray
    translation_m: FloatArray


def make_rig() -> Rig:
    """A 640 x 480 webcam pair, 12 cm apart, slightly toed-in, with barrel distortion."""
    k_left = np.array([[600.0, 0.0, 322.0], [0.0, 600.0, 238.0], [0.0, 0.0, 1.0]])
    k_right = np.array([[605.0, 0.0, 316.0], [0.0, 605.0, 243.0], [0.0, 0.0, 1.0]])
    dist_left = np.array([-0.12, 0.05, 0.0005, -0.0004, 0.0])
    dist_right = np.array([-0.10, 0.04, -0.0003, 0.0006, 0.0])
    rotation, _ = cv2.Rodrigues(np.array([0.01, -0.03, 0.005]))
    translation = np.array([-0.12, 0.002, 0.001])
    return Rig(k_left, dist_left, k_right, dist_right, np.asarray(rotation), translation)


def board_texture() -> NDArray[np.uint8]:
    """The chessboard with a one-square white border, grey levels 30 and 225."""
    cols, rows = PATTERN[0] + 1, PATTERN[1] + 1  # squares
    n = TEXEL_PER_SQUARE
    tex = np.full(((rows + 2) * n, (cols + 2) * n), 225, np.uint8)
    for r in range(rows):
        for c in range(cols):
            if (r + c) % 2 == 0:
                tex[(r + 1) * n : (r + 2) * n, (c + 1) * n : (c + 2) * n] = 30
    return np.asarray(cv2.GaussianBlur(tex, (0, 0), 0.7))


def render(
    texture: NDArray[np.uint8],
    k: FloatArray,
    dist: FloatArray,
    rot: FloatArray,
    trans: FloatArray,
    undistorted_grid: FloatArray,
) -> NDArray[np.uint8]:
    """Render the board at pose (rot, trans) (board frame to camera frame, metres).

    ``undistorted_grid`` is ``(H, W, 2)``: the ideal pinhole pixel of every distorted
    image pixel (from :func:`ideal_grid`). Board coordinates (x, y) in metres have their
    origin at the first inner corner.
    """
    # board point (u, v) [m] -> camera: rot @ (u, v, 0) + trans; pinhole: K (...)
    h_board = k @ np.column_stack([rot[:, 0], rot[:, 1], trans])
    h_inv = np.linalg.inv(h_board)
    g = undistorted_grid.reshape(-1, 2)
    q = g @ h_inv[:, :2].T + h_inv[:, 2]
    uv = q[:, :2] / q[:, 2:3]  # board metres
    n = TEXEL_PER_SQUARE
    tx = (uv / SQUARE_M + 2.0) * n - 0.5  # first inner corner at 2 squares from the edge
    shape = undistorted_grid.shape[:2]
    mx = tx[:, 0].reshape(shape).astype(np.float32)
    my = tx[:, 1].reshape(shape).astype(np.float32)
    img = cv2.remap(
        texture, mx, my, cv2.INTER_AREA, borderMode=cv2.BORDER_CONSTANT, borderValue=128
    )
    return np.asarray(img, dtype=np.uint8)


def ideal_grid(k: FloatArray, dist: FloatArray) -> FloatArray:
    """For each pixel of a distorted image, its ideal (undistorted) pixel position."""
    w, h = SIZE
    xs, ys = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    pts = np.column_stack([xs.ravel(), ys.ravel()]).reshape(-1, 1, 2)
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-10)
    und = cv2.undistortPointsIter(pts, k, dist, np.eye(3), k, crit)
    return np.asarray(und, dtype=np.float64).reshape(h, w, 2)


def board_poses(n: int, rng: np.random.Generator) -> list[tuple[FloatArray, FloatArray]]:
    """``n`` board poses in the left camera's frame, in front of both cameras."""
    poses = []
    width = (PATTERN[0] - 1) * SQUARE_M
    height = (PATTERN[1] - 1) * SQUARE_M
    for _ in range(n):
        rvec = rng.uniform(-0.45, 0.45, 3) * np.array([1.0, 1.0, 0.4])
        rot, _ = cv2.Rodrigues(rvec)
        centre = np.array(
            [rng.uniform(-0.1, 0.04), rng.uniform(-0.06, 0.06), rng.uniform(0.5, 0.8)]
        )
        trans = centre - rot @ np.array([width / 2, height / 2, 0.0])
        poses.append((np.asarray(rot), trans))
    return poses


def stereo_chessboards(
    n: int, seed: int = 7
) -> tuple[Rig, list[NDArray[np.uint8]], list[NDArray[np.uint8]]]:
    """``n`` synthetic chessboard pairs through :func:`make_rig`."""
    rig = make_rig()
    rng = np.random.default_rng(seed)
    tex = board_texture()
    grid_l = ideal_grid(rig.k_left, rig.dist_left)
    grid_r = ideal_grid(rig.k_right, rig.dist_right)
    lefts, rights = [], []
    for rot, trans in board_poses(n, rng):
        lefts.append(render(tex, rig.k_left, rig.dist_left, rot, trans, grid_l))
        rot_r = rig.rotation @ rot
        trans_r = rig.rotation @ trans + rig.translation_m
        rights.append(render(tex, rig.k_right, rig.dist_right, rot_r, trans_r, grid_r))
    return rig, lefts, rights


def board_facing(
    distance_m: float, *, baseline_m: float = 0.1
) -> tuple[Rig, NDArray[np.uint8], NDArray[np.uint8]]:
    """A chessboard facing the left camera of :func:`make_rig` at ``distance_m``.

    The rig is :func:`make_rig`'s (same intrinsics, distortion and toe-in) with its
    baseline scaled to ``baseline_m``. The board plane is ``Z = distance_m`` in the left
    camera's frame, centred on the optical axis: every point of it is at least
    ``distance_m`` from the camera centre, and its centre exactly that far.
    """
    base = make_rig()
    t = base.translation_m * (baseline_m / float(np.linalg.norm(base.translation_m)))
    rig = Rig(base.k_left, base.dist_left, base.k_right, base.dist_right, base.rotation, t)
    width = (PATTERN[0] - 1) * SQUARE_M
    height = (PATTERN[1] - 1) * SQUARE_M
    rot = np.eye(3)
    trans = np.array([-width / 2, -height / 2, distance_m])
    tex = board_texture()
    left = render(tex, rig.k_left, rig.dist_left, rot, trans, ideal_grid(rig.k_left, rig.dist_left))
    rot_r = rig.rotation @ rot
    trans_r = rig.rotation @ trans + rig.translation_m
    grid_r = ideal_grid(rig.k_right, rig.dist_right)
    right = render(tex, rig.k_right, rig.dist_right, rot_r, trans_r, grid_r)
    return rig, left, right
