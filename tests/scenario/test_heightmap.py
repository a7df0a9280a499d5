"""Height grids: heightfield files (greyscale PNG 8/16-bit, .npy) read as maps seen from above, each
bad file refused with its reason, rough ground drawn from its seed (same seed, same bits)."""
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from pytest_navscenario.core.errors import ScenarioError
from pytest_navscenario.scenario.ground import heightmap
from pytest_navscenario.scenario.ground.heightmap import HeightmapError, height_grid, load_heightfield
from pytest_navscenario.scenario.model import Scenario
from pytest_navscenario.scenario.terrain import Heightfield, Rough


@pytest.fixture(autouse=True)
def _fresh_cache():
    heightmap.clear_grid_cache()
    yield
    heightmap.clear_grid_cache()


def _scenario(folder: Path) -> Scenario:
    from pytest_navscenario.scenario.loader import loads_scenario
    return loads_scenario("version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 0, y: 5}}\n",
                          source=str(folder / "s.yaml"))


def test_a_16_bit_png_is_a_map_seen_from_above_scaled_from_min_to_max_height(tmp_path):
    img = np.zeros((3, 5), dtype=np.uint16)         # 5 columns (x), 3 rows (y); top row = +y
    img[0, 4] = 60000                                # top right: the (+x, +y) corner is the highest
    img[2, 0] = 30000                                # bottom left: (-x, -y), half as high
    img[1, 2] = 10000                                # so that the lowest value (0) is elsewhere
    Image.fromarray(img).save(tmp_path / "h.png")
    element = Heightfield("hf", 1.0, 2.0, file="h.png", length=4.0, width=2.0, min_height=-0.5,
                          max_height=1.5)
    grid = height_grid(element, _scenario(tmp_path))
    assert grid.heights.shape == (3, 5) and grid.cell == (1.0, 1.0)
    assert grid.heights[2, 4] == pytest.approx(1.5)           # row 2 = the +y edge
    assert grid.heights[0, 0] == pytest.approx(-0.5 + 2.0 * 0.5)
    assert grid.heights.min() == pytest.approx(-0.5)
    assert grid.sample(2.0, 1.0) == pytest.approx(1.5)         # the element's own frame, centred
    assert np.isnan(grid.sample(2.1, 0.0))                     # outside: NaN
    assert not grid.heights.flags.writeable
    assert height_grid(element, _scenario(tmp_path)) is grid   # cached per process


def test_an_8_bit_png_and_an_npy_of_the_same_map_give_the_same_grid(tmp_path):
    values = np.array([[0, 10, 20], [30, 40, 255]], dtype=np.uint8)
    Image.fromarray(values).save(tmp_path / "a.png")
    np.save(tmp_path / "b.npy", values.astype(float) * 3.0 - 7.0)    # any numbers: lowest to highest
    scenario = _scenario(tmp_path)
    a = height_grid(Heightfield("a", 0, 0, file="a.png", length=2, width=1, max_height=2.0), scenario)
    b = height_grid(Heightfield("b", 0, 0, file="b.npy", length=2, width=1, max_height=2.0), scenario)
    assert np.array_equal(a.heights, b.heights)
    assert load_heightfield(tmp_path, "a.png", 2, 1)[1] != load_heightfield(tmp_path, "b.npy", 2, 1)[1]


def test_sampling_follows_mujocos_triangles_not_bilinear(tmp_path):
    np.save(tmp_path / "h.npy", np.array([[0.0, 1.0], [0.0, 0.0]])[::-1])   # only (+x, -y) is high
    grid = height_grid(Heightfield("h", 0, 0, file="h.npy", length=1, width=1), _scenario(tmp_path))
    assert grid.heights[0, 1] == 1.0
    # centre of the cell: on the diagonal from (c, r) to (c+1, r+1), halfway between 0 and 0
    assert grid.sample(0.0, 0.0) == pytest.approx(0.0)
    assert grid.sample(0.25, -0.25) == pytest.approx(0.5)      # in the lower triangle: planar
    assert grid.sample(-0.25, 0.25) == pytest.approx(0.0)      # in the upper triangle: flat


