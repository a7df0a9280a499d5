"""The GPU batch engine: a batch's episodes as the worlds of MuJoCo Warp models on an accelerator
(or on the CPU, where Warp runs its kernels too), behind the ``BatchEngine`` interface of
sim/batching/batch.py. Optional: ``pip install "pytest-navscenario[gpu]"`` (mujoco-warp, warp-lang).

What it runs (``unsupported`` refuses the rest, which then runs on the CPU, one episode at a
time, with the reason in the summary's batching line):

* the planar body (every footprint), static obstacles of every kind (boxes, cylinders, polygons
  and meshes: their convex parts collide, their exact prism is what the lidar sees; glass that the
  lidar does not see), moving obstacles (their positions written on the device before every
  physics step), the safety layer, lidar noise (every noise model: drawn on the host from the
  episode's seed), sensor faults (latency, localisation drift), the stuck check, waypoints;
* not: a robot body that rides the ground or any terrain (wheeled, legged and MJCF bodies, ramps,
  steps, heightfields: their contacts with the ground and the grid ray casts are the CPU's), and a
  3D lidar.

The physics, the contact checks, the recording of every physics step and the lidar's ray casts are
on the device; the per-episode bookkeeping is the CPU episode's own code (warp_loop.py). The
trajectories agree with the CPU engine's within a tolerance, not bit for bit: MuJoCo Warp computes
in single precision with its own solver order (docs/architecture.md gives the measured agreement).
"""
from __future__ import annotations

from typing import Any, Sequence

from ...scenario.model import Scenario
from ..body_world import rides_the_ground
from ..episode import SimResult

INSTALL_HINT = 'pip install "pytest-navscenario[gpu]" (or pip install -e ".[gpu]" in a checkout)'


def missing() -> str | None:
    """Why the warp engine cannot run here (its packages are not installed), or None."""
    import importlib.util
    absent = [name for name, module in (("warp-lang", "warp"), ("mujoco-warp", "mujoco_warp"))
              if importlib.util.find_spec(module) is None]
    if absent:
        return f"{' and '.join(absent)} not installed: {INSTALL_HINT}"
    return None


class WarpEngine:
    """Runs batches as the worlds of MuJoCo Warp models on ``device`` (a Warp device name such as
    "cuda:0" or "cpu"; None: Warp's default, the first GPU if there is one). ``graph``: on a CUDA
    device, capture each group's tick as a CUDA graph and replay it."""

    name = "warp"

    def __init__(self, device: str | None = None, graph: bool = True):
        self.device, self.graph = device, graph

    def unsupported(self, scenario: Scenario) -> str | None:
        if rides_the_ground(scenario):
            what = "has terrain" if scenario.terrain else f"has a robot body ({scenario.robot.body.kind}) that rides the ground"
            return f"it {what}, which the warp engine does not simulate"
        if scenario.robot.lidar3d is not None:
            return "it has a 3D lidar, which the warp engine does not cast"
        return None

    def run(self, requests: Sequence[Any], planner: Any) -> list[SimResult | Exception]:
        from .warp_loop import WarpLockstep
        return WarpLockstep(requests, planner, self.device, self.graph).run()
