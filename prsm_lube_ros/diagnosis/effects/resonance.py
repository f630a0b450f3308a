# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How to fit a resonance (the law: :mod:`prsm_lube_ros.physics.effects.resonance`).

``A = A_22 |H(r)|`` with ``r = omega_S / omega_r``.  Any rotation order n may
excite the mode; from RMS values only the screw speed at which the excitation
meets the mode, ``omega_r = 2 pi f_r / n`` (rad/s), can be identified, so the
order enters as ``f_r = n omega_r / (2 pi)`` and the report lists f_r for the
first orders.  Three forms, each fitted, by where omega_r lies against the
recorded speeds omega_min..omega_max:

* mode above the band (``omega_r > omega_max``): the amplitude rises faster
  than omega^2; internally r at the top speed, 0.05-0.98;
* mode inside the band: a peak between two recorded speeds; internally
  ``q = ln(omega_r / omega_min) / ln(omega_max / omega_min)`` in 0..1;
* mode below the band (``omega_r < omega_min``): every speed is past
  resonance, the amplitude rises more slowly than omega^2 (tending to
  A_22 / r^2); internally r at the lowest speed, 1.02-20.

Each also fits the damping ratio zeta.  The engine chooses the form by BIC.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ...physics.effects import resonance as law
from ..locate import impulse_tracking
from ..rules import DEFAULT_SPECTRAL_RULES
from .base import Effect, register

if TYPE_CHECKING:
    from ..locate import Location, SpectralLines
    from ..table import WindowTable

__all__ = ['BOTTOM_RATIO_RANGE', 'DAMPING_RANGE', 'REPORTED_ORDERS', 'ResonanceCandidate',
           'ResonanceBelowBandCandidate', 'ResonanceInBandCandidate', 'TOP_RATIO_RANGE', 'exciting_order_values']

#: Bounds of the frequency ratio at the highest recorded speed (mode above the band).
TOP_RATIO_RANGE = (0.05, 0.98)
#: Bounds of the frequency ratio at the lowest recorded speed (mode below the band).
BOTTOM_RATIO_RANGE = (1.02, 20.0)
#: Bounds of the damping ratio.
DAMPING_RANGE = (0.005, 0.5)
#: Rotation orders for which the report gives the mode's natural frequency.
REPORTED_ORDERS = (1, 2, 3, 4)


def exciting_order_values(table: WindowTable) -> tuple[float, ...]:
    """Rotation orders that may excite a mode in ``table``'s recordings (:func:`law.exciting_orders`).

    The roller pass order n_p (Eq. 1: rollers passing a point of the nut per
    screw revolution) is the recording's nut raceway defect order; without it
    only the low orders.
    """
    roller_pass = [d.order for d in table.defect_orders if d.component == 'nut raceway']
    return law.exciting_orders(roller_pass[0]) if roller_pass else law.LOW_ORDERS