def _write(tmp_path: Path, name: str, content) -> None:
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif isinstance(content, Image.Image):
        content.save(path)
    else:
        np.save(path, content)


@pytest.mark.parametrize("name, content, file, length, width, field, words", [
    ("h.png", None, "missing.png", 2, 2, "file", "does not exist"),
    ("h.png", b"not a png at all", "h.png", 2, 2, "file", "cannot be read as a PNG"),
    ("h.npy", b"\x93NUMPY garbage", "h.npy", 2, 2, "file", "cannot be read as a NumPy"),
    ("h.npy", np.array([[0.0, np.nan], [1.0, 2.0]]), "h.npy", 2, 2, "file", "row 0, column 1"),
    ("h.npy", np.array([[0.0, np.inf], [1.0, 2.0]]), "h.npy", 2, 2, "file", "not finite"),
    ("h.npy", np.zeros((2, 2, 2)), "h.npy", 2, 2, "file", "3-D array"),
    ("h.npy", np.array([["a", "b"], ["c", "d"]]), "h.npy", 2, 2, "file", "holds <U1"),
    ("h.npy", np.zeros((1, 5)), "h.npy", 2, 2, "file", "at least 2 x 2"),
    ("h.npy", np.zeros((2, 1100)), "h.npy", 2, 2, "file", "more than the limit of 1024"),
    ("h.npy", np.zeros((11, 101)), "h.npy", 1, 10, "length", "give length and width in the proportion"),
    ("h.png", Image.new("RGB", (3, 3), (200, 10, 10)), "h.png", 2, 2, "file", "colour image"),
    ("h.tif", b"II*\x00", "h.tif", 2, 2, "file", "unknown heightfield format .tif"),
    ("h.npy", np.zeros((3, 3)), "../h.npy", 2, 2, "file", "leaves the scenario's folder"),
    ("h.npy", np.zeros((3, 3)), "/etc/h.npy", 2, 2, "file", "absolute path"),
])
def test_each_bad_heightfield_is_refused_with_its_reason(tmp_path, name, content, file, length, width,
                                                         field, words):
    folder = tmp_path / "scenarios"
    folder.mkdir()
    if content is not None:
        _write(folder if not file.startswith("..") else tmp_path, name, content)
    with pytest.raises(HeightmapError) as info:
        load_heightfield(folder, file, length, width)
    assert words in str(info.value)
    assert info.value.field == field
    # at simulation time the same problem names the scenario and the element's field
    with pytest.raises(ScenarioError) as info:
        height_grid(Heightfield("dock", 0, 0, file=file, length=length, width=width), _scenario(folder))
    assert words in str(info.value) and f"terrain[dock].{field}" in str(info.value)
    assert str(folder / "s.yaml") in str(info.value)


def test_an_oversized_file_is_refused_unread(tmp_path, monkeypatch):
    np.save(tmp_path / "h.npy", np.zeros((50, 50)))
    monkeypatch.setattr(heightmap, "MAX_HEIGHTFIELD_BYTES", 1000)
    with pytest.raises(HeightmapError, match="h.npy is 0.0 MB, more than the limit"):
        load_heightfield(tmp_path, "h.npy", 2, 2)


def test_a_file_changed_after_loading_is_an_error_not_another_terrain(tmp_path):
    np.save(tmp_path / "h.npy", np.arange(9.0).reshape(3, 3))
    _, digest = load_heightfield(tmp_path, "h.npy", 2, 2)
    element = Heightfield("h", 0, 0, file="h.npy", length=2, width=2, digest=digest)
    height_grid(element, _scenario(tmp_path))
    np.save(tmp_path / "h.npy", np.arange(9.0).reshape(3, 3)[::-1])
    with pytest.raises(ScenarioError, match="has changed since the scenario was loaded"):
        height_grid(element, _scenario(tmp_path))


