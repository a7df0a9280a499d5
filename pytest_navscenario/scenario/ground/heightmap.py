"""Height grids of terrain patches: a heightfield file beside the scenario (a greyscale PNG, 8 or 16
bit, or a NumPy ``.npy`` array) or rough ground drawn from a seed, as a grid of heights in metres.

A grid is ``HeightGrid(heights, cell)``: ``heights[r, c]`` is the ground ``heights`` metres above the
element's base ``z`` at the sample (x, y) = (-length/2 + c * dx, -width/2 + r * dy) of the element's
own frame (centred on its (x, y), +x along its yaw), ``cell`` = (dx, dy). Row 0 is the element's -y
edge: a file is read as a map seen from above (its first row, the image's top, is the +y edge;
MuJoCo reads PNG heightfields the same way). Between samples the ground is MuJoCo's: each cell is two
triangles split along its diagonal from (c, r) to (c + 1, r + 1) (``HeightGrid.sample``).

Values: the lowest value in a file is ``min_height``, the highest ``max_height``, linearly between
(MuJoCo's rule for heightfields; a PNG with no black pixel still starts at ``min_height``). Rough
ground has bumps up to ``amplitude`` spaced about ``wavelength`` apart (Gaussian-filtered noise
from the seed: one peak per wavelength squared, measured), tapered to its base over one wavelength
at its border, so its edge is not a step.

Grids are cached per process (a search re-runs the same terrain): reading, generating and checking
happen once. Every problem is a ``HeightmapError`` naming the file and saying why; ``field`` is the
element's key at fault ("file", "length"...) so that the loader can add the scenario's file and line.
"""
from __future__ import annotations

import hashlib
import math
from collections import OrderedDict
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ...core.files import data_file_size
from ..mesh import MeshError, resolve_mesh_path

MAX_HEIGHTFIELD_BYTES = 64_000_000   # a file larger than this is refused before it is read
MAX_GRID_SIDE = 1024                 # samples along a side (a 1024 x 1024 grid is 8 MB of float64)
MAX_CELL_ASPECT = 4.0                # a cell stretched more than this one way is a size mismatch
ROUGH_SAMPLES_PER_WAVELENGTH = 8     # rough ground's grid spacing: wavelength / 8
ROUGH_SIGMA = 1 / 4.5                # the noise filter's sigma, in wavelengths: peaks one wavelength apart
GRID_CACHE_SIZE = 16
HEIGHTFIELD_SUFFIXES = (".png", ".npy")


class HeightmapError(ValueError):
    """A height grid cannot be made: the message says why, ``field`` which key of the element."""

    def __init__(self, message: str, field: str = "file"):
        super().__init__(message)
        self.field = field


class HeightGrid(NamedTuple):
    """Heights (rows, cols; metres above the element's base, read-only) and the sample spacing
    (dx, dy) in metres; row 0 is the element's -y edge, column 0 its -x edge."""
    heights: np.ndarray
    cell: tuple[float, float]

    @property
    def extent(self) -> tuple[float, float]:
        """(length, width) covered by the samples, in metres."""
        rows, cols = self.heights.shape
        return (cols - 1) * self.cell[0], (rows - 1) * self.cell[1]

    def sample(self, x: Any, y: Any) -> np.ndarray:
        """Ground heights at points (x, y) of the element's own frame (centred), on MuJoCo's
        triangles; NaN outside the grid."""
        h = self.heights
        rows, cols = h.shape
        length, width = self.extent
        u = (np.asarray(x, dtype=float) + length / 2.0) / self.cell[0]
        v = (np.asarray(y, dtype=float) + width / 2.0) / self.cell[1]
        inside = (u >= 0) & (u <= cols - 1) & (v >= 0) & (v <= rows - 1)
        c = np.clip(np.floor(u), 0, cols - 2).astype(np.intp)
        r = np.clip(np.floor(v), 0, rows - 2).astype(np.intp)
        fx, fy = np.clip(u - c, 0.0, 1.0), np.clip(v - r, 0.0, 1.0)
        h00, h11 = h[r, c], h[r + 1, c + 1]
        lower = fx >= fy              # the triangle (c, r), (c + 1, r), (c + 1, r + 1)
        out = np.where(lower, h00 + (h[r, c + 1] - h00) * fx + (h11 - h[r, c + 1]) * fy,
                       h00 + (h11 - h[r + 1, c]) * fx + (h[r + 1, c] - h00) * fy)
        return np.where(inside, out, np.nan)


_CACHE: OrderedDict[Any, Any] = OrderedDict()


def _cached(key: Any, make):
    value = _CACHE.get(key)
    if value is None:
        value = make()
        _CACHE[key] = value
        if len(_CACHE) > GRID_CACHE_SIZE:
            _CACHE.popitem(last=False)
    else:
        _CACHE.move_to_end(key)
    return value


