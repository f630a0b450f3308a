# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Window tables generated directly from Eq. 22 and one hidden effect (no signals, no bags).

A second, independent simulator at the level the diagnosis works on: for unit
tests and for the study's check that detection does not rest on the rig
simulator's particulars.  It draws its own plan (speeds, loads, repeats, run
order), its own noise (window scatter and a per-run gain scatter) and its own
effect parametrisations (e.g. the fixed bearing at either end of the shaft,
background tones at random frequencies).  Spectra, when asked for, are
synthesised per window: rotation-order lines and broadband from the thread
contacts, fixed tones and broadband from the background.

Effects other than the first five (:data:`OWN_DRAWS`, kept with their own
parametrisations so the tables of earlier studies stay as they were) go through
their module's simulation hook only: drawn by ``Simulation.draw`` over the
module's ranges, applied through the law's ``Extension`` (film factor and log
gain) and, with ``condition_indicators``, changing the windows' indicators
(``Simulation.window_indicators``).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field, is_dataclass
import math
from collections.abc import Sequence
from types import SimpleNamespace
from typing import Any, cast

import numpy as np

from ..diagnosis.table import WindowTable
from ..physics.actuator import Actuator
from ..physics.effects import (background_vibration, ContactState, extension, lubricant_depletion as depletion,
                               position_dependent_stiffness as stiffness, resonance, simulation, SimulationContext,
                               thermal_viscosity as thermal)
from ..physics.vibration_model import acceleration_amplitude, ModelConstants


__all__ = ['BACKGROUND_SHARES', 'GAUSSIAN_RMS_SCATTER', 'HEALTHY_KURTOSIS_SCATTER', 'OWN_DRAWS', 'SyntheticPlan',
           'synthetic_table']

#: Effects this simulator draws and applies with its own code (the others go through their simulation hook).
OWN_DRAWS = ('position_dependent_stiffness', 'resonance', 'thermal_viscosity', 'lubricant_depletion',
             'background_vibration')
#: Standard deviation of a healthy window's band kurtosis around 3 (about sqrt(24 / n) for n = 4000 samples).
HEALTHY_KURTOSIS_SCATTER = 0.08
#: Relative scatter of a window's measured Gaussian RMS (median |x| of a 1 s window of band-limited vibration:
#: a few hundred independent samples and more).
GAUSSIAN_RMS_SCATTER = 0.03


@dataclass(frozen=True)
class SyntheticPlan:
    """What is recorded: conditions, repeats, run order, window length and noise."""

    speeds_rpm: tuple = (100.0, 150.0, 200.0)
    loads: tuple = (100.0, 200.0)
    repeats: int = 2                # each condition this often per session
    sessions: int = 1               # sessions, each after a relubrication (revolutions restart), one recording each
    session_pause: float = 60.0     # s between sessions (oil injection; the actuator cools)
    random_order: bool = True
    stroke: float = 0.17            # m of steady travel per run
    lead: float = 0.005             # m per revolution
    window: float = 1.0             # s
    rest: float = 30.0              # s between runs
    window_noise: float = 0.02      # std of ln RMS per window
    run_noise: float = 0.005        # std of ln RMS per run (set-up scatter)
    record_temperature: bool = True
    ambient: float = 25.0           # degC
    theta: float = 1.0
    constants: ModelConstants = field(default_factory=lambda: ModelConstants(0.02, -1.0e-3, 0.33))
    spectrum_bins: int = 0          # > 0: synthesise spectra with this many bins up to 2 kHz
    # Out and back, physics outside the catalogue, temperature histories (all off by default):
    out_and_back: bool = False      # each run followed by a return at its speed and load (direction -1)
    return_factor: float = 1.0      # amplitude factor of the returns (flank loading, backlash, preload)
    step_factor: float = 1.0        # amplitude factor from run step_at x runs on (the sensor re-seated)
    step_at: float = 0.5
    warm_start: float = 0.0         # K above ambient at the start (thermal: a warm actuator cooling)
    cool_down_every: int = 0        # runs between cool-down pauses (0: none)
    cool_down_pause: float = 0.0    # s of standstill of each pause (the nut cools, revolutions stand still)
    condition_indicators: bool = False   # columns kurtosis, crest_factor, defect_db, defect_order per window


