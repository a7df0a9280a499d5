"""Dispatch: many episodes at once, on this machine's cores or on a Ray cluster.

In: a batch of ``EpisodeJob`` (scenario, subject, seed, tick limit, which trajectories to keep).
Out: one ``EpisodeResult`` per job, in job order, with the same bits whichever executor ran it
(``SerialExecutor`` in this process, ``ProcessExecutor`` on local worker processes,
``RayExecutor`` as Ray tasks). An episode that raised comes back as the same exception, raised
when its result is asked for; a worker that dies mid-episode loses nothing (its jobs run again).

Read first: ``jobs.py`` (what crosses to a worker and back), then ``local.py`` and ``on_ray.py``.
Ray is optional (``pip install "pytest-navscenario[ray]"``) and imported only by ``on_ray.py``.
"""
from __future__ import annotations

from ..core.lazy import lazy_exports

_EXPORTS = {"EpisodeJob": "jobs", "run_job": "jobs", "Pending": "jobs", "SubjectFactory": "jobs",
            "SerialExecutor": "local", "ProcessExecutor": "local", "make_local_executor": "local",
            "RayExecutor": "on_ray", "RaySetupError": "on_ray"}
__all__ = sorted(_EXPORTS)

__getattr__ = lazy_exports(__name__, _EXPORTS)
