# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Diagnostic level of one actuator's surface condition, live: the defect screen on its last steady windows.

Pure logic, no ROS import, as :mod:`.health` is for the lubrication: the
estimator node hands each steady window's
:class:`~.condition_indicators.ConditionIndicators` to a
:class:`SurfaceMonitor` and turns :meth:`SurfaceMonitor.status` into a second
``DiagnosticStatus`` per actuator.  The rules:

* the last ``windows`` steady windows with indicators form a rolling group
  (across runs: a short traverse alone holds too few windows, and orders are
  multiples of the screw speed, so windows of different speeds pool);
  :func:`~.defect_screen.run_condition` pools them as a run of ``assess`` is
  pooled, and :func:`~.defect_screen.screen` judges the pool against the
  calibration's healthy :class:`~.defect_screen.ConditionBaseline` (without
  one, the absolute limits only).  One window alone is not judged: the
  envelope spectrum of a single window of Gaussian vibration reaches 10 dB
  over its floor somewhere about once in a thousand bins, the average of 10
  windows practically never;
* until the group is full the status is OK "not screened yet";
* a suspected defect is ERROR at once and clears only after ``windows``
  clean judgements in a row (every window that raised it has left the group),
  so a defect at the threshold does not flap the level;
* a new calibration (a new baseline) judges afresh: the latch is dropped and
  the group judged again at once if it is full (its windows are dropped too
  when the analysis band changed, since the indicators are of the band);
* steady windows without indicators (a calibration of the raw RMS, written
  before analysis bands) cannot be screened: WARN "not screened", calibrate again.

Messages stay the same while the state does (no window-by-window numbers):
the defect order in the message is the component's nominal order, the
measured line, kurtosis, crest factor and the evidence in full are in
:class:`SurfaceStatus` for the KeyValues.  :func:`withheld` is what the
lubrication status says meanwhile: theta_Oil is no lubrication measure while
a surface defect is suspected (a spall raises the band RMS as oil loss does).
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, replace
import math
from typing import TYPE_CHECKING

from ..errors import InputError
from .defect_screen import (below_unexplained, DEFAULT_RULES, DefectFinding, NOT_SUSPECTED, run_condition, screen,
                            screen_limits, strike_line, unexplained_level)
from .health import ERROR, LEVEL_NAMES, OK, STALE, WARN

if TYPE_CHECKING:
    from collections.abc import Sequence

    from ..physics.defect_orders import DefectOrder
    from .condition_indicators import ConditionIndicators
    from .defect_screen import ConditionBaseline, DefectRules, RunCondition
    from .health import HealthStatus

__all__ = ['DEFAULT_DEFECT_WINDOWS', 'NOT_A_MEASURE', 'SurfaceMonitor', 'SurfaceStatus', 'defect_orders_text',
           'kurtosis_limit', 'nominal_order', 'surface_message', 'withheld']

#: Steady windows pooled for the live defect screen (10 s of 1 s windows, as a short run of ``assess``).
DEFAULT_DEFECT_WINDOWS = 10
#: What a suspected defect means for theta_Oil, in the words of the status messages.
NOT_A_MEASURE = 'theta_Oil is not a lubrication measure while it lasts'


@dataclass(frozen=True)
class SurfaceStatus:
    """What the surface condition status says right now."""

    level: int
    message: str
    suspected: bool                 # a surface defect is suspected (latched, see module doc)
    finding: DefectFinding          # the suspicion's evidence while suspected, else the last judgement
    condition: RunCondition | None  # the last pooled indicators judged (None before the first)
    windows: int                    # steady windows in the group now
    kurtosis_limit: float           # kurtosis beyond which the pool counts as impulsive
    since: float = math.nan         # end (s since the epoch) of the window that raised the suspicion
    clean: int = 0                  # clean judgements in a row while suspected


def kurtosis_limit(baseline: ConditionBaseline | None, rules: DefectRules = DEFAULT_RULES) -> float:
    """Kurtosis from which :func:`~.defect_screen.screen` calls a pool impulsive (its first rule)."""
    return screen_limits(baseline, rules)[0]


def nominal_order(component: str, orders: Sequence[DefectOrder]) -> float:
    """The defect order of ``component`` ('a or b' names a shared order) among ``orders``; NaN if none."""
    names = component.split(' or ')
    return next((o.order for o in orders if o.component in names), math.nan)


