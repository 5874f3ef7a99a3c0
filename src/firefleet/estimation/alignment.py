"""Rigid alignment of 2-D point sets and the absolute trajectory error.

Comparing a trajectory with a reference (ground truth, or a batch optimum that lives in
a frame of its own) is done after the rigid motion that best aligns them, without scale
(Umeyama 1991 with ``c = 1``; Horn 1987 in closed form). The absolute trajectory error is
the root mean square of the residual distances (Sturm et al. 2012, eq. 8).

References
----------
S. Umeyama, "Least-squares estimation of transformation parameters between two point
patterns", IEEE TPAMI 13(4), 1991.
J. Sturm et al., "A benchmark for the evaluation of RGB-D SLAM systems", IROS 2012.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError, as_float_array

__all__ = ["absolute_trajectory_error", "align_rigid_2d"]


def align_rigid_2d(source: ArrayLike, target: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """The rotation and translation that best map ``source`` onto ``target``.

    Parameters
    ----------
    source, target : array_like, shape (N, 2)
        Corresponding points [m], N >= 2.

    Returns
    -------
    rotation : ndarray, shape (2, 2)
        Proper rotation R (det +1).
    translation : ndarray, shape (2,)
        t, minimising ``sum |R source_i + t - target_i|^2`` (Umeyama 1991, eqs. 40-42,
        scale fixed at 1).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation.alignment import align_rigid_2d
    >>> source = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 2.0]])
    >>> target = source @ np.array([[0.0, -1.0], [1.0, 0.0]]).T + [3.0, 4.0]  # turned 90 deg
    >>> rotation, translation = align_rigid_2d(source, target)
    >>> (rotation.round(12) + 0.0).tolist(), translation.round(12).tolist()
    ([[0.0, -1.0], [1.0, 0.0]], [3.0, 4.0])
    """
    src = as_float_array(source, "source", (None, 2))
    dst = as_float_array(target, "target", (src.shape[0], 2))
    if src.shape[0] < 2:
        raise InputError(f"source must have at least 2 points, got {src.shape[0]}")
    mu_s, mu_d = src.mean(axis=0), dst.mean(axis=0)
    cov = (dst - mu_d).T @ (src - mu_s) / src.shape[0]
    u, _, vt = np.linalg.svd(cov)
    fix = np.diag([1.0, np.sign(np.linalg.det(u) * np.linalg.det(vt)) or 1.0])
    rot = u @ fix @ vt
    return np.asarray(rot, dtype=np.float64), np.asarray(mu_d - rot @ mu_s, dtype=np.float64)


def absolute_trajectory_error(estimate: ArrayLike, reference: ArrayLike) -> float:
    """RMS position error [m] of ``estimate`` after its rigid alignment to ``reference``.

    Parameters
    ----------
    estimate, reference : array_like, shape (N, 2) or (N, 3)
        Positions (only x, y are used from poses).

    Returns
    -------
    float
        ``sqrt(mean |R e_i + t - r_i|^2)`` with R, t from :func:`align_rigid_2d`.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation.alignment import absolute_trajectory_error
    >>> reference = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    >>> absolute_trajectory_error(reference + [5.0, -1.0], reference)  # a shift costs nothing
    0.0
    >>> round(absolute_trajectory_error([[0.0, 0.1], [1.0, -0.1], [2.0, 0.1]], reference), 4)
    0.0943
    """
    e = np.asarray(estimate, dtype=np.float64)
    r = np.asarray(reference, dtype=np.float64)
    if e.ndim != 2 or e.shape[1] not in (2, 3) or r.shape != e.shape:
        raise InputError(
            f"estimate and reference must be (N, 2) or (N, 3) alike, got {e.shape}, {r.shape}"
        )
    rot, t = align_rigid_2d(e[:, :2], r[:, :2])
    res = e[:, :2] @ rot.T + t - r[:, :2]
    return float(np.sqrt(np.mean(np.sum(res * res, axis=1))))