def _draw_effect(effect: str, rng: np.random.Generator, plan: SyntheticPlan) -> dict:
    """Effect parameters drawn within physical ranges, the effect's form among its physical forms."""
    if effect not in OWN_DRAWS:
        context = _context(plan)
        hook = simulation(effect)
        law = hook.draw(rng, context)
        return {'law': law, 'extension': hook.extension_params(law, context)}
    top = max(plan.speeds_rpm) * math.pi / 30
    bottom = min(plan.speeds_rpm) * math.pi / 30
    if effect == 'position_dependent_stiffness':
        change = rng.uniform(0.08, 0.3)                  # amplitude change over the stroke
        offset = rng.uniform(0.02, 0.1)                  # bearing distance beyond the stroke, m
        arrangement = ('fixed-free', 'free-fixed', 'fixed-fixed')[int(rng.integers(3))]
        if arrangement == 'fixed-fixed':
            other = rng.uniform(0.02, 0.1)
            return {'arrangement': arrangement, 'bearing_before': offset, 'bearing_after': other,
                    'contact_ratio': _contact_ratio_for(change, arrangement, plan.stroke, offset, other)}
        far = arrangement == 'fixed-free'                # bearing beyond the far end or before the start
        length_end = offset if far else offset + plan.stroke
        length_start = offset + plan.stroke if far else offset
        # 1 + rho L_a/L_ref vs 1 + rho L_b/L_ref: solve rho (at the longer length) for the change.
        long, short = max(length_start, length_end), min(length_start, length_end)
        # (1 + rho_long) / (1 + rho_long short/long) = 1 / (1 - change)
        rho_long = (1 / (1 - change) - 1) / (1 - (short / long) / (1 - change))
        return {'free_length_start': length_start, 'free_length_end': length_end,
                'ratio_long': rho_long, 'long_length': long, 'change': change, 'arrangement': arrangement}
    if effect == 'resonance':
        band = ('above', 'inside', 'below')[int(rng.integers(3))]
        if band == 'above':
            ratio = rng.uniform(0.55, 0.9)
        elif band == 'inside':
            ratio = (top / bottom) ** rng.uniform(0.3, 0.7)
        else:
            ratio = rng.uniform(1.3, 2.5) * top / bottom
        return {'top_ratio': ratio, 'damping_ratio': rng.uniform(0.02, 0.1), 'top_speed': top, 'band': band}
    if effect == 'thermal_viscosity':
        law = thermal.LAWS[int(rng.integers(len(thermal.LAWS)))]
        return {'rise': rng.uniform(8.0, 25.0), 'tau': rng.uniform(150.0, 600.0), 'beta': rng.uniform(0.02, 0.04),
                'law': law, 'shape': {'vogel': rng.uniform(90.0, 150.0),
                                      'walther': rng.uniform(30.0, 300.0)}.get(law, math.nan)}
    if effect == 'lubricant_depletion':
        return {'fall': rng.uniform(0.08, 0.25), 'form': depletion.FORMS[int(rng.integers(2))],
                'recovery_time': None if rng.integers(2) else rng.uniform(30.0, 120.0)}
    if effect == 'background_vibration':
        return {'fraction': rng.uniform(*background_vibration.FRACTION_RANGE),
                'tones': tuple(rng.uniform(60, 900, size=2)),
                'form': background_vibration.FORMS[int(rng.integers(3))]}
    raise ValueError(effect)


def _plain(params: dict) -> dict:
    """An effect's drawn parameters for the truth: a hooked effect's law as a plain mapping (JSON-ready)."""
    law = params.get('law')
    return {**params, 'law': asdict(law)} if is_dataclass(law) and not isinstance(law, type) else params


def _context(plan: SyntheticPlan) -> SimulationContext:
    """What a hooked effect is drawn against: the plan's conditions, one session's revolutions, 4 kHz sampling."""
    conditions = len(plan.speeds_rpm) * len(plan.loads) * plan.repeats
    slow = min(plan.speeds_rpm) * math.pi / 30
    return SimulationContext(
        actuator=Actuator(lead=plan.lead), speeds=tuple(s * math.pi / 30 for s in plan.speeds_rpm),
        loads=tuple(float(f) for f in plan.loads), stroke=plan.stroke,
        session_revolutions=conditions * plan.stroke / plan.lead,
        reference_amplitude=float(acceleration_amplitude(slow, max(plan.loads), plan.theta, plan.constants)),
        sample_rate=4000.0, band_high=1600.0)