def defect_orders_text(orders: Sequence[DefectOrder]) -> str:
    """The orders as a KeyValue: ``screw raceway 6.25, nut raceway 3.75, ...`` ('none' when empty)."""
    return ', '.join(f'{o.component} {o.order:.4g}' for o in orders) or 'none'


def _order_words(component: str, order: float, orders: Sequence[DefectOrder]) -> str:
    """``6.25x screw speed`` for a line of ``component`` (the nominal order: stable while the state is)."""
    nominal = nominal_order(component, orders)
    return f'{nominal if math.isfinite(nominal) else order:.3g}x screw speed'


def surface_message(finding: DefectFinding, condition: RunCondition, orders: Sequence[DefectOrder],
                    limit: float, rules: DefectRules = DEFAULT_RULES) -> str:
    """The status message of a judgement: the state and the component, no number that changes window by window."""
    impulsive = math.isfinite(condition.kurtosis) and condition.kurtosis >= limit
    if finding.suspected:
        if finding.component and finding.evidence.startswith('impulsive'):
            return (f'impulsive at {_order_words(finding.component, finding.order, orders)}: {finding.component} '
                    f'defect suspected; {NOT_A_MEASURE}')
        if finding.component:
            return (f'envelope line at {_order_words(finding.component, finding.order, orders)}: '
                    f'{finding.component} defect suspected; {NOT_A_MEASURE}')
        return ('impulsive vibration with no envelope line at a defect order: surface defect suspected; '
                f'{NOT_A_MEASURE}')
    line = strike_line(condition.envelope_peaks, orders, condition.order_resolution)   # the line the screen judged
    line = line if line is not None and line.db >= rules.envelope_db else None
    if impulsive:
        return f'no surface defect: impulsive (kurtosis above {limit:.1f}) but no envelope line at a defect order'
    if line is not None:
        why = ('below a line at an order no component explains'
               if below_unexplained(line.db, unexplained_level(condition.envelope_peaks), rules)
               else 'within what the healthy runs show')
        return (f'no surface defect: kurtosis below {limit:.1f}; the envelope line at '
                f'{_order_words(line.component, line.order, orders)} ({line.component}) is {why}')
    return f'no surface defect: kurtosis below {limit:.1f}, no envelope line at a defect order'


