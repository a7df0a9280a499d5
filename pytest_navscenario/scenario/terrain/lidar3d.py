"""The 3D lidar (``robot.lidar3d``): its declaration and YAML keys."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..keys import SCENARIO_LIMITS as _LIMITS
from ..keys import Integer, Number, Rule, section


@dataclass(frozen=True)
class Lidar3D:
    """A spinning multi-ring lidar (defaults like a 16-ring unit): ``rings`` rings spread evenly
    from ``fov_low`` to ``fov_high`` degrees of elevation, ``beams`` beams per ring over 360
    degrees, mounted at (``mount_x``, ``mount_y``, ``mount_z``) on the robot's base, tilted by
    ``mount_pitch`` degrees (positive: looking down). Its points (N x 3, sensor frame) are part of
    the observation. The noise, dropout and spurious-return models are the 2D lidar's."""
    rings: int = 16
    beams: int = 360
    fov_low: float = -15.0               # degrees
    fov_high: float = 15.0               # degrees
    range_min: float = 0.3               # m
    range_max: float = 30.0              # m
    mount_x: float = 0.0                 # m, robot frame
    mount_y: float = 0.0
    mount_z: float = 0.5                 # m above the base's origin
    mount_pitch: float = 0.0             # degrees, positive looks down
    noise_sigma: float = 0.0
    dropout: float = 0.0
    noise_per_metre: float = 0.0
    dropout_at_max: float | None = None
    spurious: float = 0.0


def _lidar3d_ranges(values: Any, given: Any) -> tuple[str, str, str] | None:
    if values["range_max"] <= values["range_min"]:
        return ("range_max", f"range_max ({values['range_max']!r} m) must be greater than range_min "
                f"({values['range_min']!r} m)", "raise range_max")
    if values["fov_high"] < values["fov_low"]:
        return ("fov_high", f"fov_high ({values['fov_high']!r} deg) must not be below fov_low "
                f"({values['fov_low']!r} deg)", "swap them")
    return None


LIDAR3D = section(Lidar3D, "robot.lidar3d", "a spinning multi-ring lidar whose points are part of the "
                  "observation", [
    Integer("rings", "", "rings, spread evenly from fov_low to fov_high", ge=1, le=256),
    Integer("beams", "", "beams per ring over 360 degrees", ge=1, le=int(_LIMITS["max_lidar_beams"])),
    Number("fov_low", "deg", "the lowest ring's elevation", ge=-90.0, le=90.0),
    Number("fov_high", "deg", "the highest ring's elevation", ge=-90.0, le=90.0),
    Number("range_min", "m", "shortest range it reads", ge=0),
    Number("range_max", "m", "longest range", gt=0),
    Number("mount_x", "m", "mounting position on the base, forward"),
    Number("mount_y", "m", "mounting position on the base, left"),
    Number("mount_z", "m", "mounting height above the base's origin"),
    Number("mount_pitch", "deg", "mounting tilt, positive looks down", ge=-90.0, le=90.0),
    Number("noise_sigma", "m", "Gaussian noise on each range", ge=0),
    Number("dropout", "", "probability that a beam reads as no return", ge=0, le=1.0),
    Number("noise_per_metre", "m/m", "the noise's sigma grows by this per metre of range", ge=0, le=1.0),
    Number("dropout_at_max", "", "dropout probability at range_max (none: dropout at every range)", ge=0,
           le=1.0, nullable=True),
    Number("spurious", "", "probability of a spurious return short of the true one", ge=0, le=1.0),
], what="the 3D lidar settings (a mapping)", rules=[
    Rule("range_max is greater than range_min, fov_high not below fov_low", _lidar3d_ranges),
    Rule(f"rings x beams at most {int(_LIMITS['max_lidar3d_rays'])} rays a scan, and its ranges recorded over "
         f"the episode (scans x rings x beams x 4 bytes) at most {int(_LIMITS['max_lidar3d_record_bytes']) >> 30} "
         f"GiB", None)])
