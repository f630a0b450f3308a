# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How to fit background vibration (the law: :mod:`prsm_lube_ros.physics.effects.background_vibration`).

``A = sqrt(A_22^2 + B^2)``; B shows most at low speed.  Its forms differ in
the spectrum only: lines at fixed frequencies, a broadband floor, or both
(:meth:`BackgroundVibration.form_name` compares the lines' power with B^2).  Parameter: B (m/s^2); internally B over the
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
#: Share of the fitted background power B^2 the fixed lines must carry to name the form "lines" alone.
LINE_SHARE = 0.4


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
    form = law.FORMS[0]
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

    def independent_evidence(self, table, location, params=None) -> str:
        """Fixed-frequency spectral lines with constant power, at least :data:`MIN_LINE_SHARE` of the power."""
        lines = location.spectrum if location is not None else None
        if lines is None or not lines.frequencies or lines.share_at_lowest_speed < MIN_LINE_SHARE:
            return ''
        return 'spectrum: ' + lines.note

    def form_name(self, params, table, location) -> str:
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

    def describe(self, params):
        """B and its share of the smallest RMS."""
        b = params['background_rms']
        return (f'Background of B = {b:.4g} m/s^2 RMS, {100 * b / params["rms_scale"]:.0f} % of the smallest '
                'window RMS recorded. ' + self.physics)
