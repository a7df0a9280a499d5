"""Noise seeds of repeated runs, shared by ``--nav-repeat`` (plugin/collect.py) and the search's
confirmation runs (search/holding.py), so that a frozen failure's confirmation runs are replayed
exactly by ``pytest <file> --nav-seed <its nav_seed> --nav-repeat <runs + 1>``."""
from __future__ import annotations

import hashlib


def repeat_seed(base_seed: int, repeat: int) -> int:
    """The base seed of one --nav-repeat run: the run's own seed for repeat 0, else a stable
    63-bit mix of (base seed, repeat) so every repeat draws different sensor noise."""
    if repeat == 0:
        return base_seed
    digest = hashlib.sha256(f"navscenario-repeat:{base_seed}:{repeat}".encode()).digest()
    return int.from_bytes(digest[:8], "big") >> 1
