# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How to fit background vibration (the law: :mod:`prsm_lube_ros.physics.effects.background_vibration`).

``A = sqrt(A_22^2 + B^2)``; B shows most at low speed.  Its forms differ in
the spectrum only: lines at fixed frequencies, a broadband floor, or both
(:meth:`BackgroundVibrationCandidate.form_name` compares the lines' power with B^2).  Parameter: B (m/s^2),
at least the RMS of the fixed lines the spectrum measures and of the vibration at standstill (the larger);
internally the rest of B (added in power) over the smallest RMS recorded.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ...physics.effects import background_vibration as law
from ..locate import fixed_line_power, SHAPE_NOISE_FACTOR
from .base import Effect, register

if TYPE_CHECKING:
    from ..locate import Location
    from ..table import WindowTable

__all__ = ['BackgroundVibrationCandidate', 'FRACTION_RANGE', 'LINE_SHARE', 'MIN_LINE_SHARE', 'QUIET_QUANTILE',
           'REST_SHARE', 'SHAPE_CONTRARY_FACTOR', 'STANDSTILL_CONTRARY_SHARE', 'SHAPE_MIN_EXPECTED', 'SHAPE_STRUCTURE',
           'rest_share']

#: Bounds of B over the smallest recorded RMS.
FRACTION_RANGE = (0.0, 1.5)
#: Smallest share of the power at the lowest speed in fixed spectral lines that counts as evidence.
MIN_LINE_SHARE = 1e-3
#: Smallest share of the quietest running windows' power that the vibration at standstill must carry to count
#: as evidence: enough to lift their amplitude by about 2.5 %, beyond what a sensor's noise floor does.
REST_SHARE = 0.05
#: The quietest running windows: this quantile of the window RMS.
QUIET_QUANTILE = 0.1
#: Share of the fitted background power B^2 the fixed lines must carry to name the form "lines" alone.
LINE_SHARE = 0.4
#: Largest power at standstill, as a share of the fitted B^2, that contradicts the fit: B more than twice the RMS
#: read with the screw still (6 dB, beyond what fitting B from a few speeds leaves uncertain).
STANDSTILL_CONTRARY_SHARE = 0.25
#: Contrary evidence: the highest speed's spectral shape differs from white by at least this total variation ...
SHAPE_STRUCTURE = 0.2
#: ... and the shape change a white background would cause is this many times what is seen ...
SHAPE_CONTRARY_FACTOR = 5.0
#: ... and at least this total variation.
SHAPE_MIN_EXPECTED = 0.1


@register
class BackgroundVibrationCandidate(Effect, law.Extension):
    """Vibration from elsewhere adds in power; at low speed the amplitude stops following the model."""

    id = 'background_vibration'
    title = 'background vibration'
    physics = ('Vibration that does not come from the thread contacts (motor, bearings, frame) adds in power, '
               'A^2 = A_22^2 + B^2; it does not follow the screw speed, so at low speed the amplitude stops '
               'falling with omega^2 as the model says.')
    equations = 'A = sqrt(A_22^2 + B^2)'
    parameter_names = ('background_fraction',)
    covariate = 'speed'
    adds_power = True
    form = law.FORMS[0]
    to_separate = ('lower screw speeds (the background dominates there), a record at standstill with the drive '
                   'on, and vibration spectra')

    def scales(self, table: WindowTable) -> dict[str, float]:
        """Smallest recorded RMS, the RMS of the fixed lines the spectrum measures and that at standstill, m/s^2.

        ``rest_rms`` is the table's figure at standstill when it counts
        (:data:`REST_SHARE` of the quietest running power, :func:`rest_share`), else 0.
        """
        rest = table.rest_rms if self.standstill_evidence(table) else 0.0
        return {'rms_scale': float(np.min(table.rms)), 'line_rms': math.sqrt(fixed_line_power(table)),
                'rest_rms': float(rest)}

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The part of B beyond the fixed lines, over min RMS, in :data:`FRACTION_RANGE`."""
        return np.array([FRACTION_RANGE[0]]), np.array([FRACTION_RANGE[1]])

    def starts(self) -> list[np.ndarray]:
        """Small to large backgrounds."""
        return [np.array([0.1]), np.array([0.3]), np.array([0.6])]

    def to_params(self, p: np.ndarray, scales: dict[str, float]) -> dict[str, float]:
        """background_rms B (m/s^2): what was measured (lines, standstill) and the fitted rest added in power.

        Lines at fixed frequencies with constant power, and vibration with the
        screw still, are vibration from elsewhere measured directly, so B is
        never fitted below the larger of the two (a fit that would rather give
        their power to the contact law, with a negative C_lambda say, or to a
        resonance, cannot).  Vibration at standstill that running does not
        carry (a servo dithering to hold position, say) then makes the fit
        worse, and the background does not earn.
        """
        measured = max(scales.get('line_rms', 0.0), scales.get('rest_rms', 0.0))
        return {'background_rms': float(math.hypot(measured, p[0] * scales['rms_scale'])), **scales}

    def spectral_evidence(self, table: WindowTable, location: Location | None,
                          params: dict[str, float] | None = None, beside: Effect | None = None) -> str:
        """Fixed lines of constant power (:data:`MIN_LINE_SHARE`) or a spectral shape change.

        Power added from elsewhere with a spectrum of its own changes the
        shape of the recorded spectrum between the lowest and the highest speed;
        whatever multiplies the whole response does not.  A band fixed in Hz whose
        power follows the speed (a mode the orders pass) changes the shape too,
        beyond the octave around it that the shape leaves out: with such a band
        located, or ``beside`` an effect whose law changes the shape by itself
        (a resonance, located or not), a changing shape is no evidence of added
        power.
        """
        lines = location.spectrum if location is not None else None
        if lines is not None and lines.frequencies and lines.share_at_lowest_speed >= MIN_LINE_SHARE:
            return 'spectrum: ' + lines.note
        shape = getattr(location, 'shape', None)
        shaped = ((lines is not None and lines.mode_frequencies)
                  or (beside is not None and beside.changes_spectral_shape))
        if shape is not None and shape.floor_added and not shaped:
            return 'spectrum: ' + shape.note
        return ''

    def standstill_evidence(self, table: WindowTable) -> str:
        """Vibration at standstill carrying :data:`REST_SHARE` of the quietest running power (B is fitted above it).

        Vibration the accelerometer reads with the screw still
        (:attr:`.table.WindowTable.rest_rms`) is power from elsewhere measured
        directly, when it carries :data:`REST_SHARE` of the quietest running
        windows' power (:func:`rest_share`); B is then never fitted below it
        (:meth:`to_params`).  A resonance or any law of the contacts puts it at
        zero, so it counts beside any effect.
        """
        share = rest_share(table)
        if not share >= REST_SHARE:
            return ''
        return (f'standstill: with the screw still the accelerometer reads {table.rest_rms:.3g} m/s^2 RMS '
                f'(median of {table.rest_windows} windows), {100 * share:.0f} % of the power of the quietest '
                'running windows, which the contact law puts at zero')

    def measured_against(self, table: WindowTable, params: dict[str, float],
                         predicted: np.ndarray | None = None) -> str:
        """The screw still, the accelerometer reads far less than the fitted B (:data:`STANDSTILL_CONTRARY_SHARE`).

        Vibration from elsewhere is there whenever the rig is powered, at
        standstill too (a source that stops with the screw turns with it, and
        follows its speed: another law).  With the standstill measured
        (:attr:`.table.WindowTable.rest_rms`, over enough windows) and its power
        below :data:`STANDSTILL_CONTRARY_SHARE` of B^2, the fitted B is power the
        recording shows is not there: what it fits is some law of speed the
        contacts make (a mode every speed is past, whose amplitude flattens as
        a floor's does).
        """
        b = params.get('background_rms', math.nan)
        rest = table.rest_rms
        if not (math.isfinite(rest) and b > 0 and rest ** 2 < STANDSTILL_CONTRARY_SHARE * b ** 2):
            return ''
        return (f'standstill: with the screw still the accelerometer reads {rest:.3g} m/s^2 RMS (median of '
                f'{table.rest_windows} windows), {100 * rest ** 2 / b ** 2:.1f} % of the power of the fitted '
                f'background (B = {b:.3g} m/s^2), which vibration from elsewhere would keep there')

    def contrary_evidence(self, table: WindowTable, location: Location | None,
                          params: dict[str, float] | None = None) -> str:
        """The spectral shape keeps although the fitted B's share of the power differs between the speeds.

        A background with a spectrum unlike the contact's (white, say) whose
        share changes by ds between the lowest and highest speed moves the shape
        by about ds times the highest speed's distance from white; when that is
        :data:`SHAPE_CONTRARY_FACTOR` times what is seen (or the noise), the
        fitted background is not in the spectrum.  The shape at the highest speed
        must have structure (:data:`SHAPE_STRUCTURE` from white): a background
        with the contact's own spectral shape cannot be told by the spectrum,
        and is not argued against; nor is one when the spectrum holds fixed lines
        (the shape's band medians step over lines).
        """
        shape, lines = getattr(location, 'shape', None), getattr(location, 'spectrum', None)
        if params is None or shape is None or not shape.testable or shape.changes or shape.structure < SHAPE_STRUCTURE:
            return ''
        if lines is not None and (lines.frequencies or lines.mode_frequencies):
            return ''                  # power in lines, which the band medians of the shape step over
        from ...estimation.calibration import operating_levels
        levels = np.array(operating_levels(table.speed))
        index = np.argmin(np.abs(np.abs(table.speed)[:, None] - levels[None, :]), axis=1)
        square = [float(np.mean(table.rms[index == i] ** 2)) for i in (int(np.argmin(levels)), int(np.argmax(levels)))]
        shares = [min(params['background_rms'] ** 2 / m, 1.0) for m in square]
        # A white background changing its share by this much would move the shape by about this much.
        expected = abs(shares[0] - shares[1]) * shape.structure
        seen = max(shape.distance, SHAPE_NOISE_FACTOR * shape.noise)
        if expected < max(SHAPE_CONTRARY_FACTOR * seen, SHAPE_MIN_EXPECTED):
            return ''
        return (f'spectrum: the fitted background would carry {100 * shares[0]:.0f} % of the power at the lowest '
                f'speed and {100 * shares[1]:.0f} % at the highest, yet {shape.note}')

    def form_name(self, params: dict[str, float], table: WindowTable, location: Location | None) -> str:
        """Lines, floor or both, from the spectrum: lines carrying less than :data:`LINE_SHARE` of B^2 leave a floor.

        Without spectra (or with one speed) the form cannot be told.  The absence of
        lines is no evidence against a background: a broadband floor has none.
        """
        lines = location.spectrum if location is not None else None
        if lines is None or not lines.testable:
            return 'form not known (no spectra at two speeds or more): lines or broadband floor'
        if not lines.frequencies:
            return law.FORMS[1]
        if lines.total_power >= LINE_SHARE * params['background_rms'] ** 2:
            return law.FORMS[0]
        return law.FORMS[2]

    def describe(self, params: dict[str, float]) -> str:
        """B and its share of the smallest RMS."""
        b = params['background_rms']
        return (f'Background of B = {b:.4g} m/s^2 RMS, {100 * b / params["rms_scale"]:.0f} % of the smallest '
                'window RMS recorded. ' + self.physics)


def rest_share(table: WindowTable) -> float:
    """Power at standstill over that of the quietest running windows (:data:`QUIET_QUANTILE`); 0 if not recorded."""
    quiet = float(np.quantile(table.rms, QUIET_QUANTILE)) if len(table.rms) else math.nan
    if not (math.isfinite(table.rest_rms) and quiet > 0):
        return 0.0
    return table.rest_rms ** 2 / quiet ** 2
