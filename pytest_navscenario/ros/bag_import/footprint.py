"""The robot's footprint from the bag: the collision geometry of the base link in the URDF on
``/robot_description``, else a Nav2 costmap footprint (``published_footprint`` topic or a
``footprint`` / ``robot_radius`` parameter event), else a default circle; the note says which.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET

from ...scenario.model import Footprint
from .reading import BagData

DEFAULT_RADIUS = 0.15


def footprint_from_bag(data: BagData, radius: float | None) -> tuple[Footprint, str, list[str]]:
    """(footprint, where it came from, warnings); ``radius`` (--robot-radius) wins when given."""
    if radius is not None:
        return Footprint(shape="circle", radius=radius), f"a circle of radius {radius} m from --robot-radius", []
    warnings: list[str] = []
    if data.description:
        found, why = urdf_footprint(data.description, data.base_frame)
        if found is not None:
            return found, f"the URDF on /robot_description ({why})", warnings
        warnings.append(f"/robot_description: {why}")
    for source, kind, value in data.footprints:
        fp = _nav2(kind, value)
        if fp is not None:
            return fp, f"the Nav2 footprint ({source})", warnings
    return (Footprint(shape="circle", radius=DEFAULT_RADIUS),
            f"the default circle of radius {DEFAULT_RADIUS} m (no /robot_description or Nav2 footprint in the bag; "
            f"set --robot-radius)", warnings)


def inner_radius(fp: Footprint) -> float:
    """Half the footprint's narrowest width: what must stay free around a pose the robot drove."""
    return fp.radius if fp.shape == "circle" else min(fp.length, fp.width) / 2


def _nav2(kind: str, value) -> Footprint | None:
    if kind == "radius":
        return Footprint(shape="circle", radius=round(float(value), 3))
    xs, ys = [p[0] for p in value], [p[1] for p in value]
    return Footprint(shape="box", length=round(max(xs) - min(xs), 3), width=round(max(ys) - min(ys), 3))


def urdf_footprint(text: str, base_frame: str) -> tuple[Footprint | None, str]:
    """The footprint of the first link with collision geometry reached from ``base_frame`` over
    fixed joints (base_footprint -> base_link), and what was used or why nothing could be."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        return None, f"not well-formed XML ({exc})"
    links = {link.get("name"): link for link in root.iter("link")}
    fixed = [(j.find("parent").get("link"), j.find("child").get("link")) for j in root.iter("joint")
             if j.get("type") == "fixed" and j.find("parent") is not None and j.find("child") is not None]
    start = base_frame if base_frame in links else ("base_link" if "base_link" in links else None)
    if start is None:
        return None, f"no link {base_frame!r} (links: {', '.join(sorted(links)) or 'none'})"
    seen, queue = set(), [start]
    while queue:
        name = queue.pop(0)
        if name in seen:
            continue
        seen.add(name)
        shapes = [g for c in links.get(name, ET.Element("link")).findall("collision") for g in c.findall("geometry/*")]
        if shapes:
            return _from_shapes(name, shapes)
        queue += [c for p, c in fixed if p == name] + [p for p, c in fixed if c == name]
    return None, f"no collision geometry on {start} or the links fixed to it"


def _from_shapes(link: str, shapes: list[ET.Element]) -> tuple[Footprint | None, str]:
    first = shapes[0]
    if first.tag == "box":
        lx, ly, _ = (float(v) for v in first.get("size", "0 0 0").split())
        return Footprint(shape="box", length=round(lx, 3), width=round(ly, 3)), f"{link}: box {lx} x {ly} m"
    if first.tag in ("cylinder", "sphere"):
        r = float(first.get("radius", "0"))
        return Footprint(shape="circle", radius=round(r, 3)), f"{link}: {first.tag} of radius {r} m"
    return None, f"{link}: collision geometry {first.tag!r} (a mesh has no size here) is not read"
