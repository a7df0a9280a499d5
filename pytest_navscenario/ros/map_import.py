"""``navscenario from-map map.yaml --start x,y,yaw --goal x,y,yaw -o seed.yaml``.

A map_server occupancy grid (the YAML with ``image``, ``resolution``, ``origin``,
``occupied_thresh``, ``free_thresh``, ``negate`` and the PGM beside it) becomes box obstacles:
occupied cells (occupancy probability above ``occupied_thresh``, computed as map_server does:
``(255 - v) / 255``, or ``v / 255`` with ``negate: 1``; in ``mode: raw`` the pixel value is the
occupancy in percent) are merged into few boxes by greedy
maximal rectangles (grow right, then down), so a 200 x 200 map of walls gives tens of boxes,
not thousands. The origin's yaw rotates the map about the origin.
"""
from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core.errors import NavScenarioError
from ..scenario.model import BoxObstacle, Mission, Scenario
from .robot_options import add_robot_arguments, mission_timeout, robot_from_args
from .world_import import parse_pose, write_seed


class MapImportError(NavScenarioError):
    """A map_server map cannot be read: YAML fields, image missing or unreadable."""


@dataclass(frozen=True)
class MapInfo:
    image: Path
    resolution: float
    origin: tuple[float, float, float]   # x, y (m), yaw (rad)
    occupied_thresh: float
    negate: bool
    mode: str = "trinary"


def read_map_yaml(path: str | Path) -> MapInfo:
    import yaml

    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise MapImportError(f"{path}: no such map YAML file") from None
    except yaml.YAMLError as exc:
        raise MapImportError(f"{path}: not valid YAML ({getattr(exc, 'problem', exc)})") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise MapImportError(f"{path}: cannot read: {exc}") from None
    if not isinstance(data, dict):
        raise MapImportError(f"{path}: not a map_server map YAML (expected a mapping with image, resolution, origin)")
    missing = [k for k in ("image", "resolution", "origin") if k not in data]
    if missing:
        raise MapImportError(f"{path}: map YAML lacks {', '.join(missing)} (map_server needs image, resolution, origin)")
    image = str(data["image"])
    if Path(image).is_absolute():
        raise MapImportError(f"{path}: image: {image!r} is an absolute path; make it relative to the YAML "
                             f"(e.g. image: {Path(image).name}) so the map can be moved")
    img = path.parent / image
    if not img.is_file():
        raise MapImportError(f"{path}: image: {image!r} not found (looked for {img})")

    def num(key: str, default: float | None = None) -> float:
        v = data.get(key, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise MapImportError(f"{path}: {key}: expected a number, got {v!r}")
        return float(v)

    res = num("resolution")
    if res <= 0:
        raise MapImportError(f"{path}: resolution: must be > 0 m/cell, got {res}")
    origin = data["origin"]
    if not isinstance(origin, list) or len(origin) not in (2, 3) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in origin):
        raise MapImportError(f"{path}: origin: expected [x, y, yaw] (m, m, rad), got {origin!r}")
    occ = num("occupied_thresh", 0.65)
    negate = data.get("negate", 0)
    if negate not in (0, 1, True, False):
        raise MapImportError(f"{path}: negate: expected 0 or 1, got {negate!r}")
    if not 0 <= occ <= 1:
        raise MapImportError(f"{path}: occupied_thresh: expected a probability in [0, 1], got {occ}")
    mode = str(data.get("mode", "trinary"))
    if mode not in ("trinary", "scale", "raw"):
        raise MapImportError(f"{path}: mode: expected trinary, scale or raw, got {mode!r}")
    o = [float(v) for v in origin] + [0.0] * (3 - len(origin))
    return MapInfo(image=img, resolution=res, origin=(o[0], o[1], o[2]), occupied_thresh=occ,
                   negate=bool(negate), mode=mode)


