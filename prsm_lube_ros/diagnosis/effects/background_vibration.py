# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How to fit background vibration (the law: :mod:`prsm_lube_ros.physics.effects.background_vibration`).

``A = sqrt(A_22^2 + B^2)``; B shows most at low speed and, in the spectrum, as
lines at fixed frequencies.  Parameter: B (m/s^2); internally B over the
smallest RMS recorded.
"""
from __future__ import annotations

import numpy as np

from ...physics.effects import background_vibration as law
from .base import Effect, register

#: Bounds of B over the smallest recorded RMS.
FRACTION_RANGE = (0.0, 1.5)
#: Smallest share of the power at the lowest speed in fixed spectral lines that counts as evidence.
MIN_LINE_SHARE = 1e-3


@register
class BackgroundVibration(Effect, law.Extension):
    """Vibration from elsewhere adds in power; at low speed the amplitude stops following the model."""

    id = 'background_vibration'
    title = 'background vibration'
    physics = ('Vibration that does not come from the thread contacts (motor, bearings, frame) adds in power, '
               'A^2 = A_22^2 + B^2; it does not follow the screw speed, so at low speed the amplitude stops '
               'falling with omega^2 as the model says.')
    equations = 'A = sqrt(A_22^2 + B^2)'
    parameter_names = ('background_fraction',)
    covariate = 'speed'
    to_separate = ('lower screw speeds (the background dominates there), a record at standstill with the drive '
                   'on, and vibration spectra')

    def scales(self, table) -> dict:
        """Smallest recorded RMS, m/s^2."""
        return {'rms_scale': float(np.min(table.rms))}

    def bounds(self):
        """B / min RMS in :data:`FRACTION_RANGE`."""
        return np.array([FRACTION_RANGE[0]]), np.array([FRACTION_RANGE[1]])

    def starts(self):
        """Small to large backgrounds."""
        return [np.array([0.1]), np.array([0.3]), np.array([0.6])]

    def to_params(self, p, scales):
        """background_rms B (m/s^2)."""
        return {'background_rms': float(p[0] * scales['rms_scale']), **scales}

    def independent_evidence(self, table, location) -> str:
        """Fixed-frequency spectral lines with constant power, at least :data:`MIN_LINE_SHARE` of the power."""
        lines = location.spectrum if location is not None else None
        if lines is None or not lines.frequencies or lines.share_at_lowest_speed < MIN_LINE_SHARE:
            return ''
        return 'spectrum: ' + lines.note

    def contrary_evidence(self, table, location) -> str:
        """The spectra could show fixed lines (two speeds or more) and show none."""
        lines = location.spectrum if location is not None else None
        if lines is None or not lines.testable or lines.frequencies:
            return ''
        return 'the spectra show no fixed-frequency line, the usual mark of motor, bearing or frame vibration'

    def describe(self, params):
        """B and its share of the smallest RMS."""
        b = params['background_rms']
        return (f'Background of B = {b:.4g} m/s^2 RMS, {100 * b / params["rms_scale"]:.0f} % of the smallest '
                'window RMS recorded. ' + self.physics)
