"""A run as an MCAP log that opens in Foxglove as it is (``firefleet run --mcap``).

:func:`mcap_bytes` writes a run's arrays with the Foxglove SDK's schemas (protobuf),
stamped with the simulated time (t = 0 is the epoch); :func:`read_mcap` reads one back
into ``result.npz``'s arrays, for ``firefleet serve`` to replay it.

=============================  =================  ====================================
topic                          schema             what
=============================  =================  ====================================
``/tf``                        FrameTransforms    ``world`` -> ``robot_<i>`` each sample
``/robot_<i>/pose``            PoseInFrame        true pose of robot i (1-based)
``/robot_<i>/<name>``          PoseInFrame        an estimated pose (``odometry_pose``)
``/robot_<i>/thermal``         RawImage (32FC1)   the thermal frame [deg C]
``/robot_<i>/<ranges>``        LaserScan          ``lidar_range_m``, ``ultrasonic_range_m``
``/points/<name>``             PosesInFrame       desired points, leader, formation slots
``/map``                       Grid (uint8)       the occupancy map (0..100), once
``/scene``                     SceneUpdate        paths, obstacles, once
``/signals``                   JSON               every other array, one message a sample
``/events``                    Log                the run, then each claim and its result
=============================  =================  ====================================
"""

from firefleet.mcap_log._reader import read_mcap
from firefleet.mcap_log._writer import mcap_bytes

__all__ = ["mcap_bytes", "read_mcap"]