def _contact_ratio_for(change: float, arrangement: str, stroke: float, before: float, after: float) -> float:
    """k_c / (E A), 1/m, that changes the amplitude by ``change`` over the stroke (at the mean load)."""
    x = np.linspace(0.0, stroke, 101)
    compliance = 1.0 / stiffness.shaft_stiffness_for(arrangement, 1.0, math.sqrt(4 / math.pi), x, stroke, before,
                                                     after)
    return float(change / (np.ptp(compliance) - change * np.max(compliance)))


#: Power shares (each tone, broadband) of the background by form ('': no form given, tones with some floor).
BACKGROUND_SHARES = {'': (0.35, 0.3), background_vibration.FORMS[0]: (0.5, 0.0),
                     background_vibration.FORMS[1]: (0.0, 1.0), background_vibration.FORMS[2]: (0.1, 0.8)}


def _given_laws(rng: np.random.Generator, effect: str | tuple[str, ...] | None, plan: SyntheticPlan,
                params: dict | None) -> dict[str, dict]:
    """Each hidden effect's parameters: those given in ``params``, the others drawn (see :func:`synthetic_table`)."""
    if effect is None or isinstance(effect, str):
        given = {effect: params} if effect else {}
    else:
        given = {name: (params or {}).get(name) for name in effect}
    return {name: dict(p) if p is not None else _draw_effect(name, rng, plan) for name, p in given.items()}


