# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Drive program of the simulated rig: screw motion and applied load as piecewise polynomials of time."""
from __future__ import annotations

from dataclasses import asdict, dataclass
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..validation import require
from .rig_config import ExperimentPlan, RigConfig

if TYPE_CHECKING:
    import numpy.typing as npt


__all__ = ['DriveProgram', 'Stroke', 'append_stroke', 'schedule_session']


# ---------------------------------------------------------------------------------------------
# Drive program: screw motion and applied load as piecewise polynomials of time
# ---------------------------------------------------------------------------------------------
class DriveProgram:
    """Screw angle/speed (constant-acceleration phases) and applied load (linear phases) over time.

    Times are s since simulated time zero.  Each phase holds until the next
    begins; the last holds for ever.  Angle and speed are continuous, so the
    angle is the exact integral of the speed.
    """

    def __init__(self, angle: float = 0.0):
        """Standstill at ``angle`` (rad) and no load from time zero."""
        self._motion = [[0.0], [float(angle)], [0.0], [0.0]]   # start, angle, speed, acceleration
        self._load = [[0.0], [0.0], [0.0]]                      # start, load, rate
        self._arrays: tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]] | None = None
        self.traverse_starts: list[float] = []                  # s, start of every stroke appended

    def _tables(self) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
        """The phase tables as arrays (motion, load), made again after each change."""
        if self._arrays is None:
            self._arrays = (tuple(np.array(column) for column in self._motion),
                            tuple(np.array(column) for column in self._load))
        return self._arrays

    def motion(self, times: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Screw angle in rad and speed in rad/s at ``times`` (s)."""
        (start, angle, speed, accel), _ = self._tables()
        times = np.asarray(times, dtype=float)
        index = np.clip(np.searchsorted(start, times, side='right') - 1, 0, None)
        dt = times - start[index]
        return (angle[index] + speed[index] * dt + 0.5 * accel[index] * dt * dt,
                speed[index] + accel[index] * dt)

    def load(self, times: npt.ArrayLike) -> np.ndarray:
        """Applied axial load in N at ``times`` (s)."""
        _, (start, load, rate) = self._tables()
        times = np.asarray(times, dtype=float)
        index = np.clip(np.searchsorted(start, times, side='right') - 1, 0, None)
        return load[index] + rate[index] * (times - start[index])

    def append_motion(self, start: float, acceleration: float, speed: float | None = None) -> None:
        """New phase from ``start``; angle continuous, speed continuous unless given (exact end of a ramp)."""
        self._truncate(self._motion, start)
        angle, current = (float(v) for v in self.motion(start))
        self._arrays = None
        for column, value in zip(self._motion, (start, angle, current if speed is None else speed,
                                                acceleration)):
            column.append(float(value))

    def append_load(self, start: float, rate: float, load: float | None = None) -> None:
        """New load phase from ``start`` with ``rate`` in N/s; load continuous unless given."""
        self._truncate(self._load, start)
        current = float(self.load(start))
        self._arrays = None
        for column, value in zip(self._load, (start, current if load is None else load, rate)):
            column.append(float(value))

    def _truncate(self, table: list[list[float]], start: float) -> None:
        """Drop phases that begin at or after ``start`` (later commands replace planned ones)."""
        keep = sum(1 for begin in table[0] if begin < start) or 1
        if keep < len(table[0]):
            for column in table:
                del column[keep:]
            self._arrays = None

    def forget_before(self, time: float) -> None:
        """Drop phases that ended before ``time`` (keeps a long-running live program small)."""
        for table in (self._motion, self._load):
            active = max(sum(1 for begin in table[0] if begin <= time) - 1, 0)
            if active:
                for column in table:
                    del column[:active]
                self._arrays = None

    def command_speed(self, now: float, target: float, acceleration: float) -> None:
        """Ramp the screw speed from ``now`` to ``target`` (rad/s) at ``acceleration`` (rad/s^2)."""
        _, current = (float(v) for v in self.motion(now))
        if current == target:
            self.append_motion(now, 0.0, target)
            return
        duration = abs(target - current) / acceleration
        self.append_motion(now, math.copysign(acceleration, target - current))
        self.append_motion(now + duration, 0.0, target)

    def command_load(self, now: float, target: float, rate: float) -> None:
        """Ramp the applied load from ``now`` to ``target`` (N) at ``rate`` (N/s)."""
        current = float(self.load(now))
        if current == target or rate <= 0:
            self.append_load(now, 0.0, target)
            return
        self.append_load(now, math.copysign(rate, target - current))
        self.append_load(now + abs(target - current) / rate, 0.0, target)


@dataclass(frozen=True)
class Stroke:
    """One traverse of the nut in the schedule (times in s since simulated time zero)."""

    kind: str            # 'forward' (measured run under load), 'return' (back under load) or 'rewind' (load off)
    speed: float         # rad/s, signed (rewind negative)
    load: float          # N, applied (0 for rewind)
    start: float         # s, motion starts
    end: float           # s, motion ends
    steady_start: float  # s, acceleration ramp ends
    steady_end: float    # s, deceleration ramp starts

    def as_dict(self, origin: float) -> dict:
        """Mapping with times in s since the Unix epoch (``origin`` = stamp of time zero)."""
        result = asdict(self)
        for key in ('start', 'end', 'steady_start', 'steady_end'):
            result[key] = origin + result[key]
        return result


def append_stroke(program: DriveProgram, start: float, speed: float, travel: float, ramp_travel: float,
                  lead: float, load: float = 0.0, kind: str = 'forward') -> Stroke:
    """Trapezoidal speed profile moving the nut by ``travel`` (m) at ``speed`` (rad/s, signed).

    Constant acceleration over ``ramp_travel`` (m) at each end, so the ramp
    takes ``t = 2 theta_r / |omega|`` with ``theta_r = 2 pi ramp_travel / lead``.
    """
    total = 2.0 * math.pi * travel / lead
    ramp = 2.0 * math.pi * ramp_travel / lead
    ramp_time = 2.0 * ramp / abs(speed)
    cruise_time = (total - 2.0 * ramp) / abs(speed)
    acceleration = speed / ramp_time
    steady_start, steady_end = start + ramp_time, start + ramp_time + cruise_time
    end = steady_end + ramp_time
    program.append_motion(start, acceleration, 0.0)
    program.append_motion(steady_start, 0.0, speed)
    program.append_motion(steady_end, -acceleration, speed)
    program.append_motion(end, 0.0, 0.0)
    program.traverse_starts.append(float(start))
    return Stroke(kind, float(speed), float(load), start, end, steady_start, steady_end)


def schedule_session(program: DriveProgram, start: float, conditions: Sequence[tuple[float, float]],
                     plan: ExperimentPlan, rig: RigConfig) -> tuple[list[Stroke], float]:
    """One session from ``start`` (s): standstill, then per condition a forward run and a rewind.

    The load actuator ramps the load up in the ``load_ramp_time`` before each
    forward run and down after it; rewinds run unloaded at ``-rewind_speed``.
    With ``plan.return_under_load`` the nut comes back at the run's speed under
    its load instead (a ``'return'`` stroke: out and back both measured), and
    the load ramps down after the return.  After every ``plan.cool_down_every``
    runs the rig stands still ``plan.cool_down_pause`` s more (the nut cools).
    Returns the strokes and the end time (after a final standstill).
    """
    require(rig.load_ramp_time <= plan.standstill,
            f'rig load_ramp_time {rig.load_ramp_time} s must not exceed plan standstill {plan.standstill} s')
    lead = rig.actuator.lead
    strokes = []
    now = start + plan.standstill
    for number, (speed, load) in enumerate(conditions):
        if number and plan.cool_down_every and number % plan.cool_down_every == 0:
            now += plan.cool_down_pause
        if rig.load_ramp_time > 0:
            program.append_load(now - rig.load_ramp_time, load / rig.load_ramp_time, 0.0)
        program.append_load(now, 0.0, load)
        run = append_stroke(program, now, speed, plan.stroke, plan.ramp_travel, lead, load, 'forward')
        if plan.return_under_load:
            back = append_stroke(program, run.end + plan.standstill, -speed, plan.stroke, plan.ramp_travel, lead,
                                 load, 'return')
            if rig.load_ramp_time > 0:
                program.append_load(back.end, -load / rig.load_ramp_time, load)
            program.append_load(back.end + rig.load_ramp_time, 0.0, 0.0)
            strokes += [run, back]
            now = back.end + plan.standstill
            continue
        if rig.load_ramp_time > 0:
            program.append_load(run.end, -load / rig.load_ramp_time, load)
        program.append_load(run.end + rig.load_ramp_time, 0.0, 0.0)
        rewind = append_stroke(program, run.end + plan.standstill, -plan.rewind_speed, plan.stroke,
                               plan.ramp_travel, lead, 0.0, 'rewind')
        strokes += [run, rewind]
        now = rewind.end + plan.standstill
    return strokes, now