class SurfaceMonitor:
    """Level and message of one actuator's surface condition, updated window by window (see module doc)."""

    def __init__(self, orders: Sequence[DefectOrder], windows: int = DEFAULT_DEFECT_WINDOWS,
                 rules: DefectRules = DEFAULT_RULES):
        self.orders = tuple(orders)
        self.rules = rules
        self._group: deque[ConditionIndicators] = deque(maxlen=_checked_windows(windows))
        self._baseline: ConditionBaseline | None = None
        self._condition: RunCondition | None = None
        self._finding = NOT_SUSPECTED
        self._suspected = False
        self._since = math.nan
        self._clean = 0
        self._unscreenable = ''
        self._last_end = math.nan
        self._message = self._not_yet()

    @property
    def windows(self) -> int:
        """Steady windows pooled for a judgement."""
        return int(self._group.maxlen or 1)

    @property
    def suspected(self) -> bool:
        """Whether a surface defect is suspected now."""
        return self._suspected

    @property
    def judged(self) -> bool:
        """Whether a judgement stands (the group was full once since start or the last calibration)."""
        return self._condition is not None

    @property
    def pending(self) -> bool:
        """Whether steady windows with indicators come in but the group has not been judged yet."""
        return self.pending_with(False)

    def pending_with(self, incoming: bool) -> bool:
        """:attr:`pending`, counting a steady window with indicators on its way (``incoming``) as come in.

        A live node publishes a window's theta_Oil before its indicators reach
        the screen: the first window after start is pending as the screen will
        be, and so is the first after a calibration without a band (nothing
        screenable) gave way to one with a band.
        """
        return self._condition is None and (incoming or (bool(self._group) and not self._unscreenable))

    @property
    def baseline(self) -> ConditionBaseline | None:
        """The healthy baseline judged against (None: the absolute limits only)."""
        return self._baseline

    def _not_yet(self) -> str:
        return f'not screened yet: fewer than {self.windows} steady windows (defect_windows)'

    def set_windows(self, windows: int) -> None:
        """Pool ``windows`` windows from now on (the newest are kept); the next window is judged on them."""
        self._group = deque(self._group, maxlen=_checked_windows(windows))
        if self._condition is None:
            self._message = self._not_yet()

    def set_baseline(self, baseline: ConditionBaseline | None, keep_windows: bool = True) -> None:
        """A new calibration's baseline: judge afresh (latch dropped), at once when the group is full.

        ``keep_windows`` False drops the group too (the analysis band changed, so
        did the indicators).
        """
        self._baseline = baseline
        self._suspected, self._since, self._clean = False, math.nan, 0
        self._finding, self._condition = NOT_SUSPECTED, None
        if not keep_windows:
            self._group.clear()
        self._message = self._not_yet()
        self._judge(self._last_end)

    def observe(self, indicators: ConditionIndicators | None, end: float = math.nan) -> None:
        """Take one steady window's indicators (None: the window has none) ending at ``end`` (s)."""
        if indicators is None:
            self._unscreenable = ('steady windows carry no condition indicators (a calibration of the raw RMS, '
                                  'written before analysis bands); calibrate again')
            return
        self._unscreenable = ''
        if not math.isfinite(indicators.kurtosis):
            return   # too few samples or no band: nothing to pool
        self._group.append(indicators)
        self._last_end = end
        self._judge(end)

    def _judge(self, end: float) -> None:
        if len(self._group) < self.windows:
            return
        condition = run_condition(list(self._group), self.orders)
        finding = screen(condition, self.orders, self._baseline, self.rules)
        self._condition = condition
        if finding.suspected:
            if not self._suspected:
                self._since = end
            self._suspected, self._finding, self._clean = True, finding, 0
        elif self._suspected:
            self._clean += 1
            if self._clean >= self.windows:
                self._suspected, self._since, self._clean = False, math.nan, 0
        if not self._suspected:
            self._finding = finding
        self._message = surface_message(self._finding, condition, self.orders,
                                        kurtosis_limit(self._baseline, self.rules), self.rules)

    def status(self, stale: str = '') -> SurfaceStatus:
        """Level and message now; ``stale`` (why the inputs count as stopped) makes it STALE."""
        if self._suspected:
            level = ERROR
        elif self._unscreenable and self._condition is None:
            level = WARN
        else:
            level = OK
        message = f'not screened: {self._unscreenable}' if level == WARN else self._message
        if stale:
            last = '' if self._condition is None else f'; last level {LEVEL_NAMES[level]}'
            level, message = STALE, stale + last
        return SurfaceStatus(level, message, self._suspected, self._finding, self._condition, len(self._group),
                             kurtosis_limit(self._baseline, self.rules), self._since, self._clean)


def _checked_windows(windows: int) -> int:
    if not (isinstance(windows, int) and not isinstance(windows, bool) and windows >= 1):
        raise InputError(f'defect_windows={windows!r} must be an integer >= 1')
    return windows


def withheld(status: HealthStatus, surface: SurfaceStatus, pending: bool = False) -> HealthStatus:
    """The lubrication ``status`` as the surface screen allows it to be read (STALE stays as it is).

    While a surface defect is suspected: WARN, theta_Oil withheld; never
    "lubrication insufficient" or "degraded", since the vibration that would
    say so is the defect's.  While the screen is ``pending`` (steady windows
    with indicators come in, fewer than a group so far: the first
    ``defect_windows`` after start or a change of band), a theta level worse
    than OK is WARN "not yet judged": a spall at start-up would otherwise read
    as oil loss until its first judgement.  A single window is not judged
    instead: alone, the envelope of healthy vibration shows a line at a
    defect order too often (module doc).
    """
    if status.level == STALE:
        return status
    if not surface.suspected:
        if pending and status.theta_level in (WARN, ERROR) and status.level in (WARN, ERROR):
            return replace(status, level=WARN,
                           message='lubrication not yet judged: theta_oil is below a threshold, but the surface '
                                   'screen has not yet had defect_windows steady windows to tell a surface defect '
                                   'from oil loss')
        return status
    what = f'{surface.finding.component} defect' if surface.finding.component else 'surface defect'
    return replace(status, level=WARN,
                   message=f'theta_oil withheld: {what} suspected (see the surface condition status); '
                           f'{NOT_A_MEASURE}')
