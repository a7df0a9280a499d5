"""Mesh obstacles: reading STL (binary or ASCII) and Wavefront OBJ triangle meshes beside a
scenario, and what the rest of the package uses of them: the outline seen from above and the height.

Why no mesh library: the two formats' triangle lists are all that is needed and are read in a few
lines of numpy (trimesh and numpy-stl would be a large dependency for that). Every problem is a
``MeshError`` whose text says what is wrong with the file; the loader adds the scenario file, line
and field.
"""
from __future__ import annotations

import os
import struct
from pathlib import Path

import numpy as np

MAX_MESH_BYTES = 20_000_000      # a mesh file larger than this is refused before it is read
MAX_TRIANGLES = 500_000
MAX_OUTLINE_POINTS = 2_000       # after simplification (1 mm)
OUTLINE_TOLERANCE = 0.001        # m: the outline is simplified by at most this


class MeshError(ValueError):
    """A mesh file cannot be used: the message says why (the loader adds where)."""


def resolve_mesh_path(scenario_dir: Path, relative: str, what: str = "mesh") -> Path:
    """The ``what`` (mesh, heightfield...) file for ``relative`` (a path written in the scenario),
    which must stay inside the scenario's folder (no absolute paths, no ``..`` or links out of it)."""
    if os.path.isabs(relative) or relative.startswith(("/", "\\")):
        raise MeshError(f"{relative!r} is an absolute path; {what} files must lie beside the scenario "
                        f"(write a path relative to {scenario_dir})")
    folder = scenario_dir.resolve()
    path = (folder / relative).resolve()
    if path != folder and folder not in path.parents:
        raise MeshError(f"{relative!r} leaves the scenario's folder {folder}; copy the {what} next to "
                        f"the scenario (or into a folder below it)")
    return path


