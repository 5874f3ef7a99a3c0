"""A scenario's static geometry for the run page: paths, obstacles, the formation circle.

Read from the scenario's command by the field names the kinds use (``paths`` of
polynomials, ``obstacles`` of circles, ``alpha_m`` the formation's radius,
``robot_radius_m``), so that a kind with the same fields gets the same drawing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from firefleet.errors import InputError
from firefleet.serve.replay import to_list

__all__ = ["scene_of", "scene_of_name"]


def scene_of(scenario: Any) -> dict[str, Any]:
    """The static geometry of a scenario, for JSON.

    Returns
    -------
    dict
        ``kind``, ``n_robots``, ``robot_radius_m`` (half the axle, or the command's
        ``robot_radius_m``), ``paths`` (lists of [x, y] [m], 200 points each),
        ``obstacles`` ([x, y, radius] [m]), ``formation_radius_m`` (or None).

    Examples
    --------
    >>> from firefleet import load_scenario
    >>> from firefleet.serve.scene import scene_of
    >>> scene = scene_of(load_scenario("path-straight"))
    >>> scene["kind"], len(scene["paths"]), scene["paths"][0][0]
    ('path-following', 1, [0.0, 0.0])
    """
    command = scenario.command
    paths = []
    for path in getattr(command, "paths", ()) or ():
        coefficients = getattr(path, "coefficients", None)
        if coefficients is None:
            continue
        x = np.linspace(path.x_start_m, path.x_end_m, 200)
        y = np.polynomial.polynomial.polyval(x, np.asarray(coefficients, dtype=np.float64))
        paths.append(to_list(np.column_stack([x, y])))
    obstacles = [
        [float(o.x_m), float(o.y_m), float(o.radius_m)]
        for o in getattr(command, "obstacles", ()) or ()
        if hasattr(o, "radius_m")
    ]
    radius = getattr(command, "robot_radius_m", None)
    if radius is None:
        radius = scenario.robot.axle_length_m / 2.0
    alpha = getattr(command, "alpha_m", None)
    return {
        "kind": str(command.kind),
        "title": str(getattr(scenario, "title", "")),
        "n_robots": int(scenario.n_robots),
        "robot_radius_m": float(radius),
        "paths": paths,
        "obstacles": obstacles,
        "formation_radius_m": float(alpha) if alpha is not None else None,
    }


def scene_of_name(name: str) -> dict[str, Any] | None:
    """The geometry of the built-in scenario ``name``; None if there is none by that name."""
    from firefleet.scenarios.registry import builtin_names, load_scenario

    if name not in builtin_names():
        return None
    try:
        return scene_of(load_scenario(name))
    except InputError:
        return None