class _Synthesis:
    """The synthetic actuator walked through the plan: its state and the table's columns so far."""

    def __init__(self, plan: SyntheticPlan, laws: dict[str, dict], rng: np.random.Generator,
                 total_revs: float) -> None:
        """At the start: time and revolutions 0, the nut ``plan.warm_start`` K above ambient, no columns yet."""
        self.plan, self.laws, self.rng, self.total_revs = plan, laws, rng, total_revs
        self.heat, self.loss, self.noise_floor = (laws.get('thermal_viscosity'), laws.get('lubricant_depletion'),
                                                  laws.get('background_vibration'))
        self.rows: dict[str, list] = {k: [] for k in ('speed', 'load', 'rms', 'position', 'revolutions', 'time',
                                                      'temperature', 'run', 'recording')}
        self.theta_eff: list[float] = []
        self.spectra: list[np.ndarray] = []
        self.a22_list: list[float] = []
        self.directions: list[float] = []
        self.clock, self.revs, self.temp = 0.0, 0.0, plan.ambient + plan.warm_start
        self.turns = 0.0      # revolutions run over all sessions (a spall does not heal at relubrication)
        self.indicators: dict[str, list[float]] = {k: [] for k in ('kurtosis', 'crest_factor', 'defect_db',
                                                                   'defect_order', 'gaussian_rms')}
        # The indicators' own stream (spawned, not drawn from rng): with or without them, the other columns agree.
        self.indicator_rng = rng.spawn(1)[0]
        # The Gaussian part's scatter has a stream of its own too: the indicators drawn before it was measured stay.
        self.gaussian_rng = rng.spawn(1)[0]
        self.depleted = 0.0   # effective revolutions of the depletion (recovering at rest)

    def pause(self, number: int, way: int, per_session: int) -> None:
        """Before run ``number`` (out: ``way`` > 0): a relubrication between sessions or a cool-down pause."""
        plan, heat = self.plan, self.heat
        if way > 0 and number and number % per_session == 0:
            self.revs, self.clock, self.depleted = 0.0, 0.0, 0.0   # relubricated; a new recording starts
            if heat:
                self.temp = plan.ambient + (self.temp - plan.ambient) * math.exp(-plan.session_pause / heat['tau'])
        elif way > 0 and number and plan.cool_down_every and number % plan.cool_down_every == 0:
            self.clock += plan.cool_down_pause
            if heat:
                self.temp = plan.ambient + (self.temp - plan.ambient) * math.exp(-plan.cool_down_pause / heat['tau'])

    def run(self, run: int, session: int, way: int, factor: float, speed: float, load: float) -> None:
        """The windows of one run at ``speed`` rad/s and ``load`` N, out or back (``way``), set-up ``factor``."""
        plan, rng = self.plan, self.rng
        nut_speed = plan.lead * speed / (2 * math.pi)
        n_win = max(int(plan.stroke / nut_speed / plan.window), 3)
        run_gain = rng.normal(0.0, plan.run_noise)
        for k in range(n_win):
            self.clock += plan.window
            self.revs += speed * plan.window / (2 * math.pi)
            self.turns += speed * plan.window / (2 * math.pi)
            self.depleted += speed * plan.window / (2 * math.pi)
            if self.heat:
                target = plan.ambient + self.heat['rise']
                self.temp = target + (self.temp - target) * math.exp(-plan.window / self.heat['tau'])
            position = (k + 0.5) * plan.window * nut_speed
            position = position if way > 0 else plan.stroke - position
            self._window(run, session, way, speed, load, position, factor, run_gain)

    def _window(self, run: int, session: int, way: int, speed: float, load: float, position: float,
                factor: float, run_gain: float) -> None:
        """One window's row (with scatter: the run's ``run_gain``, its own, the set-up ``factor``) and truth."""
        plan, rng, noise_floor, rows = self.plan, self.rng, self.noise_floor, self.rows
        theta, film, a22, amplitude = _window_amplitude(plan, self.laws, speed, load, position, self.depleted,
                                                        self.total_revs, self.temp, self.turns)
        contact_power = a22 ** 2     # the contacts alone (before the hooked effects add to the amplitude)
        noise = factor * math.exp(run_gain + rng.normal(0.0, plan.window_noise))
        amplitude *= noise
        background = 0.0
        if noise_floor:
            slow = min(plan.speeds_rpm) * math.pi / 30
            reference = float(acceleration_amplitude(slow, max(plan.loads), plan.theta, plan.constants))
            background = noise_floor['fraction'] * reference
            amplitude = float(background_vibration.total_amplitude(amplitude, background))
        rows['speed'].append(speed * (1 + rng.normal(0, 0.002)))
        rows['load'].append(load * (1 + rng.normal(0, 0.005)))
        rows['rms'].append(amplitude)
        rows['position'].append(position)
        rows['revolutions'].append(self.revs)
        rows['time'].append(self.clock)
        rows['temperature'].append(self.temp + rng.normal(0, 0.05) if plan.record_temperature else math.nan)
        rows['run'].append(run)
        rows['recording'].append(session)
        self.directions.append(float(way))
        self.theta_eff.append(theta * film)
        self.a22_list.append(a22)
        if plan.condition_indicators:
            self._indicators(speed, load, position, float(contact_power), amplitude, noise)
        if plan.spectrum_bins:
            self.spectra.append(_spectrum(plan, speed, amplitude ** 2 - background ** 2, background,
                                          (noise_floor or {}).get('tones', ()), rng,
                                          (noise_floor or {}).get('form', '')))

    def _indicators(self, speed: float, load: float, position: float, contact_power: float, amplitude: float,
                    noise: float) -> None:
        """One window's condition indicators: Gaussian contact vibration, changed by hooked effects.

        Healthy: kurtosis ``3 + N(0, HEALTHY_KURTOSIS_SCATTER)``, crest factor
        about 4, the largest envelope peak at a defect order 3 dB over the floor
        (chi-square scatter), no order, and the whole RMS ``amplitude`` Gaussian
        (``gaussian_rms`` with :data:`GAUSSIAN_RMS_SCATTER`).  A hooked effect's
        ``Simulation.window_indicators`` replaces what it changes (its kurtosis
        excess with a 10 % scatter); the ``impulsive_power`` it returns (before
        the window's scatter factor ``noise``) leaves the Gaussian part.
        """
        rng = self.indicator_rng
        columns = {'kurtosis': 3.0 + HEALTHY_KURTOSIS_SCATTER * rng.standard_normal(),
                   'crest_factor': 4.0 + 0.3 * rng.standard_normal(),
                   'defect_db': 10.0 * math.log10(1.0 + rng.chisquare(2) / 2.0), 'defect_order': math.nan}
        state = ContactState(speed=speed, load=load, nut_position=position, temperature=self.temp,
                             ambient_temperature=self.plan.ambient, revolutions=self.turns)
        impulsive = 0.0
        for name, law in self.laws.items():
            if name in OWN_DRAWS:
                continue
            changed = simulation(name).window_indicators(law['law'], state, np.asarray(contact_power))
            for key, column in changed.items():
                number = float(column)
                if key == 'impulsive_power':
                    impulsive += number
                    continue
                if key == 'kurtosis':
                    number = columns['kurtosis'] + (number - 3.0) * math.exp(0.1 * rng.standard_normal())
                columns[key] = number
        gaussian = math.sqrt(max(amplitude ** 2 - impulsive * noise ** 2, 0.0))
        columns['gaussian_rms'] = gaussian * (1.0 + GAUSSIAN_RMS_SCATTER * self.gaussian_rng.standard_normal())
        for key, number in columns.items():
            self.indicators[key].append(float(number))

    def rest(self) -> None:
        """The rest after a run: the clock runs on, oil creeps back (with recovery), the nut cools."""
        plan = self.plan
        self.clock += plan.rest
        if self.loss and self.loss.get('recovery_time'):
            self.depleted *= math.exp(-plan.rest / self.loss['recovery_time'])
        if self.heat:
            self.temp = plan.ambient + (self.temp - plan.ambient) * math.exp(-plan.rest / self.heat['tau'])

    def table(self) -> WindowTable:
        """The window table of the windows so far."""
        plan = self.plan
        resolution = 2000.0 / plan.spectrum_bins if plan.spectrum_bins else math.nan
        columns = {key: np.array(values, dtype=float) if plan.condition_indicators else None
                   for key, values in self.indicators.items()}
        return WindowTable(theta=plan.theta, direction=cast(Any, self.directions),  # __post_init__ makes arrays
                           spectra=np.array(self.spectra) if self.spectra else None, spectrum_resolution=resolution,
                           kurtosis=columns['kurtosis'], crest_factor=columns['crest_factor'],
                           defect_db=columns['defect_db'], defect_order=columns['defect_order'],
                           gaussian_rms=columns['gaussian_rms'],
                           **cast(dict[str, Any], self.rows))