@register
class ResonanceCandidate(Effect, law.Extension):
    """The excitation frequency approaches a structural mode above the speed band."""

    id = 'resonance'
    changes_spectral_shape = True
    title = 'structural resonance'
    form = 'mode above the speed band'
    physics = ('A rotation-order excitation (any order) meets a lightly damped natural frequency of the '
               'structure, so the quasi-static step X0 = F0/K0 (Eq. 14) no longer holds: the response follows '
               "Eq. 13's magnification |H(r)| and the amplitude departs from the omega^2 law of Eq. 22.")
    equations = 'A = A_22 / sqrt((1 - r^2)^2 + (2 zeta r)^2), r = omega_S / omega_r, omega_r = 2 pi f_r / n'
    parameter_names = ('top_ratio', 'damping_ratio')
    covariate = 'speed'
    to_separate = 'more screw speeds (at least 4, up to the highest the actuator runs) at each load'

    def applicable(self, table: WindowTable) -> str:
        """Needs three speed levels at least (the shape of A against speed)."""
        from ...estimation.calibration import operating_levels
        levels = operating_levels(table.speed)
        if len(levels) < 3:
            return f'{len(levels)} screw speed(s) recorded: a resonance needs 3 or more to show its shape'
        return ''

    def scales(self, table: WindowTable) -> dict[str, float]:
        """The highest and lowest recorded screw speeds, rad/s."""
        speed = np.abs(table.speed)
        return {'top_speed': float(np.max(speed)), 'bottom_speed': float(np.min(speed))}

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Frequency ratio at the top speed and damping ratio."""
        return (np.array([TOP_RATIO_RANGE[0], DAMPING_RANGE[0]]),
                np.array([TOP_RATIO_RANGE[1], DAMPING_RANGE[1]]))

    def starts(self) -> list[np.ndarray]:
        """A grid of frequency ratios below resonance."""
        return [np.array([r, z]) for r in (0.4, 0.6, 0.75, 0.85, 0.93) for z in (0.03, 0.1)]

    def _resonant_speed(self, p: np.ndarray, scales: dict[str, float]) -> float:
        return scales['top_speed'] / p[0]

    def spectral_evidence(self, table: WindowTable, location: Location | None,
                          params: dict[str, float] | None = None, beside: Effect | None = None) -> str:
        """Order lines whose powers follow one mode in Hz, or a band fixed in Hz whose power follows the speed.

        With fitted ``params`` the band must also follow the fitted transfer:
        the mode rings with the share ``1 - 1/|H|^2`` of the response where
        ``|H| > 1``, so the speed where the band is strongest must be where
        (or next to where) that predicted share is largest, and the prediction
        must reach a quarter of the band's largest share, and the order that
        meets the band at the fitted resonant speed must be one the screw
        makes (:meth:`_implied_order`), and its power must not follow the
        windows' strikes (:func:`.locate.impulse_tracking` above
        ``SpectralRules.struck_band_z``: a spall's ring).  Of several bands,
        those that follow count (the largest named); a band the transfer does
        not put there is another mode or the contact's own response.
        """
        lines = location.spectrum if location is not None else None
        if lines is None:
            return ''
        tracked = self._order_evidence(lines, params)
        if tracked:
            return tracked
        if not lines.mode_frequencies:
            return self._ring_evidence(table, lines, params)
        if params is None:
            return 'spectrum: ' + lines.mode_note
        highest = DEFAULT_SPECTRAL_RULES.mode_max_order
        following = [band for band, frequency in enumerate(lines.mode_frequencies)
                     if self._follows_transfer(lines, band, params)
                     and self._implied_order(frequency, params) <= highest
                     and not (table is not None
                              and impulse_tracking(table, frequency) > DEFAULT_SPECTRAL_RULES.struck_band_z)]
        if not following:
            return self._ring_evidence(table, lines, params)
        band = max(following, key=lambda b: max(lines.mode_shares[b]))
        order = self._implied_order(lines.mode_frequencies[band], params)
        return (f'spectrum: {lines.band_note(band)}; at the fitted resonant speed it is order {order:.2f}, '
                f'natural frequency {lines.mode_frequencies[band]:.1f} Hz')

    @staticmethod
    def _implied_order(frequency: float, params: dict[str, float]) -> float:
        """The rotation order that meets a mode at ``frequency`` (Hz) at the fitted resonant speed: 2 pi f_r / omega_r.

        A band whose order is above ``SpectralRules.mode_max_order`` is no
        evidence for the fitted mode: no rotation order of the screw excites it
        there (rollers times thread starts stay below order 50), and such a band
        is what something else rings, a spall's strikes above all (studies:
        surface_defect 1905 and 1339 and two 1333, bands at orders 63-102: a
        resonance no longer named beside the spall,
        ``benchmarks/results/engine_ab_mode_order``).
        """
        return frequency * 2.0 * math.pi / params['resonant_speed']

    @staticmethod
    def _ring_evidence(table: WindowTable, lines: SpectralLines, params: dict[str, float] | None) -> str:
        """A band fixed in Hz at every speed implying, at the fitted omega_r, an order that excites the mode.

        Only for a fitted mode below the band (every speed past resonance, where
        the order's response is attenuated and no band follows the transfer):
        the contacts' broadband rings the mode at f_r at every speed
        (:func:`~prsm_lube_ros.physics.effects.resonance.broadband_ring_share`;
        :attr:`.locate.SpectralLines.ring_frequencies`), and the order that meets
        it at the fitted resonant speed, ``n = 2 pi f_r / omega_r``, must be
        one that excites a mode (:func:`~prsm_lube_ros.physics.effects.resonance.exciting_orders`
        of the recording's roller pass order) within ``SpectralRules.mode_order_tolerance``.
        A fixed band from elsewhere, or the contacts' own mode far above, implies no such order.
        """
        if (params is None or not lines.ring_frequencies
                or params['resonant_speed'] >= params.get('bottom_speed', math.inf)):
            return ''
        orders = exciting_order_values(table)
        tolerance = DEFAULT_SPECTRAL_RULES.mode_order_tolerance
        for band, frequency in enumerate(lines.ring_frequencies):
            implied = ResonanceCandidate._implied_order(frequency, params)
            near = min(orders, key=lambda n: abs(implied / n - 1.0))
            if abs(implied / near - 1.0) <= tolerance:
                return (f'spectrum: {lines.ring_note(band)}; at the fitted resonant speed it is order {implied:.2f}, '
                        f'{near:.3g} excites it (natural frequency {frequency:.1f} Hz)')
        return ''

    @staticmethod
    def _order_evidence(lines: SpectralLines, params: dict[str, float] | None) -> str:
        """Order-tracked line powers following one mode in Hz; with ``params``, at a tracked order's frequency.

        The fitted resonant speed omega_r and the spectrum's f_r must agree:
        ``2 pi f_r / omega_r`` within ``SpectralRules.mode_order_tolerance`` of one of the tracked orders.
        """
        found = lines.order_mode or {}
        if not found.get('found'):
            return ''
        if params is not None:
            implied = ResonanceCandidate._implied_order(found['natural_frequency_hz'], params)
            tolerance = DEFAULT_SPECTRAL_RULES.mode_order_tolerance
            if not any(abs(implied / order - 1.0) <= tolerance for order in found.get('order_values', ())):
                return ''
            return f'spectrum: {found["note"]}; at the fitted resonant speed that is order {implied:.2f}'
        return 'spectrum: ' + found['note']

    @staticmethod
    def _follows_transfer(lines: SpectralLines, band: int, params: dict[str, float]) -> bool:
        """Whether the shares per speed of mode band ``band`` follow the fitted magnification (see above)."""
        speeds = np.asarray(lines.mode_speeds, dtype=float)
        shares = np.asarray(lines.mode_shares[band], dtype=float)
        gain = law.magnification(speeds / params['resonant_speed'], params['damping_ratio'])
        predicted = np.where(gain > 1.0, 1.0 - 1.0 / np.maximum(gain, 1.0) ** 2, 0.0)
        rank = np.argsort(np.argsort(speeds))
        strongest, expected = rank[int(np.argmax(shares))], rank[int(np.argmax(predicted))]
        return abs(int(strongest) - int(expected)) <= 1 and predicted.max() >= 0.25 * shares.max()

    def to_params(self, p: np.ndarray, scales: dict[str, float]) -> dict[str, float]:
        """resonant_speed (rad/s), damping_ratio and the band's top and bottom speeds."""
        return {'resonant_speed': float(self._resonant_speed(p, scales)), 'damping_ratio': float(p[1]), **scales}

    def variants(self) -> list[Effect]:
        """Mode above, inside and below the speed band."""
        return [self, ResonanceInBandCandidate(), ResonanceBelowBandCandidate()]

    def describe(self, params: dict[str, float]) -> str:
        """Where the resonance lies, the natural frequency per order and the magnification at the band's ends."""
        speed = params['resonant_speed']
        top = params['top_speed'] / speed
        bottom = params.get('bottom_speed', params['top_speed']) / speed
        gains = [float(law.magnification(r, params['damping_ratio'])) for r in (bottom, top)]
        orders = ', '.join(f'{law.natural_frequency(speed, n):.1f} Hz (order {n})' for n in REPORTED_ORDERS)
        return (f'The excitation meets a mode {self.form[5:]} at a screw speed of {speed:.1f} rad/s '
                f'({speed * 30 / math.pi:.0f} r/min), damping ratio {params["damping_ratio"]:.3f}; the natural '
                f'frequency is {orders} or n times {speed / (2 * math.pi):.2f} Hz for order n. At the lowest and '
                f'highest speed r = {bottom:.2f} and {top:.2f}, the response magnified x{gains[0]:.2f} and '
                f'x{gains[1]:.2f}. ' + self.physics)


class ResonanceInBandCandidate(ResonanceCandidate):
    """The mode inside the recorded speed band: a peak between two speeds."""

    form = 'mode inside the speed band'
    parameter_names = ('band_position', 'damping_ratio')

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Position of omega_r in the band (log scale, 0..1) and damping ratio."""
        return np.array([0.0, DAMPING_RANGE[0]]), np.array([1.0, DAMPING_RANGE[1]])

    def starts(self) -> list[np.ndarray]:
        """Across the band, light and moderate damping."""
        return [np.array([q, z]) for q in (0.15, 0.5, 0.85) for z in (0.03, 0.1)]

    def _resonant_speed(self, p: np.ndarray, scales: dict[str, float]) -> float:
        return scales['bottom_speed'] * (scales['top_speed'] / scales['bottom_speed']) ** float(p[0])

    def variants(self) -> list[Effect]:
        """Only itself."""
        return [self]


class ResonanceBelowBandCandidate(ResonanceCandidate):
    """The mode below the recorded speed band: every speed past resonance."""

    form = 'mode below the speed band'
    parameter_names = ('bottom_ratio', 'damping_ratio')

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Frequency ratio at the lowest speed and damping ratio."""
        return (np.array([BOTTOM_RATIO_RANGE[0], DAMPING_RANGE[0]]),
                np.array([BOTTOM_RATIO_RANGE[1], DAMPING_RANGE[1]]))

    def starts(self) -> list[np.ndarray]:
        """Just past resonance to far past it."""
        return [np.array([r, z]) for r in (1.1, 1.5, 3.0) for z in (0.03, 0.1)]

    def _resonant_speed(self, p: np.ndarray, scales: dict[str, float]) -> float:
        return scales['bottom_speed'] / p[0]

    def variants(self) -> list[Effect]:
        """Only itself."""
        return [self]
