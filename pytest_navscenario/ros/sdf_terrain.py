"""Gazebo ``<heightmap>`` collisions as heightfield terrain, for ``navscenario import sdf``.

A Gazebo (classic) heightmap is a square greyscale image stretched over ``<size>`` x by y metres,
centred on the collision's pose plus ``<pos>``; a pixel's height is its value over the image's
brightest value times ``<size>`` z (``HeightmapShape``: scale z = size z / the image's max colour),
the image's top row at +y. The scenario's heightfield maps the file's lowest value to
``min_height`` and its highest to ``max_height`` (scenario/ground/heightmap.py), so the same ground is
``min_height = lowest / highest * size z``, ``max_height = size z``, resting on the pose's z plus
``<pos>`` z. The image is copied beside the seed (``heightmaps/<name>.png``) as it is.

What cannot be carried over is said, never dropped silently: a DEM (GeoTIFF) heightmap, an image
the heightfield reader refuses (colour, too large, not found), a tilted heightmap.
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any, Callable

from ..scenario.ground.heightmap import HeightmapError, read_height_file
from ..scenario.terrain import Heightfield


def heightmap_terrain(path: Path, where: str, shape: ET.Element, pose: tuple[float, ...], name: str,
                      find: Callable[[Path, str], Path | None], floats: Callable[..., list[float]],
                      out: Any) -> None:
    """Add the ``<heightmap>`` ``shape`` of a collision at ``pose`` (x, y, z, roll, pitch, yaw) to
    ``out.terrain`` and its image to ``out.meshes`` (files written beside the seed), or say in
    ``out.warnings`` why not. ``find`` resolves the image's uri as meshes are resolved, ``floats``
    reads an element's numbers as the world importer does (its errors)."""
    tilt = math.radians(1.0)
    if abs(pose[3]) > tilt or abs(pose[4]) > tilt:
        out.warnings.append(f"{where}: heightmap tilted (roll {math.degrees(pose[3]):.1f}, pitch "
                            f"{math.degrees(pose[4]):.1f} deg) cannot be represented (not imported)")
        return
    uri = (shape.findtext("uri") or "").strip()
    if not uri.lower().endswith(".png"):
        out.warnings.append(f"{where}: heightmap {uri or '(no uri)'}: only PNG heightmaps are read (a DEM or "
                            f"another image format is not; convert it to a 16-bit greyscale PNG) (not imported)")
        return
    sx, sy, sz = floats(shape.find("size"), 3, f"{where} heightmap size", path) if shape.find("size") is not None \
        else (1.0, 1.0, 1.0)
    px, py, pz = floats(shape.find("pos"), 3, f"{where} heightmap pos", path) if shape.find("pos") is not None \
        else (0.0, 0.0, 0.0)
    found = find(path, uri)
    if found is None:
        model = uri[len("model://"):].split("/", 1)[0] if uri.startswith("model://") else ""
        hint = (f"; pass --model-path with the folder that holds the model '{model}' (e.g. a Gazebo models "
                f"folder)" if model else "; pass --model-path with the folder that holds it, or copy it there")
        if hasattr(out, "missing_heightmaps"):
            out.missing_heightmaps.append(uri)
        out.warnings.append(f"{where}: heightmap {uri}: no such file beside the world, looked in {path.parent} "
                            f"and its models/ folder{hint} (not imported)")
        return
    try:
        values = read_height_file(found)
    except HeightmapError as exc:
        out.warnings.append(f"{where}: heightmap {uri}: {exc} (not imported)")
        return
    if not (sx > 0 and sy > 0):
        out.warnings.append(f"{where}: heightmap size {sx:g} x {sy:g} m is not positive (not imported)")
        return
    low, high = float(values.min()), float(values.max())
    top = abs(sz)
    floor_ = low / high * top if high > 0 else 0.0
    rel = f"heightmaps/{found.stem}{found.suffix.lower()}"
    data = found.read_bytes()
    if rel in out.meshes and out.meshes[rel] != data:
        rel = f"heightmaps/{found.stem}-{len(out.meshes)}{found.suffix.lower()}"
    out.meshes[rel] = data
    c, s = math.cos(pose[5]), math.sin(pose[5])
    x, y = pose[0] + c * px - s * py, pose[1] + s * px + c * py
    out.names.add(name)
    out.terrain.append(Heightfield(name=name, x=_round(x), y=_round(y), file=rel, length=_round(sx),
                                   width=_round(sy), min_height=_round(floor_), max_height=_round(max(top, floor_)),
                                   yaw=_round(math.degrees(pose[5]), 3), z=_round(pose[2] + pz)))
    rows, cols = values.shape
    out.notes.append(f"{where}: heightmap {uri} ({cols} x {rows} samples, {sx:g} x {sy:g} m, heights "
                     f"{floor_:.3g} to {top:g} m) -> terrain '{name}' ({rel}); Gazebo's own smoothing of "
                     f"the image between samples is not carried over")


def _round(v: float, nd: int = 4) -> float:
    return float(round(float(v), nd)) + 0.0
