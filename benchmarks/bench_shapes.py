"""What one non-convex polygon or mesh obstacle costs an item, up to the loader's limits (issue 26.5).

    python benchmarks/bench_shapes.py [--repeat 3]

For each row a scenario file is written (a star polygon, or an OBJ mesh beside the scenario) and an
item's own work is timed in CPU seconds of this process, with every cache cleared first: loading the
file (for a mesh: reading it and its outline seen from above), the convex parts, the MuJoCo model, the
feasibility check (the shortest path, which the metrics reuse), and the first 10 ticks of the built-in
``dwa`` planner. The obstacle stands 1 m beside the robot's straight way, so the safety layer and the
lidar see it. The budget is one second per item; the limits (``MAX_POLYGON_POINTS``,
``mesh.MAX_TRIANGLES``, ``mesh.MAX_OUTLINE_POINTS``) are set to hold it. Medians of ``--repeat``.

    python benchmarks/bench_shapes.py --hostile

instead times refusing two hostile OBJ files (16 MB of two million faces; 20 MB of one face with
ten million corners), each read in a fresh process: CPU seconds and the process's peak memory.
"""
from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pytest_navscenario.harness.runner import check_feasibility  # noqa: E402
from pytest_navscenario.scenario import geometry, mesh  # noqa: E402
from pytest_navscenario.scenario.loader import MAX_POLYGON_POINTS, load_scenario  # noqa: E402
from pytest_navscenario.sim.episode import simulate  # noqa: E402
from pytest_navscenario.sim.world import clear_model_cache, compiled_world  # noqa: E402
from pytest_navscenario.subjects.loading import make_planner  # noqa: E402
from pytest_navscenario.verdict import paths  # noqa: E402

HEAD = "version: 1\nmission: {start: {x: 0, y: 0}, goal: {x: 10, y: 0}, timeout: 20}\nobstacles:\n"


def star(corners: int, outer: float = 2.0, inner: float = 1.0) -> list[tuple[float, float]]:
    return [(round((outer if i % 2 == 0 else inner) * math.cos(2 * math.pi * i / corners), 4),
             round((outer if i % 2 == 0 else inner) * math.sin(2 * math.pi * i / corners), 4))
            for i in range(corners)]