def test_rough_ground_is_seeded_bounded_tapered_and_bumps_about_a_wavelength_apart():
    rough = Rough("yard", 0, 0, length=20.0, width=10.0, amplitude=0.15, wavelength=1.0, seed=7)
    grid = height_grid(rough)
    assert grid.heights.shape == (81, 161) and grid.cell == (0.125, 0.125)
    assert grid.heights.max() == pytest.approx(0.15, rel=0.05) and grid.heights.min() >= 0.0
    assert np.all(grid.heights[0] == 0) and np.all(grid.heights[:, -1] == 0)   # meets its base
    heightmap.clear_grid_cache()
    assert np.array_equal(height_grid(rough).heights, grid.heights)              # same seed, same bits
    from dataclasses import replace
    assert not np.array_equal(height_grid(replace(rough, seed=8)).heights, grid.heights)
    inner = grid.heights[8:-8, 8:-8]
    padded = np.pad(inner, 1, mode="edge")   # a 3 x 3 maximum filter, as scipy.ndimage's (edges: nearest)
    peaks = (inner == np.lib.stride_tricks.sliding_window_view(padded, (3, 3)).max(axis=(2, 3))).sum()
    area = (inner.shape[0] * 0.125) * (inner.shape[1] * 0.125)
    assert 0.5 < area / peaks < 2.0          # about one bump per square wavelength


def test_rough_ground_too_fine_for_the_grid_limit_says_what_to_change():
    with pytest.raises(HeightmapError, match="make the patch smaller") as info:
        heightmap.check_rough(200.0, 5.0, 0.5)
    assert info.value.field == "wavelength"
    with pytest.raises(ScenarioError, match=r"terrain\[r\].wavelength: a rough patch 200 x 5 m .* 3201 x 81"):
        height_grid(Rough("r", 0, 0, length=200.0, width=5.0, amplitude=0.1, wavelength=0.5))


LOADED = """version: 1
robot: {body: {type: wheeled}, drive: diff}
mission: {start: {x: -8, y: 0}, goal: {x: -6, y: 0}}
terrain:
  - type: heightfield
    name: yard
    x: 0
    y: 0
    file: {file}
    length: {length}
    width: 2
  - {type: rough, name: bumps, x: 20, y: 0, length: 4, width: 4, amplitude: 0.1, wavelength: {wavelength}}
"""


@pytest.mark.parametrize("file, content, length, wavelength, field, line, words", [
    ("missing.npy", None, 2, 1.0, "terrain[0].file", 9, "does not exist"),
    ("h.npy", np.array([[0.0, np.nan], [1.0, 2.0]]), 2, 1.0, "terrain[0].file", 9, "not finite"),
    ("h.npy", np.zeros((3, 41)), 0.05, 1.0, "terrain[0].length", 10, "give length and width in the proportion"),
    ("../out.npy", np.zeros((3, 3)), 2, 1.0, "terrain[0].file", 9, "leaves the scenario's folder"),
    ("h.npy", np.zeros((3, 3)), 2, 0.001, "terrain[1].wavelength", 12, "make the patch smaller"),
])
def test_the_loader_names_file_line_and_field_of_a_bad_height_grid(tmp_path, file, content, length, wavelength,
                                                                   field, line, words):
    from pytest_navscenario.scenario.loader import load_scenario

    folder = tmp_path / "s"
    folder.mkdir()
    if content is not None:
        np.save((folder / file).resolve() if not file.startswith("..") else tmp_path / "out.npy", content)
    path = folder / "yard.yaml"
    path.write_text(LOADED.replace("{file}", file).replace("{length}", str(length))
                    .replace("{wavelength}", str(wavelength)))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    err = info.value
    assert (err.path, err.line, err.field) == (str(path), line, field), str(err)
    assert words in err.message


def test_a_loaded_heightfield_carries_its_grid_in_the_content_hash(tmp_path):
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.scenario.model import content_hash

    np.save(tmp_path / "h.npy", np.arange(9.0).reshape(3, 3))
    path = tmp_path / "yard.yaml"
    path.write_text(LOADED.replace("{file}", "h.npy").replace("{length}", "2").replace("{wavelength}", "1.0"))
    first = load_scenario(path)
    assert first.terrain[0].digest == load_heightfield(tmp_path, "h.npy", 2, 2)[1]
    np.save(tmp_path / "h.npy", np.arange(9.0).reshape(3, 3) * 2)
    heightmap.clear_grid_cache()
    assert content_hash(load_scenario(path)) != content_hash(first)
    (tmp_path / "moved").mkdir()
    np.save(tmp_path / "moved" / "g.npy", np.arange(9.0).reshape(3, 3) * 2)
    moved = tmp_path / "moved" / "yard.yaml"
    moved.write_text(path.read_text().replace("h.npy", "g.npy"))
    assert content_hash(load_scenario(moved)) == content_hash(load_scenario(path))   # wherever the file is


