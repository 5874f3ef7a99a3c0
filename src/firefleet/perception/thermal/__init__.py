"""Thermal imaging: frames, radiometry, filtering, detection of fires and people, bearing, range.

Deliverable section 2.7.1: a FLIR Lepton (80 x 60 pixels, 51 degree horizontal field
of view, NETD under 50 mK) lets a robot find the seat of a fire and the heat
signature of a victim through smoke and darkness; "ranging" (measuring how far away
they are) is the deliverable's next step, done here from a size prior through the
pinhole model, or from a stereo depth.

Pipeline of :func:`detect` on one frame in degrees Celsius ``(H, W)``:

1. :func:`denoise`: column fixed-pattern offsets removed (:func:`destripe`), then a
   3 x 3 median (dead pixels, temporal noise).
   Pixels at fire temperatures are kept unfiltered (a median would erase a fire that
   fills one or two pixels).
2. Local background: a grey opening along each row with a segment a third of the
   frame wide (an object narrower than that is removed from it; a band of warm wall
   across the view and a step edge between a hot wall and a cool floor are kept).
   Candidate regions are the 8-connected components of pixels at least
   ``warm_contrast_k / 2`` above it that hold a pixel at least ``warm_contrast_k``
   above it (hysteresis), and of pixels at fire temperatures.
3. Each region: area, peak and mean temperature, centroid, bounding box, and the
   temperature of its surround (median of a ring around it).
4. Kind: ``"fire"`` if its peak reaches ``fire_min_c``, or ``fire_contrast_min_c``
   with at least ``fire_contrast_k`` above its surround (a small or distant fire
   that fills only part of a pixel); ``"person"`` if its mean is at skin or clothing
   temperature and its size is plausible for a person at the implied range;
   ``"warm"`` otherwise.
5. Sub-pixel extent from the fraction of each pixel the object fills, computed in
   8-14 um band radiance (what the microbolometer integrates), so partly covered edge
   pixels count for what they hold. Bearing is the mid-azimuth of the object's two
   edges through the camera model (:class:`CameraModel`, pinhole with Brown-Conrady
   distortion); range is ``size / angular size`` for the prior, or the median stereo
   depth in the region, with a 1-sigma uncertainty.

Temperatures are apparent (brightness) temperatures, emissivity 1.
"""

from firefleet.perception.thermal._camera import LEPTON_HFOV_RAD, CameraModel
from firefleet.perception.thermal._detect import (
    Detection,
    DetectionParams,
    FrameDetections,
    detect,
    detections_document,
    range_from_size,
)
from firefleet.perception.thermal._frames import (
    FRAME_SUFFIXES,
    check_frame,
    denoise,
    destripe,
    frame_paths,
    read_frame,
)
from firefleet.perception.thermal._radiometry import (
    KELVIN,
    LinearCalibration,
    band_radiance,
    celsius_to_counts,
    counts_to_celsius,
    radiance_to_celsius,
)

__all__ = [
    "FRAME_SUFFIXES",
    "KELVIN",
    "LEPTON_HFOV_RAD",
    "CameraModel",
    "Detection",
    "DetectionParams",
    "FrameDetections",
    "LinearCalibration",
    "band_radiance",
    "celsius_to_counts",
    "check_frame",
    "counts_to_celsius",
    "denoise",
    "destripe",
    "detect",
    "detections_document",
    "frame_paths",
    "radiance_to_celsius",
    "range_from_size",
    "read_frame",
]
