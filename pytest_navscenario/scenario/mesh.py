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

from ..core.files import data_file_size

# Limits that hold an item's own work (load, outline, convex parts, model, first ticks) to about one
# second (benchmarks/bench_shapes.py): the outline's union costs ~15 us per triangle seen from above.
MAX_MESH_BYTES = 20_000_000      # a mesh file larger than this is refused before it is read
MAX_TRIANGLES = 30_000           # counted before (binary STL: its header) or while parsing, never after
MAX_VERTICES = 3 * MAX_TRIANGLES  # OBJ vertex lines (a file may list more vertices than its faces use)
MAX_OUTLINE_POINTS = 1_000       # after simplification (1 mm); = the polygon limit of the loader
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
    size = data_file_size(path, MeshError, MAX_MESH_BYTES, "simplify the mesh (decimate it) first")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise MeshError(f"{path} cannot be read: {exc.strerror or exc}") from None
    verts, tris = _read_stl(data, path.name) if suffix == ".stl" else _read_obj(data, path.name)
    if not len(tris):
        raise MeshError(f"{path.name} has no triangles")
    if not np.isfinite(verts).all():
        raise MeshError(f"{path.name} has non-finite vertex coordinates")
    return verts, tris


def _too_many(name: str, detail: str) -> MeshError:
    return MeshError(f"{name} has more than the limit of {MAX_TRIANGLES} triangles ({detail}); simplify "
                     f"the mesh (decimate it) first")


_BINARY_STL = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])


def _lines(data: bytes):
    """(line number, line) of a text file, lazily (a list of every line of a 20 MB file would
    cost ~100 MB); LF, CR LF and CR end a line."""
    import io
    if b"\r" in data:
        data = data.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    return enumerate(io.BytesIO(data), 1)


def _first_word(raw: bytes) -> bytes:
    parts = raw.split(None, 1)
    return parts[0] if parts else b""


def _read_stl(data: bytes, name: str) -> tuple[np.ndarray, np.ndarray]:
    """A binary STL (80-byte header, a triangle count, 50 bytes per triangle) or an ASCII one
    (``solid`` ... ``vertex x y z`` ...). A binary file's header may itself start with "solid": a
    size that matches the count, or NUL bytes (no text file has them), tell the two apart."""
    count = struct.unpack_from("<I", data, 80)[0] if len(data) >= 84 else None
    if count is not None and 84 + 50 * count == len(data):
        if count > MAX_TRIANGLES:
            raise _too_many(name, f"its header declares {count}")
        rec = np.frombuffer(data, dtype=_BINARY_STL, count=count, offset=84)
        verts = rec["v"].reshape(-1, 3).astype(float)
        return verts, np.arange(len(verts)).reshape(-1, 3)
    lowered = data.lower()
    vertices = lowered.count(b"vertex")
    declared = (f"read as a binary STL, its header declares {count} triangles ({84 + 50 * count} bytes) "
                f"but the file has {len(data)} bytes" if count is not None else
                f"it is shorter ({len(data)} bytes) than a binary STL's 84-byte header")
    if b"\0" in data and not vertices:              # binary, cut short or damaged
        cut = count is not None and 84 + 50 * count > len(data)
        raise MeshError(f"{name} is a {'truncated' if cut else 'damaged'} binary STL: {declared}"
                        + (" (export or copy it again)" if cut else ""))
    if lowered.lstrip()[:5] != b"solid":
        raise MeshError(f"{name} is neither a binary STL ({declared}) nor an ASCII STL (it does not "
                        f"start with 'solid')")
    if vertices > 3 * MAX_TRIANGLES:                 # counted before parsing
        raise _too_many(name, f"{vertices} 'vertex' lines: {vertices // 3} triangles")
    rows = []
    for lineno, raw in _lines(data):
        if _first_word(raw).lower() == b"vertex":
            parts = raw.split()
            try:
                rows.append([float(v) for v in parts[1:4]])
            except ValueError:
                raise MeshError(f"{name}:{lineno}: a vertex needs three numbers, got {_show(raw)}") from None
            if len(parts) < 4:
                raise MeshError(f"{name}:{lineno}: a vertex needs three numbers, got {_show(raw)}")
    if not rows and count is not None:
        raise MeshError(f"{name} has no triangles: read as an ASCII STL (it starts with 'solid') it has no "
                        f"'vertex' lines; {declared} (a truncated binary STL?)")
    if len(rows) % 3:
        raise MeshError(f"{name}: {len(rows)} vertices is not a whole number of triangles")
    verts = np.array(rows, dtype=float).reshape(-1, 3)
    return verts, np.arange(len(verts)).reshape(-1, 3)


def _read_obj(data: bytes, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (``v x y z``) and faces (``f i j k ...``, 1-based or negative, ``i/t/n`` forms; a
    face of n corners is a fan of n - 2 triangles) of a Wavefront OBJ file, every other line
    skipped. Read line by line, stopping as soon as a limit is passed, so that a huge file costs
    no more than a mesh at the limit: a long face line's corners are counted before it is split."""
    import itertools
    import re

    verts: list[list[float]] = []
    tris: list[list[int]] = []
    token = re.compile(rb"\S+")
    for lineno, raw in _lines(data):
        word = _first_word(raw) if len(raw) < 4096 else raw.lstrip()[:2].rstrip()
        if word == b"v":
            if len(verts) >= MAX_VERTICES:
                raise MeshError(f"{name}:{lineno}: more than {MAX_VERTICES} vertices (three per triangle "
                                f"of the {MAX_TRIANGLES}-triangle limit); simplify the mesh (decimate it) first")
            parts = raw.split()
            try:
                verts.append([float(v) for v in parts[1:4]])
            except ValueError:
                raise MeshError(f"{name}:{lineno}: a vertex needs three numbers, got {_show(raw)}") from None
            if len(verts[-1]) != 3:
                raise MeshError(f"{name}:{lineno}: a vertex needs three numbers, got {_show(raw)}")
        elif word == b"f":
            room = MAX_TRIANGLES - len(tris) + 2      # corners this face may have
            if len(raw) > 4096:                       # perhaps a huge fan: count corners first
                corners = sum(1 for _ in itertools.islice(token.finditer(raw), room + 2)) - 1
                if corners > room:
                    raise _too_many(name, f"line {lineno} is a face of more than {room} corners")
            try:
                idx = [int(p.split(b"/")[0]) for p in raw.split()[1:]]
            except ValueError:
                raise MeshError(f"{name}:{lineno}: a face lists vertex numbers, got {_show(raw)}") from None
            if len(idx) < 3:
                raise MeshError(f"{name}:{lineno}: a face needs three vertices, got {_show(raw)}")
            if len(tris) + len(idx) - 2 > MAX_TRIANGLES:
                raise _too_many(name, f"counted up to line {lineno}")
            idx = [i - 1 if i > 0 else len(verts) + i for i in idx]     # 1-based, negative = relative
            if any(not 0 <= i < len(verts) for i in idx):
                raise MeshError(f"{name}:{lineno}: a face refers to a vertex that is not defined yet")
            tris.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))   # a fan
    return np.array(verts, dtype=float).reshape(-1, 3), np.array(tris, dtype=int).reshape(-1, 3)


def _show(raw: bytes) -> str:
    """A line of a mesh file as the error shows it (at most 80 characters)."""
    text = raw.decode("utf-8", "replace").strip()
    return repr(text if len(text) <= 80 else text[:77] + "...")


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
