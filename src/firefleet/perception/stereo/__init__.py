"""Stereo vision: calibration, rectification, disparity, depth, point clouds, range scans.

The deliverable's pipeline (section 2.7.2): two webcams give an image pair, interest
points are collected in both images and matched, the pair is rectified so that
corresponding points lie on the same row, then depth is recovered for collision
avoidance and SLAM in reduced visibility. The deliverable used MATLAB and SURF; this
module uses OpenCV (SIFT, RANSAC, semi-global matching) and goes on to depth, a 3-D
point cloud and a virtual range scan.

Conventions
-----------
* Images are ``(H, W)`` grey or ``(H, W, 3)`` colour ``uint8`` arrays; colour is in
  OpenCV's BGR order (what ``cv2.imread`` returns). Sizes are ``(width, height)`` in
  pixels, as OpenCV has them.
* Disparity ``d`` is in pixels of the rectified left image: the left pixel ``(x, y)``
  corresponds to the right pixel ``(x - d, y)``. Float32, NaN where there is no value.
* Depth ``Z = f B / (d + d_offs)`` in metres (``f`` focal length [px], ``B`` baseline
  [m], ``d_offs`` the principal points' column difference ``cx_right - cx_left``
  [px], zero after calibrated rectification). Camera frame of the rectified left
  camera: X right, Y down, Z forward [m] (OpenCV's).
* Bearings of the range scan are measured from the optical axis, positive to the
  left (counter-clockwise seen from above, like the robots' heading).

References
----------
.. [1] H. Hirschmueller, "Stereo processing by semiglobal matching and mutual
   information", IEEE TPAMI 30(2), 2008 (SGBM, left-right check, sub-pixel).
.. [2] R. Hartley, "Theory and practice of projective rectification", IJCV 35(2),
   1999 (uncalibrated rectification, ``cv2.stereoRectifyUncalibrated``).
.. [3] Z. Zhang, "A flexible new technique for camera calibration", IEEE TPAMI
   22(11), 2000 (chessboard calibration, ``cv2.calibrateCamera``).
.. [4] D. Scharstein et al., "High-resolution stereo datasets with subpixel-accurate
   ground truth", GCPR 2014 (Middlebury 2014, the bad-2.0 measure).
"""

from firefleet.perception.stereo._calibration import (
    CALIBRATION_FORMAT,
    StereoCalibration,
    calibrate_stereo,
    calibration_yaml,
    find_chessboard,
    load_calibration,
)
from firefleet.perception.stereo._disparity import (
    DisparityResult,
    compute_disparity,
    sgbm_disparity,
    texture,
)
from firefleet.perception.stereo._geometry import (
    RangeScan,
    depth_from_disparity,
    ply_bytes,
    point_cloud,
    range_scan,
)
from firefleet.perception.stereo._images import check_pair, read_image
from firefleet.perception.stereo._pipeline import (
    SATURATED_SHARE,
    StereoRun,
    depth_limits,
    process_pair,
    search_range_for,
)
from firefleet.perception.stereo._rectify import (
    Rectification,
    match_features,
    rectify_calibrated,
    rectify_pair,
    rectify_uncalibrated,
)

__all__ = [
    "CALIBRATION_FORMAT",
    "SATURATED_SHARE",
    "DisparityResult",
    "RangeScan",
    "Rectification",
    "StereoCalibration",
    "StereoRun",
    "calibrate_stereo",
    "calibration_yaml",
    "check_pair",
    "compute_disparity",
    "depth_from_disparity",
    "depth_limits",
    "find_chessboard",
    "load_calibration",
    "match_features",
    "ply_bytes",
    "point_cloud",
    "process_pair",
    "range_scan",
    "read_image",
    "rectify_calibrated",
    "rectify_pair",
    "rectify_uncalibrated",
    "search_range_for",
    "sgbm_disparity",
    "texture",
]
