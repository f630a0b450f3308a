# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How to fit a surface defect (the law: :mod:`prsm_lube_ros.physics.effects.surface_defect`).

``A = sqrt(A_22^2 + P_imp)``, ``P_imp = A_imp^2 (omega/omega_ref)^(2a) (F/F_ref)^(2b) g(N)^2``.
Three forms, each fitted: a steady defect (g = 1) and one growing exponentially
(``g = exp(N / N_g)``) or linearly (``g = 1 + N / N_g``), N the revolutions over
the recordings in the order given (the simulator's growth forms).
Internally: A_imp over the smallest window RMS, a, b and (growing) N_max / N_g
with N_max the most revolutions over the recordings; omega_ref is the lowest
recorded speed and F_ref the highest load.

The amplitudes alone cannot tell impulsive power from other power added at
speed, or a growing defect from oil lost with the revolutions.  The evidence
that decides is outside the amplitude fit, in the condition indicators of each
window (columns of the window table, NaN where unknown): ``kurtosis`` of the
band-passed signal (3 for Gaussian rolling-contact vibration, whatever the
lubrication), and ``defect_db``, the largest envelope-spectrum peak at a
labelled defect order, with ``defect_order``.  Impulsive windows are evidence
for the defect; indicators that are there and not impulsive are evidence
against it.  Without the indicators the candidate is not testable.
"""
from __future__ import annotations

from typing import Any, TYPE_CHECKING

import numpy as np

from ...estimation.defect_screen import below_unexplained, DEFAULT_RULES
from ...physics.effects import surface_defect as law
from .base import Effect, register

if TYPE_CHECKING:
    from ..locate import Location
    from ..table import WindowTable

__all__ = ['DEFECT_DB', 'EXPONENT_RANGES', 'GROWTH_RANGE', 'GrowingSurfaceDefectCandidate', 'IMPULSIVE_KURTOSIS',
           'IMPULSIVE_SHARE', 'INDICATOR_SHARE', 'LINEAR_GROWTH_RANGE', 'LinearlyGrowingSurfaceDefectCandidate',
           'MIN_CONDITION_WINDOWS',
           'NOT_IMPULSIVE_SHARE', 'SILENCED_SHARE', 'SIZE_RANGE',
           'SurfaceDefectCandidate', 'condition_share', 'indicators', 'unspecific_lines']

#: Bounds of A_imp over the smallest window RMS.
SIZE_RANGE = (0.0, 3.0)
#: Bounds of the exponents a (speed) and b (load).
EXPONENT_RANGES = ((0.0, 3.0), (0.0, 2.0))
#: Bounds of N_max / N_g (the impulsive RMS grows by up to e^3 over the recordings).
GROWTH_RANGE = (0.0, 3.0)
#: Bounds of N_max / N_g of the linear growth (up to 11 times over the recordings: the simulator's 1.5-4 per
#: session, over two sessions or more).
LINEAR_GROWTH_RANGE = (0.0, 10.0)
#: Band kurtosis above which a window counts as impulsive: what healthy rolling contact stays below anywhere plus
#: the margin of a strongly impulsive run (the defect screen's rules; Gaussian vibration gives 3, healthy
#: simulated 1 s windows 2.7-3.4).
IMPULSIVE_KURTOSIS = DEFAULT_RULES.healthy_kurtosis + DEFAULT_RULES.kurtosis_margin
#: Share of the windows that must be impulsive for evidence (a growing defect shows late in the session), per
#: operating condition with each condition weighing alike (:func:`condition_share`).
IMPULSIVE_SHARE = 0.25
#: At most this share of impulsive windows (and no envelope peak) for evidence against the defect.
NOT_IMPULSIVE_SHARE = 0.05
#: Envelope-spectrum line at a strike order over the envelope floor, dB, that counts as a defect order seen
#: (the defect screen's rule).
DEFECT_DB = DEFAULT_RULES.envelope_db
#: Known windows a condition needs to count in :func:`condition_share` (none of the 226 recorded study tables of
#: blocks 1746 and 1800-1919 has a condition with fewer).
MIN_CONDITION_WINDOWS = 3
#: Share of the windows that must carry the indicators for the candidate to be testable.
INDICATOR_SHARE = 0.8
#: A fit silences the contacts in a window where its Gaussian part (its amplitude without P_imp) holds less than
#: this share of the Gaussian power the window measures (10 dB).  Strikes that ring densely raise the measured
#: part by the share of samples they hold: up to 6.0 times the contacts' power in 395 simulated windows, 1.9
#: times at the 90th percentile (``benchmarks/gaussian_part_bias.py``;
#: ``test_condition_indicators.py::test_dense_strikes_raise_the_gaussian_part_less_than_ten_times``).
SILENCED_SHARE = 0.1


def indicators(table: WindowTable) -> dict[str, np.ndarray] | None:
    """The table's condition-indicator columns: kurtosis, the window's and its run's strike lines.

    ``kurtosis``, ``defect_db``, ``defect_order``, ``run_defect_db`` and
    ``run_unexplained_db``; NaN where unknown.

    None when the table has no kurtosis in :data:`INDICATOR_SHARE` of its windows.
    """
    n = len(table)

    def column(name: str) -> np.ndarray:
        value = getattr(table, name, None)
        array = np.full(n, np.nan) if value is None else np.asarray(value, dtype=float)
        return array if array.shape == (n,) else np.full(n, np.nan)

    columns = {name: column(name) for name in ('kurtosis', 'defect_db', 'defect_order', 'run_defect_db',
                                               'run_unexplained_db')}
    if n == 0 or np.isfinite(columns['kurtosis']).mean() < INDICATOR_SHARE:
        return None
    return columns


def _pooled(columns: dict[str, np.ndarray]) -> bool:
    """Whether the table carries its runs' averaged envelope lines (recordings do; window-table simulators not)."""
    return bool(np.isfinite(columns['run_defect_db']).mean() >= INDICATOR_SHARE)


def _line_levels(columns: dict[str, np.ndarray], specific: bool = True) -> np.ndarray:
    """Per window the strike-order envelope line judged: its run's averaged one where known, else its own.

    One window's envelope line reaches :data:`DEFECT_DB` by chance now and then (10-15 % of healthy 1 kHz
    windows); the run average of ten windows does not (the defect screen judges runs for that reason).
    ``specific``: a run's line below a line of the same run at an order no component explains counts as none
    (:func:`unspecific_lines`), as evidence for the defect; as evidence against it every line counts.
    """
    if not _pooled(columns):
        return columns['defect_db']
    return np.where(unspecific_lines(columns), 0.0, columns['run_defect_db']) if specific else columns['run_defect_db']


def unspecific_lines(columns: dict[str, np.ndarray]) -> np.ndarray:
    """Windows whose run's strike-order line reaches :data:`DEFECT_DB` but not the run's unexplained lines.

    Those lines the evidence for the defect does not count: below a line of
    the same run at an order no component explains (plus the margin,
    :func:`~prsm_lube_ros.estimation.defect_screen.below_unexplained`).

    The defect screen's rule (``DefectRules.unexplained_margin_db``): a machine
    modulates its vibration wherever no defect is, a structural mode's ring
    beats with the speed's orders, and such lines reach 10-19 dB where
    nothing strikes (study case two 1757: lines of 11.6-13.9 dB at the
    roller-pass order beside unexplained ones of 11.8-18.8 dB in every run,
    a resonance and thermal thinning read as a surface defect).
    """
    lines = columns['run_defect_db']
    return (lines >= DEFECT_DB) & below_unexplained(lines, columns['run_unexplained_db'])


def _follows_the_order(table: WindowTable, peaked: np.ndarray) -> bool:
    """Whether the envelope lines at a defect order show at two screw speeds or more (or one is all recorded).

    Strikes come at a fixed order of the rotation, so a defect's line stays at
    its order at every speed; a band fixed in Hz (a structural mode ringing, a
    line from elsewhere) meets a given order at one speed only, and there its
    envelope can read as a line at that order.  One speed level alone cannot
    tell them apart and is taken as it is.
    """
    from ...estimation.calibration import operating_levels
    speeds = np.abs(table.speed)
    if len(operating_levels(speeds)) < 2:
        return True
    return len(operating_levels(speeds[peaked])) >= 2 if peaked.any() else False


@register
class SurfaceDefectCandidate(Effect, law.Extension):
    """A spall or pit struck by every passing contact: impulsive power adding to the contacts' (steady form)."""

    id = 'surface_defect'
    title = 'surface defect'
    form = 'steady'
    physics = ('A spall or pit on a raceway or roller: each passing contact strikes it and the strike rings the '
               'structure, so impulsive vibration at a defect order adds in power, growing with speed (impact '
               'velocity) and load; it is not lubrication, and theta_Oil is no lubrication measure while it lasts.')
    equations = 'A = sqrt(A_22^2 + P_imp), P_imp = A_imp^2 (omega/omega_ref)^(2a) (F/F_ref)^(2b)'
    parameter_names: tuple[str, ...] = ('impulsive_fraction', 'speed_exponent', 'load_exponent')
    covariate = 'speed'
    to_separate = ('condition indicators of each window (band kurtosis, envelope spectrum at the defect orders), '
                   'several speeds and loads, and repeated conditions early and late in the session')
    grows = False
    requires_evidence = True
    #: The strikes ring a structural mode fixed in Hz, and the impulsive power grows with speed by its own exponent
    #: (impact velocity, strike rate), not the contacts' omega^2 law: its share of the power, and so the spectrum's
    #: shape, changes between the speeds by the defect alone (a shape change beside it is no background evidence).
    changes_spectral_shape = True
    #: The impulsive power's load exponent b trades against C_F: with two loads a free fit can silence the contacts
    #: at the higher one (C_F = -0.061 1/N in study case two 1333), which the windows' Gaussian part contradicts.
    trades_load_excitation = True
    #: The strikes are sparse in time: the windows' Gaussian part is the contacts' vibration without them, where an
    #: effect beside the defect shows that the defect's free exponents take on the whole RMS (a mode's fall with
    #: speed: study two 1710).
    impulsive = True

    def applicable(self, table: WindowTable) -> str:
        """Needs the condition indicators (impulsiveness is what tells a defect apart) and known revolutions."""
        if indicators(table) is None:
            return ('no condition indicators (band kurtosis) in the windows: impulsiveness, which tells a surface '
                    'defect apart, cannot be tested')
        if self.grows and (np.isfinite(table.revolutions).mean() < 0.8 or np.nanmax(table.revolutions) < 1.0):
            return 'revolutions are not known: a defect growing with them cannot be tested'
        return ''

    def scales(self, table: WindowTable) -> dict[str, float]:
        """Smallest window RMS (m/s^2), lowest speed (rad/s), highest load (N) and most revolutions run."""
        revolutions = law.cumulative_revolutions(table.revolutions, table.recording)
        return {'rms_scale': float(np.min(table.rms)), 'reference_speed': float(np.min(np.abs(table.speed))),
                'reference_load': float(np.max(np.abs(table.load))),
                'revolution_scale': float(max(np.max(revolutions), 1.0))}

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """A_imp / min RMS, a, b (and N_max / N_g) in their ranges."""
        ranges = [SIZE_RANGE, *EXPONENT_RANGES] + ([GROWTH_RANGE] if self.grows else [])
        return np.array([r[0] for r in ranges]), np.array([r[1] for r in ranges])

    def starts(self) -> list[np.ndarray]:
        """Small to large defects at mid exponents (growing: slow and fast)."""
        sizes = (0.2, 0.6, 1.2)
        if self.grows:
            return [np.array([s / 2, 1.5, 0.6, g]) for s in sizes for g in (0.5, 1.5)]
        return [np.array([s, 1.5, 0.6]) for s in sizes]

    def to_params(self, p: np.ndarray, scales: dict[str, float]) -> dict[str, Any]:
        """impulsive_rms (m/s^2), the exponents, growth_per_revolution (1/N_g) and the scales."""
        growth = float(p[3] / scales['revolution_scale']) if self.grows else 0.0
        return {'impulsive_rms': float(p[0] * scales['rms_scale']), 'speed_exponent': float(p[1]),
                'load_exponent': float(p[2]), 'growth_per_revolution': growth, 'linear': 0.0, **scales}

    def variants(self) -> list[Effect]:
        """Steady, and growing with the revolutions exponentially or linearly."""
        return [self, GrowingSurfaceDefectCandidate(), LinearlyGrowingSurfaceDefectCandidate()]

    def describe(self, params: dict[str, Any]) -> str:
        """A_imp at the reference condition, the exponents and the growth over the recordings."""
        rms = params['impulsive_rms']
        text = (f'Impulsive vibration of {rms:.3g} m/s^2 RMS at {params["reference_speed"]:.3g} rad/s and '
                f'{params["reference_load"]:.4g} N ({100 * rms / params["rms_scale"]:.0f} % of the smallest window '
                f'RMS), growing as speed^{params["speed_exponent"]:.2f} and load^{params["load_exponent"]:.2f}')
        growth = params.get('growth_per_revolution', 0.0)
        if growth > 0:
            factor = float(law.growth_factor(params['revolution_scale'], growth, bool(params.get('linear'))))
            text += (f', and with the revolutions run by x{factor:.2f}{" (linearly)" if params.get("linear") else ""} '
                     f'over {params["revolution_scale"]:.0f} revolutions (N_g = {1 / growth:.3g})')
        return text + '. ' + self.physics

    def independent_evidence(self, table: WindowTable, location: Location | None,
                             params: dict[str, Any] | None = None, beside: Effect | None = None) -> str:
        """Impulsive windows, read in the condition indicators; empty when none.

        :data:`IMPULSIVE_SHARE` of the windows with band kurtosis over
        :data:`IMPULSIVE_KURTOSIS`, or envelope peaks of :data:`DEFECT_DB` at a
        defect order in as many, at two screw speeds or more (:func:`_follows_the_order`).
        """
        return _impulsive_evidence(table, IMPULSIVE_SHARE)

    def exclusive_evidence(self, table: WindowTable, share: float) -> str:
        """Impulsive windows or envelope lines at a defect order in ``share`` of the windows or more; else empty.

        No other candidate makes either (oil loss, a mode, stiffness and a
        background vibrate Gaussian: band kurtosis 3, healthy simulated 1 s
        windows 2.7-3.4, never over :data:`IMPULSIVE_KURTOSIS`), so with the
        engine's share (half the windows of the average operating condition,
        :func:`condition_share`) the defect is named beside a first effect
        whatever its amplitude fit.
        """
        return _impulsive_evidence(table, max(share, IMPULSIVE_SHARE))

    def measured_against(self, table: WindowTable, params: dict[str, Any],
                         predicted: np.ndarray | None = None) -> str:
        """The fit silences the contacts where the recording measures their Gaussian vibration; empty when not.

        Strikes are sparse in time and the contacts' rolling vibration is
        Gaussian, so each window's Gaussian part is measured apart from the
        strikes (``gaussian_rms``: median |x| of the band signal over the
        Gaussian's).  The fit's own Gaussian part is its amplitude
        (``predicted``) with the fitted impulsive power P_imp taken out.  In
        :data:`IMPULSIVE_SHARE` of the windows or more that part is under
        :data:`SILENCED_SHARE` of the measured one's power: the fit has traded
        the contacts away (their constants against the defect's exponents:
        C_F far below 0 with two loads), which no window shows.  The margin
        holds where strikes ring densely, which raises the measured part
        (:data:`SILENCED_SHARE`).  Not testable without ``predicted`` or where
        fewer than :data:`INDICATOR_SHARE` of the windows carry the Gaussian part.
        """
        gaussian = getattr(table, 'gaussian_rms', None)
        if gaussian is None or predicted is None or len(table) == 0:
            return ''
        gaussian = np.asarray(gaussian, dtype=float)
        model = np.asarray(predicted, dtype=float)
        known = np.isfinite(gaussian) & (gaussian > 0) & np.isfinite(model)
        if known.mean() < INDICATOR_SHARE:
            return ''
        contacts = np.maximum(model ** 2 - np.asarray(self.power(params, table), dtype=float), 0.0)
        ratio = np.where(known, contacts / np.where(known, gaussian, 1.0) ** 2, np.nan)
        silenced = known & (ratio < SILENCED_SHARE)
        if silenced.mean() < IMPULSIVE_SHARE:      # a share of all windows: the fit is judged where it is made
            return ''
        return (f'Gaussian part: in {100 * silenced.mean():.0f} % of the windows the fit leaves the contacts '
                f'{100 * float(np.median(ratio[silenced])):.1f} % (median) of the Gaussian power the band signal '
                'measures: the fit silences the contacts\' rolling vibration, which the windows keep')

    def contrary_evidence(self, table: WindowTable, location: Location | None,
                          params: dict[str, Any] | None = None) -> str:
        """The indicators are there and nothing is impulsive.

        At most :data:`NOT_IMPULSIVE_SHARE` of the windows over
        :data:`IMPULSIVE_KURTOSIS`, and envelope lines of :data:`DEFECT_DB` in
        fewer than :data:`IMPULSIVE_SHARE` of them (one window's envelope line
        reaches it by chance now and then: 10-15 % of healthy simulated windows at 1 kHz); both shares per
        operating condition (:func:`condition_share`).
        """
        columns = indicators(table)
        if columns is None:
            return ''
        kurtosis, peaks = columns['kurtosis'], _line_levels(columns, specific=False)
        impulsive = condition_share(table, kurtosis > IMPULSIVE_KURTOSIS, np.isfinite(kurtosis))
        if impulsive > NOT_IMPULSIVE_SHARE or condition_share(table, np.isfinite(peaks) & (peaks >= DEFECT_DB)) \
                >= IMPULSIVE_SHARE:
            return ''
        return (f'condition indicators: the windows are not impulsive (band kurtosis median '
                f'{float(np.nanmedian(kurtosis)):.2f}, {100 * impulsive:.0f} % over {IMPULSIVE_KURTOSIS:g}) and '
                'the envelope spectra show no defect order')


def condition_share(table: WindowTable, mask: np.ndarray, known: np.ndarray | None = None) -> float:
    """The share of ``mask``'s windows per operating condition, averaged with each condition weighing alike.

    A condition is a (speed level, load level) pair
    (:func:`~prsm_lube_ros.estimation.calibration.condition_labels`); within
    each, the share is taken over its ``known`` windows (default all).  Each
    condition weighs alike because a plan's conditions do not: a traverse of
    the stroke holds windows in proportion to 1 / speed, and a defect's
    impulsive power follows its own exponents of speed and load, not the
    contacts' omega^2 law, so it stands out of the contacts in a part of the
    plan only (study two 1877: every window at the fastest speed struck,
    kurtosis 6-15, none at the slowest, which held 2.3 times as many windows).
    A share over the windows would weigh where it shows by how long the
    traverses there last.  A condition counts with :data:`MIN_CONDITION_WINDOWS`
    known windows or more (one window off the set-points is no condition of the
    plan); where none has that many, the share is over the known windows.  NaN
    without windows.
    """
    from ...estimation.calibration import condition_labels
    known = np.ones(len(mask), bool) if known is None else np.asarray(known, bool)
    if not known.any():
        return float('nan')
    labels = condition_labels(table.speed, table.load)[known]
    hits = np.asarray(mask, bool)[known]
    counts = np.bincount(labels)
    usable = counts >= MIN_CONDITION_WINDOWS
    if not usable.any():
        return float(hits.mean())
    return float(np.mean(np.bincount(labels, weights=hits.astype(float))[usable] / counts[usable]))


def _impulsive_evidence(table: WindowTable, share: float) -> str:
    """The condition indicators' words when ``share`` of the windows or more are impulsive or show a defect order.

    Band kurtosis over :data:`IMPULSIVE_KURTOSIS`, or envelope peaks of
    :data:`DEFECT_DB` at a defect order at two screw speeds or more
    (:func:`_follows_the_order`); empty when neither reaches ``share``.
    Shares are per operating condition, each condition weighing alike (:func:`condition_share`).
    """
    columns = indicators(table)
    if columns is None:
        return ''
    kurtosis, peaks = columns['kurtosis'], _line_levels(columns)
    impulsive = condition_share(table, kurtosis > IMPULSIVE_KURTOSIS, np.isfinite(kurtosis))
    peaked = np.isfinite(peaks) & (peaks >= DEFECT_DB)
    if not _follows_the_order(table, peaked):
        peaked = np.zeros_like(peaked)
    lined = condition_share(table, peaked)
    parts = []
    if impulsive >= share:
        parts.append(f'{100 * impulsive:.0f} % of the windows impulsive (band kurtosis over '
                     f'{IMPULSIVE_KURTOSIS:g}, median {float(np.nanmedian(kurtosis)):.1f}; Gaussian contact '
                     'vibration gives 3)')
    if lined >= share:
        orders = columns['defect_order'][peaked]
        order = float(np.nanmedian(orders)) if np.isfinite(orders).any() else float('nan')
        parts.append(f'envelope peaks {float(np.median(peaks[peaked])):.0f} dB over the floor at order '
                     f'{order:.3g} in {100 * lined:.0f} % of the windows'
                     + (' (their runs\' averaged envelope spectra)' if _pooled(columns) else ''))
    if not parts:
        return ''
    return 'condition indicators: ' + '; '.join(parts) + ' (shares per operating condition, each weighing alike)'


class GrowingSurfaceDefectCandidate(SurfaceDefectCandidate):
    """The defect grows with the revolutions run: ``g(N) = exp(N / N_g)``."""

    form = 'growing with revolutions'
    equations = ('A = sqrt(A_22^2 + P_imp), P_imp = A_imp^2 (omega/omega_ref)^(2a) (F/F_ref)^(2b) '
                 'exp(2 N_rev / N_g)')
    parameter_names = ('impulsive_fraction', 'speed_exponent', 'load_exponent', 'growth_fraction')
    covariate = 'revolutions'
    grows = True

    def variants(self) -> list[Effect]:
        """Only itself."""
        return [self]


class LinearlyGrowingSurfaceDefectCandidate(GrowingSurfaceDefectCandidate):
    """The defect grows linearly with the revolutions run: ``g(N) = 1 + N / N_g`` (the law's ``linear`` growth).

    A spall widens by the material each strike removes at its edge, so its
    impulsive amplitude can grow in proportion to the revolutions as well as
    in proportion to its size; over a session the two part by a quarter of
    the amplitude midway (a factor 4 at the end: 2 against 2.5), which an
    exponential law cannot follow (study two 1849, 1746 and 1827: a linearly
    growing spall, `unexplained` where the exponential form lost to an
    empirical step in time).
    """

    form = 'growing linearly with revolutions'
    equations = ('A = sqrt(A_22^2 + P_imp), P_imp = A_imp^2 (omega/omega_ref)^(2a) (F/F_ref)^(2b) '
                 '(1 + N_rev / N_g)^2')

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """A_imp / min RMS, a, b and N_max / N_g in :data:`LINEAR_GROWTH_RANGE`."""
        low, high = super().bounds()
        return np.r_[low[:3], LINEAR_GROWTH_RANGE[0]], np.r_[high[:3], LINEAR_GROWTH_RANGE[1]]

    def starts(self) -> list[np.ndarray]:
        """Small to large defects at mid exponents, growing by 2 and 6 times over the recordings."""
        return [np.array([s / 2, 1.5, 0.6, g]) for s in (0.2, 0.6, 1.2) for g in (1.0, 5.0)]

    def to_params(self, p: np.ndarray, scales: dict[str, float]) -> dict[str, Any]:
        """As the exponential form, with ``linear`` 1."""
        return {**super().to_params(p, scales), 'linear': 1.0}