def test_a_frozen_failure_takes_its_heightfield_file_along(tmp_path):
    """A failure frozen from a seed with a heightfield loads in its own folder and hashes the same."""
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.scenario.model import content_hash
    from pytest_navscenario.search.freeze import save_standalone

    (tmp_path / "seeds" / "ground").mkdir(parents=True)
    np.save(tmp_path / "seeds" / "ground" / "h.npy", np.arange(9.0).reshape(3, 3))
    seed_path = tmp_path / "seeds" / "yard.yaml"
    seed_path.write_text(LOADED.replace("{file}", "ground/h.npy").replace("{length}", "2")
                         .replace("{wavelength}", "1.0"))
    seed = load_scenario(seed_path)
    out = tmp_path / "regressions" / "yard-1.yaml"
    save_standalone(seed, seed, out)
    frozen = load_scenario(out)
    assert frozen.terrain[0].file.startswith("heightmaps/h-") and (out.parent / frozen.terrain[0].file).is_file()
    assert content_hash(frozen) == content_hash(seed)


def _npy_header_only(path: Path, shape: tuple) -> None:
    """An .npy file whose header promises ``shape`` (float64) and whose data is 64 bytes."""
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': %r, }" % (shape,)
    header = header.ljust(118) + "\n"
    path.write_bytes(b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode() + b"\x00" * 64)


def test_an_npy_whose_header_promises_a_huge_array_is_refused_before_its_data_is_read(tmp_path):
    """A 200-byte file claiming 60000 x 60000 made numpy allocate 26.8 GiB (a MemoryError traceback
    at collection); one claiming 600 x 600 over 64 bytes is a truncated file."""
    _npy_header_only(tmp_path / "liar.npy", (60000, 60000))
    with pytest.raises(HeightmapError, match=r"liar.npy is 60000 x 60000 samples, more than the limit of 1024"):
        load_heightfield(tmp_path, "liar.npy", 2, 2)
    import pickle
    (tmp_path / "p.npy").write_bytes(pickle.dumps(np.zeros((4, 4))))
    with pytest.raises(HeightmapError, match=r"p.npy cannot be read as a NumPy .npy array: it is a Python pickle"):
        load_heightfield(tmp_path, "p.npy", 2, 2)
    _npy_header_only(tmp_path / "short.npy", (600, 600))
    with pytest.raises(HeightmapError, match=r"short.npy .*holds 64 bytes of data where its header promises 2880000"):
        load_heightfield(tmp_path, "short.npy", 2, 2)


def test_values_at_the_ends_of_the_float_range_map_to_the_heights_without_overflow(tmp_path):
    """(v - low) / (high - low) overflowed for +-1e308: NaN heights, and MuJoCo refused the model."""
    np.save(tmp_path / "h.npy", np.array([[-1e308, 0.0], [0.0, 1e308]]))
    grid = height_grid(Heightfield("h", 0, 0, file="h.npy", length=2, width=2, max_height=1.0),
                       _scenario(tmp_path))
    assert np.isfinite(grid.heights).all()
    assert sorted(grid.heights.ravel().tolist()) == pytest.approx([0.0, 0.5, 0.5, 1.0])


def test_reading_a_png_leaves_pillows_own_limit_alone_and_warns_nothing(tmp_path, recwarn):
    """A planner reading a large map image with Pillow in the same process must not meet our
    limit: the size is checked from the PNG's header instead."""
    before = Image.MAX_IMAGE_PIXELS
    Image.new("L", (2500, 2500)).save(tmp_path / "big.png")
    with pytest.raises(HeightmapError, match="2500 x 2500 samples, more than the limit of 1024"):
        load_heightfield(tmp_path, "big.png", 2, 2)
    assert Image.MAX_IMAGE_PIXELS == before
    assert not [w for w in recwarn if "DecompressionBomb" in type(w.message).__name__]