def synthetic_table(rng: np.random.Generator, effect: str | tuple[str, ...] | None = None,
                    plan: SyntheticPlan | None = None, params: dict | None = None,
                    order: Sequence[int] | np.ndarray | None = None) -> tuple[WindowTable, dict]:
    """A window table of ``plan.sessions`` sessions with ``effect`` hidden (None: none) and its truth.

    ``effect`` is one effect ID or a tuple of IDs (several effects at once;
    ``params`` then maps each ID to its parameters, missing ones drawn).
    ``order``: run order as indices into the condition list (default: random or plan order).
    Returns ``(table, truth)``, truth with the effect, its parameters and the true theta per window.
    position_dependent_stiffness with ``params`` ``{'arrangement': one of the law's ARRANGEMENTS,
    'bearing_before': m, 'bearing_after': m, 'contact_ratio': k_c / (E A) in 1/m}`` uses the law's
    arrangement.  Forms in ``params``: thermal_viscosity ``law`` (exponential, vogel, walther) with its
    ``shape`` (K or mm^2/s); lubricant_depletion ``form`` (exponential, linear) and ``recovery_time`` (s at
    rest, None: none); background_vibration ``form`` (one of the law's FORMS); resonance any ``top_ratio``
    (r at the top speed: the mode above, inside or below the band).
    """
    plan = plan or SyntheticPlan()
    laws = _given_laws(rng, effect, plan, params)
    conditions = [(s * math.pi / 30, f) for _ in range(plan.repeats) for s in plan.speeds_rpm for f in plan.loads]
    if order is None:
        order = np.concatenate([rng.permutation(len(conditions)) if plan.random_order
                                else np.arange(len(conditions)) for _ in range(plan.sessions)])
    synthesis = _Synthesis(plan, laws, rng, sum(plan.stroke / plan.lead for _ in conditions))
    per_session = max(len(order) // plan.sessions, 1)
    legs = [(number, index, way) for number, index in enumerate(order) for way in ((1, -1) if plan.out_and_back
                                                                                   else (1,))]
    for run, (number, index, way) in enumerate(legs):
        session = number // per_session
        synthesis.pause(number, way, per_session)
        factor = ((plan.return_factor if way < 0 else 1.0)
                  * (plan.step_factor if run >= plan.step_at * len(legs) else 1.0))
        synthesis.run(run, session, way, factor, *conditions[index])
        synthesis.rest()
    table = synthesis.table()
    plain = {name: _plain(params) for name, params in laws.items()}
    if effect is None or isinstance(effect, str):
        drawn = plain.get(effect, {}) if effect else {}       # no effect: no laws
    else:
        drawn = plain
    truth = {'effect': effect, 'params': drawn,
             'theta_effective': np.array(synthesis.theta_eff), 'amplitude_eq22': np.array(synthesis.a22_list)}
    return table, truth


def _spectrum(plan: SyntheticPlan, speed: float, contact_power: float, background: float, tones: Sequence[float],
              rng: np.random.Generator, form: str = '') -> np.ndarray:
    """PSD ((m/s^2)^2/Hz) of one window: order lines + broadband of the contacts, fixed tones + white background."""
    bins = plan.spectrum_bins
    df = 2000.0 / bins
    freqs = np.arange(bins) * df
    psd = np.zeros(bins)
    rotation = speed / (2 * math.pi)

    def line(freq: float, power: float) -> None:
        """Add a line of ``power`` ((m/s^2)^2) at ``freq`` Hz, a narrow Gaussian in frequency."""
        if 0 < freq < 2000.0 - df:
            width = max(0.4 * df, 0.005 * freq)
            shape = np.exp(-0.5 * ((freqs - freq) / width) ** 2)
            psd[:] += power * shape / (shape.sum() * df)

    for order, share in ((10.0, 0.3), (20.0, 0.15), (33.0, 0.15)):
        line(order * rotation, share * contact_power)
    psd += 0.4 * contact_power / 2000.0
    if background > 0:
        tone_share, floor_share = BACKGROUND_SHARES[form]
        for tone in tones if tone_share else ():
            line(tone, tone_share * background ** 2)
        psd += floor_share * background ** 2 / 2000.0
    return psd * rng.chisquare(8, size=bins) / 8


def _window_amplitude(plan: SyntheticPlan, laws: dict, speed: float, load: float, position: float,
                      depleted: float, total_revs: float, temp: float,
                      turns: float = 0.0) -> tuple[float, float, float, float]:
    """One window's truth before noise: (theta, film factor, Eq. 22 amplitude, amplitude with the laws), m/s^2.

    ``depleted``: effective revolutions of the depletion, of ``total_revs`` in the plan; ``temp`` degC;
    ``turns`` revolutions run over all sessions (read by hooked effects as their ``revolutions``).
    """
    stiff, res = laws.get('position_dependent_stiffness'), laws.get('resonance')
    heat, loss = laws.get('thermal_viscosity'), laws.get('lubricant_depletion')
    theta = plan.theta
    film = 1.0
    if loss:
        form = loss.get('form', 'exponential')
        fall = -math.log1p(-loss['fall']) if form == 'exponential' else loss['fall']
        theta *= float(depletion.theta_factor(depleted, fall / total_revs, form))
    if heat:
        film = float(thermal.film_factor(temp, plan.ambient, heat['beta'], heat.get('law', 'exponential'),
                                         heat.get('shape', math.nan)))
    hooked = [(extension(name), law['extension']) for name, law in laws.items() if name not in OWN_DRAWS]
    window = SimpleNamespace(speed=speed, load=load, position=position, revolutions=turns, temperature=temp,
                             time=math.nan, recording=None)
    for ext, params in hooked:
        film *= float(ext.film_factor(params, window))
    a22 = float(acceleration_amplitude(speed, load, theta * film, plan.constants))
    amplitude = a22
    if stiff and 'contact_ratio' in stiff:
        # Any arrangement through the law: EA = 1, contact_ratio = k_c / (E A) in 1/m.
        shaft = stiffness.shaft_stiffness_for(stiff['arrangement'], 1.0, math.sqrt(4 / math.pi), position,
                                              plan.stroke, stiff['bearing_before'], stiff['bearing_after'])
        contact = stiffness.contact_stiffness_at(load, stiff['contact_ratio'], float(np.mean(plan.loads)))
        amplitude *= float(stiffness.series_stiffness_amplification(contact, shaft))
    elif stiff:
        length = stiff['free_length_start'] + (stiff['free_length_end']
                                               - stiff['free_length_start']) * position / plan.stroke
        contact = stiffness.contact_stiffness_at(load, stiff['ratio_long'] / stiff['long_length'],
                                                 float(np.mean(plan.loads)))
        amplitude *= float(stiffness.series_stiffness_amplification(contact, 1.0 / length))
    if res:
        r = res['top_ratio'] * speed / res['top_speed']
        amplitude *= float(resonance.magnification(r, res['damping_ratio']))
    for ext, params in hooked:
        amplitude *= float(np.exp(ext.log_gain(params, window, math.log(amplitude))))
    return theta, film, a22, amplitude