def clear_grid_cache() -> None:
    _CACHE.clear()


# ---------------------------------------------------------------- heightfield files


def resolve_heightfield_path(scenario_dir: Path, relative: str) -> Path:
    """The heightfield file for ``relative`` (as written in the scenario): inside the scenario's
    folder, like mesh files (no absolute paths, no ``..`` or links out of it)."""
    try:
        return resolve_mesh_path(scenario_dir, relative, what="heightfield")
    except MeshError as exc:
        raise HeightmapError(str(exc)) from None


def read_height_file(path: Path) -> np.ndarray:
    """The raw values (rows, cols) of a greyscale PNG or a 2-D ``.npy`` array, as float64, row 0
    the file's first row (the +y edge)."""
    suffix = path.suffix.lower()
    if suffix not in HEIGHTFIELD_SUFFIXES:
        raise HeightmapError(f"{path.name}: unknown heightfield format {suffix or '(no extension)'}; "
                             f"use a greyscale .png (8 or 16 bit) or a NumPy .npy array")
    size = data_file_size(path, HeightmapError, MAX_HEIGHTFIELD_BYTES, "downsample it first")
    values = _read_png(path) if suffix == ".png" else _read_npy(path, size)
    rows, cols = values.shape
    _check_sides(path, rows, cols)
    if rows < 2 or cols < 2:
        raise HeightmapError(f"{path.name} is {cols} x {rows} samples; a heightfield needs at least "
                             f"2 x 2 (its corners)")
    bad = ~np.isfinite(values)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise HeightmapError(f"{path.name} has {int(bad.sum())} value(s) that are not finite numbers "
                             f"(NaN or infinite), the first at row {r}, column {c}; fill the holes "
                             f"(e.g. with the neighbouring heights) before using it")
    return values


def _check_sides(path: Path, rows: int, cols: int) -> None:
    if rows > MAX_GRID_SIDE or cols > MAX_GRID_SIDE:
        raise HeightmapError(f"{path.name} is {cols} x {rows} samples, more than the limit of "
                             f"{MAX_GRID_SIDE} a side; downsample it (a finer grid also slows every "
                             f"lidar scan over it)")


def _read_png(path: Path) -> np.ndarray:
    """A PNG's grey values; its size is checked from its header before a pixel is decoded (so a
    small file declaring a huge image costs nothing), without touching Pillow's own limit, which a
    planner in the same process may rely on."""
    import warnings

    from PIL import Image, UnidentifiedImageError

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)   # refused below by size
            image = Image.open(path)
        with image:
            cols, rows = image.size
            _check_sides(path, rows, cols)
            image.load()
            mode, bands = image.mode, image.getbands()
            if mode in ("L", "I", "I;16", "I;16B", "I;16L", "I;16N", "F"):
                values = np.asarray(image)
            elif mode in ("LA", "La", "RGB", "RGBA", "P", "PA", "1"):
                rgb = np.asarray(image.convert("RGB"))
                if not ((rgb[..., 0] == rgb[..., 1]) & (rgb[..., 1] == rgb[..., 2])).all():
                    raise HeightmapError(f"{path.name} is a colour image ({mode}); a heightfield is "
                                         f"greyscale: save it as 8 or 16-bit grey")
                values = rgb[..., 0]
            else:
                raise HeightmapError(f"{path.name}: image mode {mode} ({', '.join(bands)}) is not a "
                                     f"greyscale image; save it as 8 or 16-bit grey")
    except HeightmapError:
        raise
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as exc:
        raise HeightmapError(f"{path.name} cannot be read as a PNG image: {exc}") from None
    except Image.DecompressionBombError:
        raise HeightmapError(f"{path.name} is too large an image; downsample it to at most "
                             f"{MAX_GRID_SIDE} x {MAX_GRID_SIDE}") from None
    if values.ndim != 2:
        raise HeightmapError(f"{path.name} is not a single-channel image (shape {values.shape})")
    return values.astype(float)