def star_prism_obj(corners: int, triangles: int) -> str:
    """A star prism whose walls are cut into rows until it has about ``triangles`` triangles."""
    pts = star(corners)
    rows = max(1, (triangles - 2 * corners) // (2 * corners))
    lines = [f"v {x} {y} {r / rows}" for r in range(rows + 1) for x, y in pts]
    lines += ["v 0 0 0", "v 0 0 1"]
    bottom, top = corners * (rows + 1) + 1, corners * (rows + 1) + 2
    for r in range(rows):
        for i in range(corners):
            a, b = r * corners + i + 1, r * corners + (i + 1) % corners + 1
            lines += [f"f {a} {b} {b + corners}", f"f {a} {b + corners} {a + corners}"]
    for i in range(corners):
        lines += [f"f {bottom} {(i + 1) % corners + 1} {i + 1}",
                  f"f {top} {rows * corners + i + 1} {rows * corners + (i + 1) % corners + 1}"]
    return "\n".join(lines) + "\n"


def bumpy_block_obj(triangles: int) -> str:
    """A closed 2 x 2 m block with a bumpy top: every top and bottom triangle has area seen from
    above (the outline's union works on all of them), ~4 N^2 triangles."""
    n = max(1, int((math.sqrt(64 + 16 * triangles) - 8) / 8))     # 4 n^2 + 8 n <= triangles
    lines = []
    for top in (True, False):
        for j in range(n + 1):
            for i in range(n + 1):
                z = 0.5 + 0.1 * math.sin(i * 0.3) * math.cos(j * 0.2) if top else 0.0
                lines.append(f"v {i / n * 2 - 1:.6f} {j / n * 2 - 1:.6f} {z:.6f}")

    def v(i: int, j: int, top: bool) -> int:
        return (0 if top else (n + 1) ** 2) + j * (n + 1) + i + 1
    for top in (True, False):
        for j in range(n):
            for i in range(n):
                a, b, c, d = v(i, j, top), v(i + 1, j, top), v(i + 1, j + 1, top), v(i, j + 1, top)
                lines += [f"f {a} {b} {c}", f"f {a} {c} {d}"] if top else [f"f {a} {c} {b}", f"f {a} {d} {c}"]
    rim = [(i, 0) for i in range(n)] + [(n, j) for j in range(n)] + [(n - i, n) for i in range(n)] + \
        [(0, n - j) for j in range(n)]
    for k, (i, j) in enumerate(rim):
        i2, j2 = rim[(k + 1) % len(rim)]
        lines += [f"f {v(i, j, False)} {v(i2, j2, False)} {v(i2, j2, True)}",
                  f"f {v(i, j, False)} {v(i2, j2, True)} {v(i, j, True)}"]
    return "\n".join(lines) + "\n"


def write_case(folder: Path, kind: str, corners: int, triangles: int) -> Path:
    path = folder / f"{kind}-{corners}-{triangles}.yaml"
    if kind == "polygon":
        points = [list(p) for p in star(corners)]
        path.write_text(HEAD + f"  - {{type: polygon, name: o, x: 5, y: 3, points: {points}}}\n")
    else:
        obj = folder / f"{kind}-{corners}-{triangles}.obj"
        obj.write_text(star_prism_obj(corners, triangles) if kind == "mesh" else bumpy_block_obj(triangles))
        y = 3 if kind == "mesh" else 2
        path.write_text(HEAD + f"  - {{type: mesh, name: o, file: {obj.name}, x: 5, y: {y}}}\n")
    return path


def item_once(path: Path) -> dict[str, float]:
    geometry.convex_parts_local.cache_clear()
    clear_model_cache()
    paths.clear_caches()
    out = {}
    t = time.process_time()
    sc = load_scenario(path)
    out["load"] = time.process_time() - t
    t = time.process_time()
    parts = geometry.convex_parts_local(tuple(geometry.outline_points(sc.obstacles[0])))
    out["parts"] = time.process_time() - t
    t = time.process_time()
    compiled_world(sc)
    out["model"] = time.process_time() - t
    t = time.process_time()
    reason, _ = check_feasibility(sc)
    assert reason is None, reason
    out["feasible"] = time.process_time() - t
    t = time.process_time()
    planner, _ = make_planner("dwa")
    simulate(sc, planner, 0, max_ticks=10)
    out["10 ticks"] = time.process_time() - t
    out["total"] = sum(out.values())
    out["n_parts"] = len(parts)
    out["n_corners"] = len(geometry.outline_points(sc.obstacles[0]))
    return out


READ_ONE = """
import resource, sys, time
from pathlib import Path
from pytest_navscenario.scenario.mesh import MeshError, read_mesh
t = time.process_time()
try:
    read_mesh(Path(sys.argv[1]))
    what = "read"
except MeshError as exc:
    what = "refused: " + str(exc)[:90]
print(f"{time.process_time() - t:.3f} s CPU, peak {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB; {what}")
"""


def hostile() -> None:
    import subprocess
    with tempfile.TemporaryDirectory() as tmp:
        many, fan = Path(tmp) / "many.obj", Path(tmp) / "fan.obj"
        many.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n" + "f 1 2 3\n" * 2_000_000)
        fan.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf " + "1 2 3 " * 3_300_000 + "\n")
        idle = subprocess.run([sys.executable, "-c", "import resource, numpy, shapely; print("
                               "resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024)"],
                              capture_output=True, text=True).stdout.strip()
        print(f"(an interpreter with numpy and shapely imported: {idle} MB)")
        for what, path in (("2 M faces, 16 MB", many), ("one face of 10 M corners, 20 MB", fan)):
            out = subprocess.run([sys.executable, "-c", READ_ONE, str(path)], capture_output=True, text=True,
                                 cwd=ROOT)
            print(f"{what:<34}{(out.stdout or out.stderr).strip()}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--hostile", action="store_true", help="time refusing two hostile mesh files instead")
    args = ap.parse_args()
    if args.hostile:
        hostile()
        return
    corners = min(MAX_POLYGON_POINTS, mesh.MAX_OUTLINE_POINTS)
    rows = [("polygon", 100, 0), ("polygon", 1000, 0), ("polygon", MAX_POLYGON_POINTS, 0),
            ("mesh", 100, 10_000), ("mesh", 1000, mesh.MAX_TRIANGLES),
            ("mesh", mesh.MAX_OUTLINE_POINTS, mesh.MAX_TRIANGLES),
            ("block", 4, 10_000), ("block", 4, mesh.MAX_TRIANGLES)]
    del corners
    seen = set()
    print(f"{'obstacle':<34}{'corners':>8}{'parts':>7}{'load':>8}{'parts':>8}{'model':>8}{'feasible':>9}"
          f"{'10 ticks':>9}{'total':>8}  (CPU s, median of {args.repeat})")
    with tempfile.TemporaryDirectory() as tmp:
        for kind, n, tris in rows:
            if (kind, n, tris) in seen:
                continue
            seen.add((kind, n, tris))
            path = write_case(Path(tmp), kind, n, tris)
            runs = [item_once(path) for _ in range(args.repeat)]
            med = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
            what = (f"polygon star, {n} points" if kind == "polygon" else
                    f"mesh star prism, {tris // 1000}k triangles" if kind == "mesh" else
                    f"mesh bumpy block, {tris // 1000}k triangles")
            print(f"{what:<34}{int(med['n_corners']):>8}{int(med['n_parts']):>7}{med['load']:>8.3f}"
                  f"{med['parts']:>8.3f}{med['model']:>8.3f}{med['feasible']:>9.3f}{med['10 ticks']:>9.3f}"
                  f"{med['total']:>8.3f}")


if __name__ == "__main__":
    main()
