"""Soak benchmark: thousands of episodes with a planner that misbehaves in 10 % of them, on 2 cores.

Checks what a regression harness must guarantee over a long run: every item is reported, memory
stays flat (growth per episode below a stated bound), and no planner subprocess outlives the run.

    python benchmarks/bench_soak.py                        # 2000 in-process episodes, -n 2
    python benchmarks/bench_soak.py --episodes 400 --external   # external (exec:) planner

Misbehaviour, chosen per scenario from its index: 4 % raise, 2 % NaN, 2 % wrong shape, 1 % too
slow, 1 % hang forever (in-process: stopped by the per-tick limit; external: crash, garbage,
exit, hang, each restarted). The remaining 90 % drive a short open-field mission normally.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

SCENARIO = """\
version: 1
name: soak-{i:05d}
family: soak
mission:
  start: {{x: 0.0, y: 0.0, yaw: 90.0}}
  goal: {{x: 0.0, y: 3.0, yaw: 90.0}}
  timeout: 10.0
obstacles:
  - {{type: box, name: crate, x: {x:.3f}, y: 1.6, length: 0.4, width: 0.4}}
"""

PLANNER = textwrap.dedent('''\
    """In-process soak planner: drives straight, misbehaves on some scenarios (by index)."""
    import math, os, time

    def _rss_kib():
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
        return 0

    class Planner:
        name = "soak"
        episodes = 0

        def reset(self, scenario):
            index = int(scenario.name.split("-")[1])
            self.mode = {0: "raise", 1: "raise", 2: "raise", 3: "raise", 4: "nan", 5: "nan",
                         6: "shape", 7: "shape", 8: "slow", 9: "hang"}.get(index % 100)
            Planner.episodes += 1
            if Planner.episodes % 100 == 0:
                with open(os.path.join(os.environ["SOAK_DIR"], f"rss-{os.getpid()}.txt"), "a") as fh:
                    fh.write(f"{Planner.episodes} {_rss_kib()}\\n")

        def act(self, obs):
            if self.mode and obs.tick == 3:
                if self.mode == "raise":
                    raise RuntimeError("soak: planner bug")
                if self.mode == "nan":
                    return (math.nan, 0.0, 0.0)
                if self.mode == "shape":
                    return (0.5, 0.0)
                if self.mode == "slow":
                    time.sleep(0.3)
                if self.mode == "hang":
                    while True:
                        pass
            dx, dy = obs.goal[0] - obs.pose[0], obs.goal[1] - obs.pose[1]
            c, s = math.cos(obs.pose[2]), math.sin(obs.pose[2])
            return (0.8 * (c * dx + s * dy), 0.8 * (-s * dx + c * dy), 0.0)
''')

EXTERNAL = textwrap.dedent('''\
    import json, sys, time
    mode = None
    for line in sys.stdin:
        msg = json.loads(line)
        if msg["type"] == "reset":
            index = int(msg["scenario"]["name"].split("-")[1])
            mode = {0: "crash", 1: "crash", 2: "garbage", 3: "garbage", 4: "exit", 5: "exit",
                    6: "error", 7: "error", 8: "hang", 9: "nan"}.get(index % 100)
            print(json.dumps({"type": "ready", "name": "soak-external"}), flush=True)
            continue
        if msg["type"] == "shutdown":
            break
        if mode and msg["tick"] == 3:
            if mode == "crash":
                raise SystemExit(3)
            if mode == "garbage":
                print("<<garbage>>", flush=True)
                continue
            if mode == "exit":
                sys.exit(0)
            if mode == "error":
                print(json.dumps({"type": "error", "message": "soak"}), flush=True)
                continue
            if mode == "hang":
                time.sleep(3600)
            if mode == "nan":
                print(json.dumps({"type": "command", "vx": float("nan")}), flush=True)
                continue
        gx, gy = msg["goal"][:2]
        x, y = msg["pose"][:2]
        print(json.dumps({"type": "command", "vx": 0.8 * (gy - y), "vy": -0.8 * (gx - x), "wz": 0.0}),
              flush=True)
''')


# Memory bound per episode: pytest itself keeps every test report until the session ends (~3 KiB
# per test for plain Python tests, measured with pytest 9), and the controller keeps each episode's
# results record for the summary and the results file (~3 KiB); episode payloads are trimmed once
# consumed. Anything above this bound is a leak.
BOUND_KIB = 10.0


def children_of(pid: int) -> list[str]:
    out = subprocess.run(["ps", "-eo", "pid,ppid,args"], capture_output=True, text=True).stdout
    return [line for line in out.splitlines()[1:] if "soak_external.py" in line]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=2000)
    ap.add_argument("--workers", default="2")
    ap.add_argument("--external", action="store_true", help="use an external (exec:) planner")
    args = ap.parse_args()

    work = Path(tempfile.mkdtemp(prefix="navsoak-"))
    suite = work / "suite"
    suite.mkdir()
    for i in range(args.episodes):
        (suite / f"soak-{i:05d}.yaml").write_text(SCENARIO.format(i=i, x=0.9 + 0.3 * ((i * 7919) % 10) / 10))
    (work / "soak_planner.py").write_text(PLANNER)
    (work / "soak_external.py").write_text(EXTERNAL)
    (work / "pytest.ini").write_text("[pytest]\n")
    subject = f"exec:{sys.executable} {work / 'soak_external.py'}" if args.external else "soak_planner:Planner"
    env = dict(os.environ, SOAK_DIR=str(work), PYTHONPATH=str(work))
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    cmd = [sys.executable, "-m", "pytest", "suite", "-q", "-p", "no:cacheprovider", "-n", args.workers,
           f"--nav-subject={subject}", "--nav-results=results.jsonl", "--nav-tick-limit=0.2",
           "--nav-artifacts=none", "--nav-summary=no"]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    time.sleep(0.5)
    leaked = children_of(proc.returncode)

    records = [json.loads(line) for line in (work / "results.jsonl").read_text().splitlines()]
    outcomes: dict[str, int] = {}
    for rec in records:
        outcomes[rec["outcome"]] = outcomes.get(rec["outcome"], 0) + 1
    growth = []
    for rss_file in work.glob("rss-*.txt"):
        rows = [tuple(map(int, line.split())) for line in rss_file.read_text().splitlines()]
        if len(rows) >= 3:  # slope after the first sample (imports and caches warm up first)
            (e0, r0), (e1, r1) = rows[1], rows[-1]
            growth.append((r1 - r0) / max(1, e1 - e0))
    print(f"command: {' '.join(cmd)}")
    print(f"episodes: {args.episodes}, reported: {len(records)}, wall: {wall:.1f} s, "
          f"{wall / max(1, len(records)) * 1000:.1f} ms per episode (2 workers)")
    print(f"outcomes: {json.dumps(outcomes, sort_keys=True)}")
    if growth:
        print(f"memory growth per episode after warm-up (KiB, per worker): "
              f"{', '.join(f'{g:.2f}' for g in growth)} (median {statistics.median(growth):.2f}; "
              f"bound {BOUND_KIB:g})")
    else:
        print("memory: no in-process samples (external planner runs in its own process)")
    print(f"leaked planner processes after the run: {len(leaked)}")
    for line in leaked:
        print("  " + line)
    ok = len(records) == args.episodes and not leaked and (not growth or max(growth) < BOUND_KIB)
    print("OK" if ok else "PROBLEM")
    if proc.returncode not in (0, 1):
        print(proc.stdout[-3000:], proc.stderr[-3000:])
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