def read_mesh(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (n, 3), triangles (m, 3) of vertex indices) of an .stl or .obj file."""
    suffix = path.suffix.lower()
    if suffix not in (".stl", ".obj"):
        raise MeshError(f"{path.name}: unknown mesh format {suffix or '(no extension)'}; use .stl or .obj")
    try:
        size = path.stat().st_size
    except FileNotFoundError:
        raise MeshError(f"{path} does not exist") from None
    except OSError as exc:
        raise MeshError(f"{path} cannot be read: {exc.strerror or exc}") from None
    if not path.is_file():
        raise MeshError(f"{path} is not a file")
    if size > MAX_MESH_BYTES:
        raise MeshError(f"{path.name} is {size / 1e6:.1f} MB, more than the limit of "
                        f"{MAX_MESH_BYTES / 1e6:.0f} MB; simplify the mesh (decimate it) first")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise MeshError(f"{path} cannot be read: {exc.strerror or exc}") from None
    verts, tris = _read_stl(data, path.name) if suffix == ".stl" else _read_obj(data, path.name)
    if not len(tris):
        raise MeshError(f"{path.name} has no triangles")
    if len(tris) > MAX_TRIANGLES:
        raise MeshError(f"{path.name} has {len(tris)} triangles, more than the limit of {MAX_TRIANGLES}; "
                        f"simplify the mesh first")
    if not np.isfinite(verts).all():
        raise MeshError(f"{path.name} has non-finite vertex coordinates")
    return verts, tris


def _read_stl(data: bytes, name: str) -> tuple[np.ndarray, np.ndarray]:
    if len(data) >= 84:
        (count,) = struct.unpack_from("<I", data, 80)
        if 84 + 50 * count == len(data):           # binary: 80-byte header, count, 50 bytes each
            rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)),
                                                      ("a", "<u2")]), count=count, offset=84)
            verts = rec["v"].reshape(-1, 3).astype(float)
            return verts, np.arange(len(verts)).reshape(-1, 3)
    text = data.decode("ascii", "replace")
    if not text.lstrip().lower().startswith("solid"):
        raise MeshError(f"{name} is neither a binary STL (its size does not match its triangle count) "
                        f"nor an ASCII STL (it does not start with 'solid')")
    rows = []
    for lineno, line in enumerate(text.splitlines(), 1):
        parts = line.split()
        if parts and parts[0].lower() == "vertex":
            try:
                rows.append([float(v) for v in parts[1:4]])
            except ValueError:
                raise MeshError(f"{name}:{lineno}: a vertex needs three numbers, got {line.strip()!r}") from None
            if len(parts) < 4:
                raise MeshError(f"{name}:{lineno}: a vertex needs three numbers, got {line.strip()!r}")
    if len(rows) % 3:
        raise MeshError(f"{name}: {len(rows)} vertices is not a whole number of triangles")
    verts = np.array(rows, dtype=float).reshape(-1, 3)
    return verts, np.arange(len(verts)).reshape(-1, 3)


def _read_obj(data: bytes, name: str) -> tuple[np.ndarray, np.ndarray]:
    verts, tris = [], []
    for lineno, raw in enumerate(data.decode("utf-8", "replace").splitlines(), 1):
        parts = raw.split()
        if not parts:
            continue
        if parts[0] == "v":
            try:
                verts.append([float(v) for v in parts[1:4]])
            except ValueError:
                raise MeshError(f"{name}:{lineno}: a vertex needs three numbers, got {raw.strip()!r}") from None
            if len(verts[-1]) != 3:
                raise MeshError(f"{name}:{lineno}: a vertex needs three numbers, got {raw.strip()!r}")
        elif parts[0] == "f":
            try:
                idx = [int(p.split("/")[0]) for p in parts[1:]]
            except ValueError:
                raise MeshError(f"{name}:{lineno}: a face lists vertex numbers, got {raw.strip()!r}") from None
            if len(idx) < 3:
                raise MeshError(f"{name}:{lineno}: a face needs three vertices, got {raw.strip()!r}")
            idx = [i - 1 if i > 0 else len(verts) + i for i in idx]     # 1-based, negative = relative
            if any(not 0 <= i < len(verts) for i in idx):
                raise MeshError(f"{name}:{lineno}: a face refers to a vertex that is not defined yet")
            tris.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))   # a fan
    return np.array(verts, dtype=float).reshape(-1, 3), np.array(tris, dtype=int).reshape(-1, 3)


def mesh_outline(verts: np.ndarray, tris: np.ndarray, scale: tuple[float, float, float], name: str
                 ) -> tuple[tuple[tuple[float, float], ...], float]:
    """(the outline of the scaled mesh seen from above, in its own frame, simplified by at most
    ``OUTLINE_TOLERANCE``; its height). Holes in the outline are filled (the robot cannot reach
    them); an outline that falls apart into separate pieces is an error (one mesh file per piece)."""
    import shapely
    from shapely.geometry import Polygon

    v = verts * np.asarray(scale, dtype=float)
    xy = v[:, :2][tris]                                               # (m, 3, 2)
    area = np.abs((xy[:, 1, 0] - xy[:, 0, 0]) * (xy[:, 2, 1] - xy[:, 0, 1])
                  - (xy[:, 2, 0] - xy[:, 0, 0]) * (xy[:, 1, 1] - xy[:, 0, 1]))
    xy = xy[area > 1e-12]
    if not len(xy):
        raise MeshError(f"{name}: seen from above the mesh has no area (it is flat and upright)")
    outline = shapely.union_all(shapely.polygons(xy)).buffer(0)
    if outline.geom_type == "MultiPolygon":
        raise MeshError(f"{name}: seen from above the mesh falls apart into {len(outline.geoms)} separate "
                        f"pieces; put each piece in its own mesh file (one obstacle each)")
    outline = Polygon(outline.exterior).simplify(OUTLINE_TOLERANCE, preserve_topology=True)
    pts = np.asarray(shapely.geometry.polygon.orient(outline, 1.0).exterior.coords)[:-1]
    if len(pts) > MAX_OUTLINE_POINTS:
        raise MeshError(f"{name}: its outline seen from above has {len(pts)} corners after simplifying "
                        f"by {OUTLINE_TOLERANCE * 1000:g} mm, more than {MAX_OUTLINE_POINTS}; simplify the mesh")
    height = float(v[:, 2].max() - v[:, 2].min())
    if height <= 0:
        raise MeshError(f"{name}: the mesh has no height (all its vertices lie at one z)")
    return tuple((round(float(a), 6), round(float(b), 6)) for a, b in pts), round(height, 6)