def _read_npy(path: Path, size: int) -> np.ndarray:
    """A 2-D numeric ``.npy`` array. Its header (shape, type) is checked before its data is read:
    numpy allocates what the header promises, so a 200-byte file promising 60000 x 60000 would
    ask for 27 GB."""
    from numpy.lib import format as npy

    try:
        with open(path, "rb") as fp:
            if fp.read(1) == b"\x80":
                raise ValueError("it is a Python pickle (never loaded: it could run code); save the array with "
                                 "numpy.save")
            fp.seek(0)
            version = npy.read_magic(fp)
            read_header = {(1, 0): npy.read_array_header_1_0, (2, 0): npy.read_array_header_2_0}.get(version)
            if read_header is None:
                raise ValueError(f"unsupported .npy format version {version[0]}.{version[1]}")
            shape, _, dtype = read_header(fp)
            data_bytes = size - fp.tell()
    except (ValueError, OSError, EOFError) as exc:
        raise HeightmapError(f"{path.name} cannot be read as a NumPy .npy array: {exc}") from None
    if dtype.kind not in "iuf":
        raise HeightmapError(f"{path.name} holds {dtype} values; a heightfield array holds numbers "
                             f"(integers or floats)")
    if len(shape) != 2:
        raise HeightmapError(f"{path.name} is a {len(shape)}-D array of shape {shape}; a "
                             f"heightfield is a 2-D array (rows, columns)")
    _check_sides(path, *shape)
    promised = shape[0] * shape[1] * dtype.itemsize
    if data_bytes < promised:
        raise HeightmapError(f"{path.name} is cut short: it holds {data_bytes} bytes of data where its header "
                             f"promises {promised} ({shape[1]} x {shape[0]} {dtype} values)")
    try:
        values = np.load(path, allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise HeightmapError(f"{path.name} cannot be read as a NumPy .npy array: {exc}") from None
    return values.astype(float)


def check_extent(name: str, shape: tuple[int, int], length: float, width: float) -> None:
    """A grid of ``shape`` (rows, cols) stretched over length x width must have cells of about the
    same size both ways (within ``MAX_CELL_ASPECT``): anything else is a size that does not match
    (length and width swapped, or the wrong file)."""
    rows, cols = shape
    dx, dy = length / (cols - 1), width / (rows - 1)
    aspect = max(dx / dy, dy / dx)
    if aspect > MAX_CELL_ASPECT:
        fit = width * (cols - 1) / (rows - 1)
        raise HeightmapError(
            f"{name} is {cols} x {rows} samples (columns x rows) but is stretched over length {length:g} "
            f"x width {width:g} m: its cells would be {dx:.3g} x {dy:.3g} m, {aspect:.1f} times longer one "
            f"way than the other; give length and width in the proportion of its columns and rows "
            f"(e.g. length: {fit:.3g} for width {width:g}), or resample the file", field="length")


def grid_digest(values: np.ndarray) -> str:
    """A hash of a grid's values and shape: what makes a heightfield part of a scenario's content."""
    v = np.ascontiguousarray(values, dtype=np.float64)
    h = hashlib.sha256(f"{v.shape[0]}x{v.shape[1]}:".encode())
    h.update(v.tobytes())
    return h.hexdigest()[:16]


def _normalised(values: np.ndarray) -> np.ndarray:
    """Values mapped to [0, 1] from their lowest to their highest (a flat grid: all 0)."""
    low, high = float(values.min()), float(values.max())
    if not high > low:
        return np.zeros_like(values)
    if math.isfinite(high - low):
        return (values - low) / (high - low)
    scale = max(abs(low), abs(high))          # values near the ends of the float range: no overflow
    return (values / scale - low / scale) / (high / scale - low / scale)


def load_heightfield(folder: Path, file: str, length: float, width: float) -> tuple[Path, str]:
    """Resolve, read and check a heightfield file for an element of ``length`` x ``width``: (its
    path, its digest). What the loader calls; every problem is a HeightmapError."""
    path = resolve_heightfield_path(folder, file)
    _, values = _file_values(path)
    check_extent(Path(file).name, values.shape, length, width)
    return path, grid_digest(values)


def _file_values(path: Path) -> tuple[Any, np.ndarray]:
    """(a cache key, the file's raw values, read-only), cached by its path, size and modification
    time."""
    try:
        st = path.stat()
    except OSError:
        return None, read_height_file(path)      # raises the reason
    key = ("file", str(path), st.st_size, st.st_mtime_ns)
    return key, _cached(key, lambda: _frozen(read_height_file(path)))


def _frozen(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


# ---------------------------------------------------------------- rough ground


def rough_shape(length: float, width: float, wavelength: float) -> tuple[int, int]:
    """(rows, cols) of a rough patch's grid: ``ROUGH_SAMPLES_PER_WAVELENGTH`` samples a wavelength."""
    spacing = wavelength / ROUGH_SAMPLES_PER_WAVELENGTH
    return max(2, math.ceil(width / spacing) + 1), max(2, math.ceil(length / spacing) + 1)


def check_rough(length: float, width: float, wavelength: float) -> None:
    """A rough patch whose grid would exceed ``MAX_GRID_SIDE`` a side is refused (HeightmapError)."""
    rows, cols = rough_shape(length, width, wavelength)
    if rows > MAX_GRID_SIDE or cols > MAX_GRID_SIDE:
        raise HeightmapError(
            f"a rough patch {length:g} x {width:g} m with bumps every {wavelength:g} m needs a grid of "
            f"{cols} x {rows} samples ({ROUGH_SAMPLES_PER_WAVELENGTH} a wavelength), more than the limit of "
            f"{MAX_GRID_SIDE} a side; make the patch smaller (or several patches) or the wavelength longer",
            field="wavelength")


def rough_heights(length: float, width: float, amplitude: float, wavelength: float, seed: int) -> np.ndarray:
    """A rough patch's heights (rows, cols) in [0, amplitude]: white noise from ``seed`` filtered by
    a Gaussian of ``ROUGH_SIGMA`` wavelengths (the grid padded by a wavelength so the filter does not
    wrap around), scaled to [0, amplitude], and tapered (a smoothstep) to 0 over one wavelength at
    the border. The same arguments give the same bits."""
    check_rough(length, width, wavelength)
    rows, cols = rough_shape(length, width, wavelength)
    pad = ROUGH_SAMPLES_PER_WAVELENGTH
    rng = np.random.Generator(np.random.PCG64(int(seed) & 0xFFFFFFFFFFFFFFFF))
    noise = rng.standard_normal((rows + 2 * pad, cols + 2 * pad))
    sigma = ROUGH_SIGMA * ROUGH_SAMPLES_PER_WAVELENGTH          # in samples
    ky = np.fft.fftfreq(noise.shape[0])[:, None]
    kx = np.fft.rfftfreq(noise.shape[1])[None, :]
    kernel = np.exp(-2.0 * (math.pi * sigma) ** 2 * (kx ** 2 + ky ** 2))
    smooth = np.fft.irfft2(np.fft.rfft2(noise) * kernel, s=noise.shape)[pad:pad + rows, pad:pad + cols]
    heights = _normalised(smooth) * amplitude
    return heights * _taper(rows, cols, length, width, wavelength)


def _taper(rows: int, cols: int, length: float, width: float, wavelength: float) -> np.ndarray:
    """1 inside, falling smoothly to 0 at the border over one wavelength (at most a quarter of the
    patch's side)."""
    def ramp(n: int, side: float) -> np.ndarray:
        pos = np.linspace(0.0, side, n)
        edge = np.minimum(pos, side - pos) / max(min(wavelength, side / 4.0), 1e-9)
        s = np.clip(edge, 0.0, 1.0)
        return s * s * (3.0 - 2.0 * s)
    return ramp(rows, width)[:, None] * ramp(cols, length)[None, :]


# ---------------------------------------------------------------- the grid of an element


def height_grid(element: Any, scenario: Any = None) -> HeightGrid:
    """The HeightGrid of a rough or heightfield element (cached per process). A heightfield's file
    is resolved beside ``scenario.source`` and must still hash to the digest the loader read; a
    problem is a ScenarioError naming the scenario and the element's field."""
    from ...core.errors import ScenarioError

    try:
        return _element_grid(element, getattr(scenario, "source", None))
    except HeightmapError as exc:
        raise ScenarioError(str(exc), path=getattr(scenario, "source", None),
                            field=f"terrain[{element.name}].{exc.field}",
                            hint=("fix the file or the path (relative to the scenario's folder)"
                                  if exc.field == "file" else f"change {exc.field}")) from None


def _element_grid(element: Any, source: str | None) -> HeightGrid:
    if element.kind == "rough":
        key = ("rough", element.length, element.width, element.amplitude, element.wavelength, element.seed)
        return _cached(key, lambda: _grid(rough_heights(element.length, element.width, element.amplitude,
                                                        element.wavelength, element.seed),
                                          element.length, element.width))
    if element.kind != "heightfield":
        raise TypeError(f"{element.kind} elements have no height grid")
    folder = Path(source).parent if source else Path.cwd()
    path = resolve_heightfield_path(folder, element.file)
    file_key, values = _file_values(path)

    def make() -> HeightGrid:
        check_extent(Path(element.file).name, values.shape, element.length, element.width)
        if element.digest and grid_digest(values) != element.digest:
            raise HeightmapError(f"{path.name} has changed since the scenario was loaded (its grid no "
                                 f"longer hashes to {element.digest}); reload the scenario")
        span = element.max_height - element.min_height
        return _grid(element.min_height + span * _normalised(values)[::-1], element.length, element.width)

    return _cached(("heightfield", file_key, element.digest, element.length, element.width,
                    element.min_height, element.max_height), make)


def _grid(heights: np.ndarray, length: float, width: float) -> HeightGrid:
    heights = np.ascontiguousarray(heights, dtype=np.float64)
    heights.flags.writeable = False
    rows, cols = heights.shape
    return HeightGrid(heights, (length / (cols - 1), width / (rows - 1)))
