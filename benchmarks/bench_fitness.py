"""Does a fitness margin lead to failures? (issue 13: "the fitness cannot see the failure mode")

Run from the repository root (not a timed test; deterministic counts):

    nice python benchmarks/bench_fitness.py --subject dwa --seeds boxes1,boxes2,cylinders,corridor

Per seed: N uniformly random layouts are simulated (their failure rate is printed as
``random_fail``); among the successes, the tenth lowest in each margin of search/fitness.py (and
in the old and the new robustness) are taken as parents, as is a random tenth, and each parent gets
five Gaussian children (sd 10 % of each range). The printed figure is the share of those children
that fail: a margin that sees failures coming has children that fail more often than the random
tenth's.
"""
from __future__ import annotations

import argparse
import random
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CHILDREN = 5


def probe(subject_spec: str, name: str, n: int) -> dict:
    import numpy as np

    from pytest_navscenario.harness.runner import run_scenario
    from pytest_navscenario.scenario.loader import load_scenario
    from pytest_navscenario.search.fitness import MEAN_SHARE, Route, _margins
    from pytest_navscenario.search.space import SearchSpace, invalid_reason
    from pytest_navscenario.subjects.loading import load_subject

    subject = load_subject(subject_spec)
    seed = load_scenario(ROOT / "scenarios" / f"{name}.yaml")
    space, route, rnd = SearchSpace(seed), Route(seed), random.Random(1)

    def failed(off) -> tuple[bool, dict | None]:
        res = run_scenario(space.apply(off), subject(), stuck_after=20.0)
        if res.outcome.value != "success":
            return True, None
        m = _margins(res, np.asarray(res.trajectory.pose).reshape(-1, 3), route)
        m["old_time"] = max(0.0, 1.0 - res.metrics.duration / seed.mission.timeout)
        return False, m

    def valid(off) -> bool:
        return invalid_reason(space.apply(off)) is None

    pool, fails = [], 0
    while len(pool) + fails < n:
        off = tuple(rnd.uniform(p.lo, p.hi) for p in space.params)
        if valid(off):
            bad, m = failed(off)
            fails += bad
            if not bad:
                pool.append((off, m))

    def rob(m, keys):
        v = [m[k] for k in keys if k in m]
        return min(v) + MEAN_SHARE * sum(v) / len(v)

    feats = {k: (lambda m, k=k: m.get(k, 1.0)) for k in ("clearance", "time", "stall", "safety", "efficiency")}
    feats["old robustness"] = lambda m: rob(m, ["old_time", "clearance", "safety", "efficiency"])
    feats["new robustness"] = lambda m: rob(m, ["time", "stall", "clearance", "safety", "efficiency"])
    k = max(3, len(pool) // 10)
    sets = {f: sorted(range(len(pool)), key=lambda i: fn(pool[i][1]))[:k] for f, fn in feats.items()}
    sets["random tenth"] = random.Random(2).sample(range(len(pool)), k)
    cache: dict[int, int] = {}

    def children(i: int) -> int:
        if i not in cache:
            r, c, made = random.Random(100 + i), 0, 0
            while made < CHILDREN:
                off = space.clip([v + r.gauss(0, 0.1) * p.width for v, p in zip(pool[i][0], space.params)])
                if valid(off):
                    made += 1
                    c += failed(off)[0]
            cache[i] = c
        return cache[i]

    out = {"random_fail": fails / n}
    out.update({f: sum(children(i) for i in idx) / (CHILDREN * len(idx)) for f, idx in sets.items()})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--subject", default="dwa")
    ap.add_argument("--seeds", default="boxes1,boxes2,cylinders,corridor")
    ap.add_argument("--layouts", type=int, default=200)
    a = ap.parse_args()
    rows = {s: probe(a.subject, s, a.layouts) for s in a.seeds.split(",")}
    keys = list(next(iter(rows.values())))
    print(f"{'seed':<12}" + "".join(f"{k:>16}" for k in keys))
    for s, r in rows.items():
        print(f"{s:<12}" + "".join(f"{r[k]:>16.1%}" for k in keys))
    print(f"{'mean':<12}" + "".join(f"{sum(r[k] for r in rows.values()) / len(rows):>16.1%}" for k in keys))


if __name__ == "__main__":
    main()