def read_pgm(path: Path) -> np.ndarray:
    """A PGM image (binary P5 or ASCII P2, 8 or 16 bit) as an (h, w) array scaled to 0..255."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise MapImportError(f"{path}: cannot read the map image: {exc}") from None
    magic = raw[:2]
    if magic not in (b"P5", b"P2"):
        raise MapImportError(f"{path}: not a PGM image (magic {magic!r}); convert the map image to PGM")
    # header: magic, width, height, maxval, separated by whitespace, '#' comments allowed
    fields, pos = [], 2
    while len(fields) < 3:
        while pos < len(raw) and raw[pos:pos + 1].isspace():
            pos += 1
        if raw[pos:pos + 1] == b"#":
            while pos < len(raw) and raw[pos:pos + 1] not in (b"\n", b"\r"):
                pos += 1
            continue
        start = pos
        while pos < len(raw) and not raw[pos:pos + 1].isspace():
            pos += 1
        if start == pos:
            raise MapImportError(f"{path}: PGM header is truncated")
        try:
            fields.append(int(raw[start:pos]))
        except ValueError:
            raise MapImportError(f"{path}: PGM header has {raw[start:pos]!r} where a number belongs") from None
    w, h, maxval = fields
    if w <= 0 or h <= 0 or not 0 < maxval < 65536:
        raise MapImportError(f"{path}: PGM header has width {w}, height {h}, maxval {maxval}")
    if magic == b"P5":
        body = raw[pos + 1:]
        dtype = np.dtype(">u2") if maxval > 255 else np.dtype(np.uint8)
        need = w * h * dtype.itemsize
        if len(body) < need:
            raise MapImportError(f"{path}: PGM image is truncated ({len(body)} of {need} bytes)")
        img = np.frombuffer(body[:need], dtype=dtype).reshape(h, w).astype(float)
    else:
        vals = raw[pos:].split()
        if len(vals) < w * h:
            raise MapImportError(f"{path}: PGM image is truncated ({len(vals)} of {w * h} values)")
        img = np.array([int(v) for v in vals[:w * h]], dtype=float).reshape(h, w)
    return img * (255.0 / maxval)


def occupied_mask(info: MapInfo) -> np.ndarray:
    """Boolean (h, w) grid, row 0 at the top of the image, True where occupied."""
    img = read_pgm(info.image)
    if info.mode == "raw":  # pixel = occupancy in percent, 255 (or > 100) = unknown
        return (img <= 100.0) & (img / 100.0 > info.occupied_thresh)
    p = img / 255.0 if info.negate else (255.0 - img) / 255.0
    return p > info.occupied_thresh


def merge_rectangles(mask: np.ndarray) -> list[tuple[int, int, int, int]]:
    """Greedy maximal rectangles covering ``mask`` exactly: (row, col, rows, cols) each.

    Scan cells in row-major order; from the first uncovered occupied cell grow right as far
    as possible, then down while the whole span stays occupied and uncovered.
    """
    free = mask.copy()
    h, w = free.shape
    rects = []
    for r in range(h):
        row = free[r]
        c = 0
        while c < w:
            if not row[c]:
                c += 1
                continue
            c2 = c
            while c2 < w and row[c2]:
                c2 += 1
            r2 = r + 1
            while r2 < h and free[r2, c:c2].all():
                r2 += 1
            free[r:r2, c:c2] = False
            rects.append((r, c, r2 - r, c2 - c))
            c = c2
    return rects


def map_obstacles(path: str | Path) -> tuple[list[BoxObstacle], MapInfo, int]:
    """Boxes for the occupied cells of a map_server map; also its info and the occupied cell count."""
    info = read_map_yaml(path)
    mask = occupied_mask(info)
    h = mask.shape[0]
    res = info.resolution
    ox, oy, oyaw = info.origin
    c, s = math.cos(oyaw), math.sin(oyaw)
    boxes = []
    for i, (r, col, nr, nc) in enumerate(merge_rectangles(mask), 1):
        # image row 0 is the top: map y grows upwards from the bottom row
        lx = (col + nc / 2.0) * res
        ly = (h - r - nr / 2.0) * res
        x, y = ox + c * lx - s * ly, oy + s * lx + c * ly
        boxes.append(BoxObstacle(name=f"cells{i}", x=round(x, 4) + 0.0, y=round(y, 4) + 0.0,
                                 length=round(nc * res, 4), width=round(nr * res, 4),
                                 yaw=round(math.degrees(oyaw), 3) + 0.0))
    return boxes, info, int(mask.sum())


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("map", metavar="MAP.yaml", help="map_server YAML (image, resolution, origin, thresholds, negate)")
    p.add_argument("--start", required=True, metavar="X,Y,YAW", help="start pose x,y,yaw (m, m, degrees) in the map frame")
    p.add_argument("--goal", required=True, metavar="X,Y,YAW", help="goal pose x,y,yaw (m, m, degrees) in the map frame")
    p.add_argument("-o", "--output", required=True, metavar="OUT.yaml", help="scenario YAML to write")
    add_robot_arguments(p)
    p.add_argument("--name", default="", metavar="TEXT", help="scenario name (default: the output file's stem)")
    p.add_argument("--force", action="store_true", help="overwrite an existing output file")


def run(args: argparse.Namespace) -> int:
    import dataclasses

    start, goal = parse_pose(args.start, "--start"), parse_pose(args.goal, "--goal")
    robot, robot_note = robot_from_args(args)
    boxes, info, cells = map_obstacles(args.map)
    scenario = Scenario(mission=Mission(start=start, goal=goal), obstacles=tuple(boxes), robot=robot, name=args.name,
                        description=f"Imported from map {Path(args.map).name} ({info.resolution} m/cell).")
    timeout, timeout_note = mission_timeout(scenario, args.timeout)
    scenario = dataclasses.replace(scenario, mission=dataclasses.replace(scenario.mission, timeout=timeout))
    write_seed(scenario, args.output, force=args.force)
    print(f"navscenario from-map: {robot_note}")
    print(f"navscenario from-map: {timeout_note}")
    print(f"navscenario from-map: {cells} occupied cells -> {len(boxes)} boxes -> wrote {args.output}")
    return 0
