"""The second pass over a bag: its scans streamed a batch at a time (memory for a batch, not the
bag), each kept only where odometry surrounds every beam of it; and a small sample of the window's
scans for what must look before the stream (the laser mount's guess, the scans' timing)."""
from __future__ import annotations

from typing import Iterator

import numpy as np

from .reading import bag_pass, stamp_ns
from .scans import ScanBatch, StreamStats

BATCH = 20                 # scans projected together (a 2 s slice at 10 Hz)
GAP = 0.5                  # s: odometry further apart than this around a beam is a gap (no pose there)


def odometry_gaps(odom_t: np.ndarray, gap: float = GAP) -> np.ndarray:
    """(g, 2) start and end times of the gaps in the odometry longer than ``gap`` seconds."""
    d = np.diff(odom_t)
    idx = np.nonzero(d > gap)[0]
    return np.stack([odom_t[idx], odom_t[idx + 1]], 1) if len(idx) else np.zeros((0, 2))


def stream_scans(data, batch: int | None = None) -> Iterator[ScanBatch]:
    """The scans of ``data.scan_topic`` whose every beam has odometry around it, a batch at a time,
    from a second pass over the bag (one batch in memory); ``data.scan_stats`` counts the rest."""
    batch = batch or BATCH
    layout, timing = data.scan_layout, data.scan_timing
    stats = data.scan_stats = StreamStats()
    od_t = data.odom[:, 0]
    lo, hi = float(od_t[0]), float(od_t[-1])
    full = data.full_odom if len(data.full_odom) else data.odom
    full_lo, full_hi = float(full[0, 0]), float(full[-1, 0])
    gaps = odometry_gaps(od_t)
    offs = timing.beam_offsets(layout.beams)
    early, late = float(offs.min()), float(offs.max())
    key = layout.key()
    ts: list[float] = []
    rows: list[np.ndarray] = []
    with bag_pass(data) as reader:
        conns = [c for c in reader.connections if c.topic == layout.topic]
        for conn, bag_ns, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            if (len(msg.ranges), float(msg.angle_min), float(msg.angle_increment)) != key:
                stats.other_layout += 1
                continue
            t = (stamp_ns(msg.header, bag_ns) - data.origin_ns) * 1e-9
            if t + early < lo - 1e-6 or t + late > hi + 1e-6:
                # outside the window; worth saying only where the bag's odometry itself has no pose
                stats.outside += int(not full_lo <= t <= full_hi and lo - 5.0 <= t <= hi + 5.0)
                continue
            if len(gaps) and ((gaps[:, 0] < t + late) & (gaps[:, 1] > t + early)).any():
                stats.in_gap += 1
                if not stats.gap_spans or t - stats.gap_spans[-1][1] > 1.0:
                    stats.gap_spans.append((t, t))
                else:
                    stats.gap_spans[-1] = (stats.gap_spans[-1][0], t)
                continue
            ts.append(t)
            rows.append(np.asarray(msg.ranges, dtype=np.float32))
            if len(ts) >= batch:
                stats.used += len(ts)
                yield ScanBatch(np.array(ts), np.stack(rows))
                ts, rows = [], []
    if ts:
        stats.used += len(ts)
        yield ScanBatch(np.array(ts), np.stack(rows))


def stream_notes(data) -> list[str]:
    """What the streamed pass left out, as notes and warnings."""
    s: StreamStats = data.scan_stats
    notes = []
    if s.other_layout:
        notes.append(f"{s.other_layout} scan(s) on {data.scan_topic} with another beam count or angles than the "
                     f"first usable one ({data.scan_layout.beams} beams from "
                     f"{math.degrees(data.scan_layout.angle_min):.1f} deg) were skipped")
    if s.in_gap:
        spans = ", ".join(f"t={a:.1f}..{b:.1f} s" for a, b in s.gap_spans[:5]) + (" ..." if len(s.gap_spans) > 5 else "")
        notes.append(f"warning: {s.in_gap} scan(s) fell where the odometry has gaps longer than {GAP:g} s ({spans}): "
                     f"skipped, not placed with a guessed pose")
    if s.outside:
        notes.append(f"warning: {s.outside} scan(s) before the first or after the last odometry message were "
                     f"skipped (no pose to place them with)")
    return notes


def sample_scans(data, count: int = 150, enough: int = 50) -> ScanBatch:
    """About ``count`` scans spread evenly over the window, for what needs a few scans before the
    streamed pass (the laser mount's guess): the first pass's probe when ``enough`` of its scans
    fall in the window, else read from the bag (by their receive times, so only they are read)."""
    layout = data.scan_layout
    od_lo, od_hi = data.odom[0, 0], data.odom[-1, 0]
    t = data.scan_probe[:, 0]
    inside = (t >= od_lo) & (t <= od_hi)
    if inside.sum() >= enough or len(t) >= len(data.scan_received):   # enough, or every scan
        return ScanBatch(t[inside], data.scan_probe_ranges[inside])
    lag = float(np.median(data.scan_probe[:, 1] - data.scan_probe[:, 0])) if len(data.scan_probe) else 0.0
    lo = data.origin_ns + (data.odom[0, 0] + lag - 1.0) * 1e9
    hi = data.origin_ns + (data.odom[-1, 0] + lag + 1.0) * 1e9
    inside = np.nonzero((data.scan_received >= lo) & (data.scan_received <= hi))[0]
    if len(inside) > count:
        inside = inside[np.linspace(0, len(inside) - 1, count).round().astype(int)]
    wanted = set(inside.tolist())
    ts, rows = [], []
    with bag_pass(data) as reader:
        conns = [c for c in reader.connections if c.topic == layout.topic]
        for index, (conn, bag_ns, raw) in enumerate(reader.messages(connections=conns)):
            if index not in wanted:
                continue
            msg = reader.deserialize(raw, conn.msgtype)
            t = (stamp_ns(msg.header, bag_ns) - data.origin_ns) * 1e-9
            if (len(msg.ranges), float(msg.angle_min), float(msg.angle_increment)) == layout.key() \
                    and od_lo <= t <= od_hi:
                ts.append(t)
                rows.append(np.asarray(msg.ranges, dtype=np.float32))
    return ScanBatch(np.array(ts), np.stack(rows) if rows else np.zeros((0, layout.beams), np.float32))
