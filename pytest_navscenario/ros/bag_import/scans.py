"""Laser scans as they were taken: their beam layout and when each beam was measured (the second,
streamed pass over the bag that hands them out a batch at a time is streaming.py).

A rotating 2D lidar measures its beams one after another: ``time_increment`` apart, the whole scan
in ``scan_time``. ROS places beam ``i`` at ``stamp + i * time_increment`` (``laser_geometry``'s
projection with per-point time, REP 117), but drivers differ on what the stamp is: the scan's
first beam (urg_node, sick_scan, the ROS convention) or the moment the scan was complete (a driver
that stamps on reception). ``choose_timing`` decides from the scan's own fields and the bag's
receive times, and says what it used; ``--scan-stamp`` and ``--scan-time-offset`` override it.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

STAMPS = ("auto", "start", "end")


@dataclass(frozen=True)
class ScanLayout:
    """The beams of the scans used (the first usable scan's layout; others are skipped, counted)."""
    topic: str
    frame: str
    beams: int
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    time_increment: float
    scan_time: float

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(self.beams)

    def key(self) -> tuple[int, float, float]:
        return self.beams, self.angle_min, self.angle_increment


def layout_of(msg: Any, topic: str) -> ScanLayout:
    return ScanLayout(topic=topic, frame=msg.header.frame_id.lstrip("/"), beams=len(msg.ranges),
                      angle_min=float(msg.angle_min), angle_increment=float(msg.angle_increment),
                      range_min=float(msg.range_min), range_max=float(msg.range_max),
                      time_increment=float(msg.time_increment), scan_time=float(msg.scan_time))


def layout_problem(layout: ScanLayout) -> str | None:
    """Why a scan's beams cannot be placed (None when they can)."""
    if layout.beams == 0:
        return "it has no beams"
    if not (math.isfinite(layout.angle_min) and math.isfinite(layout.angle_increment)):
        return (f"angle_min {layout.angle_min} / angle_increment {layout.angle_increment} is not a number, so the "
                f"beams' directions are unknown")
    if layout.beams > 1 and layout.angle_increment == 0:
        return "angle_increment is 0: every beam points the same way"
    if abs(layout.angle_increment) * (layout.beams - 1) > 2 * math.pi + 1e-3:
        return (f"{layout.beams} beams {math.degrees(layout.angle_increment):g} deg apart turn more than once "
                f"around")
    if not (layout.range_max > 0) or math.isnan(layout.range_min):
        return f"range_min {layout.range_min} / range_max {layout.range_max} leave no valid range"
    return None


@dataclass(frozen=True)
class ScanTiming:
    """When each beam was measured: beam ``i`` at ``stamp + offset + first + i * increment`` (s)."""
    increment: float = 0.0
    first: float = 0.0
    offset: float = 0.0
    how: str = "every beam at its scan's stamp"
    warnings: tuple[str, ...] = ()
    # when the scan's fields and the bag's receive times do not tell: the other readings, one of which
    # the sharper map may pick (projection.settle_timing)
    alternatives: tuple["ScanTiming", ...] = ()

    def beam_offsets(self, beams: int) -> np.ndarray:
        """(beams,) seconds of each beam after its scan's stamp (the user's offset included)."""
        return self.offset + self.first + self.increment * np.arange(beams)

    @property
    def skewed(self) -> bool:
        return self.increment != 0.0


def choose_timing(layout: ScanLayout, stamps: np.ndarray, received: np.ndarray, period: float,
                  stamp: str = "auto", offset: float = 0.0) -> ScanTiming:
    """The beams' timing from the layout's ``time_increment`` (else ``scan_time``), checked against
    the scans' ``period`` (s between scans); the stamp convention from ``stamp`` ("start": the
    stamp is when the scan began, "end": when it ended, "auto": from how long after its stamp the
    bag received each scan, ``received - stamps``)."""
    n, warnings = layout.beams, []
    cover = min(1.0, abs(layout.angle_increment) * n / (2 * math.pi))   # share of a turn the beams span
    ti, st = layout.time_increment, layout.scan_time
    if not math.isfinite(ti):
        warnings.append(f"{layout.topic}: time_increment is {ti}: ignored")
        ti = 0.0
    if not (math.isfinite(st) and st >= 0):
        warnings.append(f"{layout.topic}: scan_time is {st}: ignored")
        st = 0.0
    rate = f" ({1 / period:.3g} Hz)" if period > 0 else ""
    if ti != 0.0:
        inc, source = ti, f"time_increment {ti * 1e3:.4g} ms"
        if ti < 0:
            warnings.append(f"{layout.topic}: time_increment is negative ({ti * 1e3:.4g} ms): the beams were measured "
                            f"from the last in the array to the first; each is placed at its own time that way "
                            f"(stamp + i x time_increment, as laser_geometry does)")
        if period > 0 and abs(ti) * n > 1.05 * period:
            inc = math.copysign(period * cover / n, ti)
            warnings.append(f"{layout.topic}: time_increment {ti * 1e3:.4g} ms x {n} beams = {abs(ti) * n:.3g} s is "
                            f"longer than the scans' period {period:.3g} s{rate}, which cannot be: the beams are "
                            f"spread over the period instead ({abs(inc) * 1e3:.4g} ms apart)")
            source = f"the scans' period ({abs(inc) * 1e3:.4g} ms apart)"
    elif st > 0:
        # scan_time is the time between scans: a rotating lidar takes that long for a turn, a simulated
        # or solid-state one takes none. laser_geometry reads time_increment 0 as every beam at once;
        # spreading the beams over scan_time is the alternative that the sharper map may pick
        if period > 0 and st > 1.05 * period:
            warnings.append(f"{layout.topic}: scan_time {st:.3g} s is longer than the scans' period {period:.3g} s"
                            f"{rate}: the period is used instead")
            st = period
        inc = math.copysign(st * cover / n, layout.angle_increment or 1.0)
        spread = [dataclasses.replace(_timed(layout, inc, stamp_at, offset, received - stamps),
                                      how=f"beams spread over scan_time {st:.3g} s ({abs(inc) * 1e3:.4g} ms apart: "
                                          f"time_increment is 0), the stamp the scan's {stamp_at}")
                  for stamp_at in (("start", "end") if stamp == "auto" else (stamp,))]
        return ScanTiming(offset=offset, warnings=tuple(warnings), alternatives=tuple(spread), how=(
            f"every beam at its scan's stamp (time_increment is 0, scan_time {st:.3g} s: as laser_geometry reads it)"
            + (f", stamps moved by {offset:+g} s (--scan-time-offset)" if offset else "")))
    else:
        return ScanTiming(offset=offset, warnings=tuple(warnings), how=(
            "every beam at its scan's stamp (time_increment and scan_time are 0, as a simulator writes them)"
            + (f", stamps moved by {offset:+g} s (--scan-time-offset)" if offset else "")))
    timing = _timed(layout, inc, stamp, offset, received - stamps)
    return dataclasses.replace(timing, how=f"beams from {source}, {timing.how}", warnings=tuple(warnings))


def _timed(layout: ScanLayout, inc: float, stamp: str, offset: float, lags: np.ndarray) -> ScanTiming:
    """Beams ``inc`` seconds apart; the stamp the scan's start or end (``stamp``; "auto": from the
    bag's receive ``lags`` behind the stamps, else the ROS convention with the end as an alternative)."""
    span = abs(inc) * (layout.beams - 1)
    alternatives: tuple[ScanTiming, ...] = ()
    if stamp == "auto":
        lag = float(np.median(lags)) if len(lags) else math.nan
        if math.isfinite(lag) and 0.0 <= lag < 0.5 * span:
            stamp, why = "end", (f"the bag received each scan {lag:.3g} s after its stamp, sooner than the scan "
                                 f"takes ({span:.3g} s): the stamp is the scan's end")
        elif math.isfinite(lag) and span <= lag <= 2.0:
            stamp, why = "start", (f"the bag received each scan {lag:.3g} s after its stamp, after the scan's "
                                   f"{span:.3g} s: the stamp is the scan's start (the ROS convention)")
        else:
            unclear = "the bag's receive times do not tell" + (f" (received {lag:+.3g} s after the stamp)"
                                                               if math.isfinite(lag) else "")
            end = _timed(layout, inc, "end", offset, lags)
            alternatives = (dataclasses.replace(end, how=end.how.replace(
                "the stamp is the scan's end (--scan-stamp end)", f"{unclear}: the stamp taken as the scan's end")),)
            stamp, why = "start", f"{unclear}: the stamp taken as the scan's start (the ROS convention)"
    else:
        why = f"the stamp is the scan's {stamp} (--scan-stamp {stamp})"
    # the scan runs from the stamp on (start) or up to it (end); beam 0 is the earliest when inc > 0
    first = (0.0 if inc > 0 else span) if stamp == "start" else (-span if inc > 0 else 0.0)
    how = (f"{span:.3g} s a scan; {why}" + (f"; stamps moved by {offset:+g} s (--scan-time-offset)" if offset else ""))
    return ScanTiming(increment=inc, first=first, offset=offset, how=how, alternatives=alternatives)


@dataclass
class ScanBatch:
    """Scans of one layout: stamps (k,) in s on the odometry's clock (offset not applied) and
    ranges (k, beams) in m."""
    t: np.ndarray
    ranges: np.ndarray


@dataclass
class StreamStats:
    """What the streamed pass saw: scans used, skipped (another layout, outside the odometry, in
    an odometry gap) and where."""
    used: int = 0
    other_layout: int = 0
    outside: int = 0
    in_gap: int = 0
    gap_spans: list[tuple[float, float]] = field(default_factory=list)
