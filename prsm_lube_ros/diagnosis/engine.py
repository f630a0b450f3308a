# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Diagnosis: fit the paper's model, locate the mismatch, fit every candidate, rank them and decide.

An effect with several physical forms (:meth:`.effects.Effect.variants`: the
shaft stiffness of each bearing arrangement, a mode below, inside or above the
speed band, the viscosity laws, depletion exponential or linear, with or
without recovery at rest) is fitted in each on all windows; of the forms whose
constants are physical (all forms when none is), the one with the lowest BIC
stands for it, except that a form with more parameters than the
best of the fewest-parameter forms must lower the BIC by ``rules.form_margin``;
forms with as many parameters within ``rules.form_tie`` of it are named with it
("Vogel or Walther (ASTM D341)": the data fit them equally well); the forms
of a law swept within runs (position) are compared on the windows'
deviations from their run means (``rules.within_run_share``).  Only the
chosen form is scored on held-out runs.  Its name is in the JSON (``form``,
and ``forms`` with every form's BIC relative to it).

Two effects at once (forward selection): once an effect is named, the
residual it leaves is tested the same way (lack of fit and located pattern);
when something remains, each other candidate (in its own chosen form) is
fitted together with the first, and the best pair is kept when the second
effect earns its place by the rules of :func:`_add_second`; when nothing
remains, only candidates with evidence at standstill are tried (a floor the
first effect's fit absorbed), or with evidence no other effect makes in
``rules.exclusive_evidence_share`` of the windows (impulsive strikes; per operating condition); such a
candidate that no rule of :func:`_add_second` keeps is named all the same,
its share of the RMS unresolved (:func:`_exclusive_second`).  Both are then
reported (``effects`` in the JSON; ``verdict`` and ``best`` stay the first).

A candidate *earns its extra parameters* when, with physical constants
(C_lambda > 0), it lowers the BIC (effective sample size, see
:mod:`.fitting`) by ``rules.bic_margin`` or more **and** lowers the held-out
error by ``rules.min_gain`` or more; or when evidence from outside the
amplitude fit (the spectrum's fixed lines or the vibration at standstill for
background vibration, a mode band for a resonance) shows it
and it does not predict held-out runs worse.  A candidate whose law can mimic
others in the amplitudes (:attr:`.effects.Effect.requires_evidence`: a surface
defect's added power with free exponents) is fitted only where its evidence
shows (impulsive windows); elsewhere it is rejected unfitted, with what argues
against it.  Earning candidates rank by
held-out error.  When the runner-up comes close (half the leader's gain or
more) both are fitted together and each is tested for what it adds given the
other: the one that adds nothing is dropped.  If neither adds anything, the
amplitudes cannot tell them apart; evidence from outside the fit decides if it
favours one (a background shows fixed spectral lines, or the spectra could
show them and do not); otherwise the verdict is ``ambiguous`` with both listed
and what to record to separate them.

Adequacy is tested, not assumed, at the level of runs (every traverse has its
own set-up factor, so run-to-run scatter is noise, not physics):
:func:`.adequacy.lack_of_fit` tests the condition means against the scatter
of repeated runs (pure error), and that scatter against what a rig's set-up
gives.  ``adequate`` needs no candidate to earn its parameters, no lack of
fit, no excess run scatter *and* no covariate left carrying the residual;
otherwise, with no candidate, the verdict is ``unexplained`` with where the
residual lives and its size, unless the residual is located on a candidate's
own covariate and its law explains it (:func:`_located_law`: a BIC drop of
``rules.located_law_bic`` and the held-out gain, or for a law swept within runs
what it shows there; no pattern left there, and better held-out predictions
than the empirical term of the located shape).  A plan with no repeated condition cannot tell
run scatter from model error: ``cannot tell``, with what to record.
``confident`` is true only when the chosen model (the paper's for
``adequate``) passes the lack-of-fit test; the statistics are in the JSON
under ``adequacy``.  Calibration flags (``prsm-lube calibrate``'s warnings)
are carried into the JSON as ``flags``.

Verdicts: an effect ID; ``adequate`` (no candidate earns its parameters and the model fits within the noise);
``ambiguous`` (tied candidates in ``tied``, or none earns its parameters but
the run order is confounded with speed or load, so adequacy cannot be
confirmed); ``unexplained`` (the residual is
strongly structured or the baseline constants are unphysical, yet no
candidate explains it); ``cannot tell`` (the paper's model fits, but the
operating plan has too few (speed, load) conditions beyond the three
constants to test its form, e.g. three conditions on one line: the fit is
exact whatever the truth, so adequacy means nothing; see
:func:`~prsm_lube_ros.estimation.calibration.form_flag`).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from enum import StrEnum
import math
from typing import Any, cast, Collection, Generic, Mapping, Sequence, TYPE_CHECKING, TypeVar

import numpy as np

from ..errors import InputError
from ..estimation.calibration import (Calibration, calibration_flags, check_identifiable, form_advice, form_flag,
                                      form_testable, operating_conditions, operating_levels, replicated_conditions,
                                      run_level_covariance)
from ..validation import finite_or_none
from .adequacy import lack_of_fit, LackOfFit, REPEAT_ADVICE
from .combined import CombinedEffect
from .effects import Effect, registered
from .empirical import causes, empirical_terms, EmpiricalTerm
from .fitting import bic, constants_jacobian, cv_folds, effective_sample_size, fit_model, fit_vector, ModelFit, \
    predict_log, score_held_out, within_run_correlation, within_run_delta_bic, within_run_gain, \
    within_run_residual, within_run_sample_size, within_run_share
from .locate import covariate_tests, locate, Location, partial_trend
from .rules import DEFAULT_RULES, DiagnosisRules
from .table import DRIFT_COVARIATES, PLAN_COVARIATES, WindowTable

if TYPE_CHECKING:
    from ..estimation.run_scatter import RunScatter

#: An effect, or a combination of two (:func:`_choose_form` returns the kind it is given).
_E = TypeVar('_E', bound=Effect)
_T = TypeVar('_T')

__all__ = ['ADEQUATE', 'AMBIGUOUS', 'CANNOT_TELL', 'Candidate', 'CandidateFit', 'Confounding',
           'Decision', 'Diagnosis', 'EmpiricalFit', 'OUTCOMES', 'SecondEffect', 'Status', 'UNEXPLAINED', 'Verdict',
           'confounding', 'diagnose_table', 'drift_correlation', 'evidence_tolerance', 'same_shape_covariates']


class Verdict(str):
    """What a diagnosis concludes: the ID of the (first) effect it names, or one of the words of :data:`OUTCOMES`.

    A ``str`` (the JSON's ``verdict`` and every comparison with a word or an
    effect ID keep working); :attr:`names_an_effect` tells the two kinds apart.
    """

    __slots__ = ()

    @property
    def names_an_effect(self) -> bool:
        """True when the verdict is an effect ID, not one of the four words."""
        return str(self) not in OUTCOMES


ADEQUATE, AMBIGUOUS, UNEXPLAINED, CANNOT_TELL = (Verdict(word) for word in
                                                 ('adequate', 'ambiguous', 'unexplained', 'cannot tell'))
#: The verdicts that name no effect.
OUTCOMES = frozenset({'adequate', 'ambiguous', 'unexplained', 'cannot tell'})


class Status(StrEnum):
    """Where a candidate stands; the values are the words of the text, the JSON and the report."""

    EARNS = 'earns'                 # explains the mismatch well enough to be named
    REJECTED = 'rejected'           # fitted, but does not earn its parameters (the reason says which rule)
    NOT_TESTABLE = 'not testable'   # the recording cannot show it (the reason says what to record)
    DROPPED = 'dropped'             # earned alone, but another effect explains it (or more)


@dataclass(frozen=True)
class Decision:
    """One rule's decision on a candidate: which rule, the status it gives, and why in words.

    ``restart``: the text replaces the account so far (a later rule that names
    a candidate the earlier ones rejected); otherwise it is added to it.
    """

    rule: str
    status: Status
    text: str
    restart: bool = False


@dataclass(frozen=True)
class CandidateFit:
    """What fitting one candidate gave (the results, apart from any decision): its chosen form's fit and scores."""

    effect: Effect
    fit: ModelFit | None
    gain: float = math.nan      # 1 - cv_rmse / baseline cv_rmse
    delta_bic: float = math.nan
    evidence: str = ''
    form: str = ''              # the chosen form's name
    forms: tuple = ()           # (form name, BIC relative to the chosen form)
    family: Effect | None = None                # the registered effect (all its forms)
    form_vectors: Mapping[str, np.ndarray] = field(default_factory=dict)   # form -> its fitted internal parameters
    within_delta_bic: float = math.nan          # BIC drop on deviations from run means (a law swept within runs)
    within_gain: float = math.nan               # held-out gain on those deviations (the shape of held-out runs)


class _FromScores(Generic[_T]):
    """A :class:`Candidate` attribute that is its :class:`CandidateFit`'s (the results, read-only)."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, candidate: Candidate, owner: type | None = None) -> _T:
        return cast(_T, getattr(candidate.scores, self.name))


@dataclass
class Candidate:
    """One candidate effect: its fit results and the decisions of the rules on it, in order (the last one stands)."""

    scores: CandidateFit
    decisions: tuple[Decision, ...]

    def decide(self, decision: Decision) -> None:
        """Add a rule's decision (the decisions themselves are immutable values)."""
        self.decisions = (*self.decisions, decision)

    @property
    def status(self) -> Status:
        """The status the last decision gave."""
        return self.decisions[-1].status

    @property
    def reason(self) -> str:
        """The decisions' words from the last one that restarts the account on."""
        restart = max((i for i, d in enumerate(self.decisions) if d.restart), default=0)
        return '; '.join(d.text for d in self.decisions[restart:])

    #: The fit results, read from :attr:`scores`.
    effect = _FromScores[Effect]()          # the effect in its chosen form
    fit = _FromScores['ModelFit | None']()  # the chosen form's fit (None when the candidate was not fitted)
    gain = _FromScores[float]()             # 1 - cv_rmse / the paper's model's cv_rmse
    delta_bic = _FromScores[float]()        # BIC against the paper's model
    evidence = _FromScores[str]()           # evidence from outside the amplitude fit ('' when none)
    form = _FromScores[str]()               # the chosen form's name (with the forms that fit as well)

    def as_json(self) -> dict:
        """Mapping for the ``candidates`` list."""
        scores = self.scores
        out: dict[str, Any] = {
            'effect': self.effect.id, 'title': self.effect.title, 'status': self.status,
            'reason': self.reason, 'equations': self.effect.equations, 'form': self.form,
            'forms': [{'form': name, 'delta_bic': finite_or_none(delta)} for name, delta in scores.forms],
            'parameters': list(self.effect.parameter_names), 'evidence': self.evidence,
            'decisions': [{'rule': d.rule, 'status': d.status, 'text': d.text} for d in self.decisions]}
        if self.fit is not None:
            c = self.fit.constants
            out.update({'rmse': finite_or_none(self.fit.rmse), 'cv_rmse': finite_or_none(self.fit.cv_rmse),
                        'cv_run_rmse': finite_or_none(self.fit.cv_run_rmse), 'gain': finite_or_none(self.gain),
                        'delta_bic': finite_or_none(self.delta_bic),
                        'effective_windows': finite_or_none(self.fit.n_eff),
                        'within_run_delta_bic': finite_or_none(scores.within_delta_bic),
                        'within_run_gain': finite_or_none(scores.within_gain), 'params': _clean(self.fit.params),
                        'constants': c.by_name(),
                        'explanation': self.effect.describe(self.fit.params)})
        return out


@dataclass(frozen=True)
class SecondEffect:
    """A second effect named with the first: the pair's fit and what the second adds."""

    candidate: Candidate        # the second effect alone (its first-round fit)
    fit: ModelFit               # both effects fitted together
    params: dict                # the second effect's parameters in the joint fit
    gain: float                 # 1 - cv_rmse(pair) / cv_rmse(first alone)
    delta_bic: float            # BIC(pair) - BIC(first alone)
    effect: Effect              # the second effect in the form chosen on top of the first
    form: str                   # its name
    first_effect: Effect        # the first effect in its form in the pair
    first_params: dict          # and its parameters in the joint fit
    first_form: str
    combined: CombinedEffect | None = None   # the joint model ``fit`` belongs to
    basis: str = ''             # why it is named on top of the first (see :func:`_add_second`)
    route: int = 1              # the rule that named it: 1-3 of :func:`_add_second`, 4 exclusive, 5 Gaussian part
    run_gain: float = math.nan  # 1 - cv_run_rmse(pair) / cv_run_rmse(first alone): held-out run amplitudes
    within_delta_bic: float = math.nan   # a law swept within runs: BIC(pair) - BIC(first) on run deviations
    within_gain: float = math.nan        # and the held-out gain there (:func:`_shows_within_runs`)
    #: Named by evidence no other effect makes (:func:`_exclusive_second`), its amplitude law not kept: ``fit``
    #: and ``first_params`` are the first effect's alone, ``params`` empty, its share of the RMS unresolved.
    unresolved: bool = False

    @property
    def explanation(self) -> str:
        """What the second effect is, in words: its fitted law, or why its share of the RMS is unresolved."""
        if self.unresolved:
            shown = 'by evidence no other effect makes' if self.route == 4 else 'in the windows\' Gaussian part'
            return (f'{self.effect.title} shown {shown} ({self.basis}); its share of the RMS '
                    f'is unresolved: its amplitude law is not kept beside {self.first_effect.id}. '
                    + self.effect.physics)
        return self.effect.describe(self.params)

    def as_json(self) -> dict:
        """Entry of the ``effects`` list."""
        return {'effect': self.effect.id, 'form': self.form, 'params': _clean(self.params),
                'explanation': self.explanation, 'gain': finite_or_none(self.gain),
                'delta_bic': finite_or_none(self.delta_bic), 'cv_rmse': finite_or_none(self.fit.cv_rmse),
                'basis': self.basis, 'within_run_delta_bic': finite_or_none(self.within_delta_bic),
                'within_run_gain': finite_or_none(self.within_gain), 'share_unresolved': self.unresolved}

    def first_as_json(self) -> dict:
        """The first effect's entry of the ``effects`` list, with its parameters in the joint fit."""
        return {'effect': self.first_effect.id, 'form': self.first_form, 'params': _clean(self.first_params),
                'explanation': self.first_effect.describe(self.first_params)}


@dataclass(frozen=True)
class EmpiricalFit:
    """An empirical term of the located shape fitted with Eq. 22 (physics outside the catalogue)."""

    term: EmpiricalTerm
    fit: ModelFit
    gain: float                 # 1 - cv_rmse / cv_rmse of the paper's model
    delta_bic: float            # against the paper's model
    overrules: str = ''         # the catalogue effect it explains better than (held-out), if any
    rules: DiagnosisRules = DEFAULT_RULES   # the thresholds it is judged by

    @property
    def earns(self) -> bool:
        """It earns its parameters as a candidate would (BIC and held-out gain)."""
        rules = self.rules
        return self.delta_bic <= -rules.bic_margin and self.gain >= rules.min_gain and not self.fit.unphysical()

    def beats(self, named: ModelFit, covariates: Collection[str] = ()) -> bool:
        """True when it predicts held-out runs better than ``named`` (the catalogue model) does.

        A step, stretch or direction factor is a shape no catalogue law has: the
        catalogue model must predict held-out runs better to be named.  A step's
        or stretch's place was chosen on all runs, the held-out ones included,
        which flatters its held-out error; so it must also have the lower BIC
        with its place counted as parameters (one for a step, its start and
        its end for a stretch; a warm actuator cooling down
        follows its thermal law as closely as a step, with the place found in
        the temperature recorded).  A smooth term follows any monotone or
        curved law, so it overrules the catalogue model only when it is better
        by ``rules.min_gain``, and never in one of ``covariates``, those the
        named effects follow (their law is a smooth law of it: a curve fitting
        better says the law's form is approximate, not that the physics is
        missing).
        """
        if not self.earns or not named.cv_rmse > 0:
            return False
        if self.term.form == 'smooth' and self.term.covariate in covariates:
            return False
        if self.term.form in ('step', 'stretch'):
            # the BIC cost of the place: one run for a step, the first and the last for a stretch
            place = (2 if self.term.form == 'stretch' else 1) * math.log(max(self.fit.n_eff, 2.0))
            if not _delta_bic(self.fit, named) + place < 0:
                return False
        margin = self.rules.min_gain if self.term.form == 'smooth' else 0.0
        return self.fit.cv_rmse < (1.0 - margin) * named.cv_rmse

    @property
    def note(self) -> str:
        """What the empirical term shows, in words."""
        term = self.term
        return (f'physics outside the catalogue: the mismatch is modelled empirically as a {term.form} in '
                f'{term.covariate} ({term.describe(self.fit.params)}), held-out error {100 * self.gain:.0f} % '
                f'lower than the paper\'s model, BIC {self.delta_bic:+.0f}; no catalogue effect has this shape. '
                f'Causes: {causes(term)}')

    def as_json(self) -> dict:
        """The ``empirical`` block."""
        term = self.term
        out: dict[str, Any] = {
            'covariate': term.covariate, 'form': term.form, 'params': _clean(self.fit.params),
            'explanation': term.describe(self.fit.params), 'gain': finite_or_none(self.gain),
            'delta_bic': finite_or_none(self.delta_bic), 'cv_rmse': finite_or_none(self.fit.cv_rmse),
            'earns': self.earns,
            'causes': causes(term), 'overrules': self.overrules or None,
            'constants': self.fit.constants.by_name()}
        if term.form in ('step', 'stretch'):
            out['runs'] = [int(r) for r in term.runs]
        return out


@dataclass
class Diagnosis:
    """The outcome of :func:`diagnose_table`."""

    verdict: Verdict
    baseline: ModelFit
    candidates: list
    best: Candidate | None
    location: Location
    tied: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    what_to_record: str = ''
    table: WindowTable | None = None
    confounding: list = field(default_factory=list)   # Confounding findings
    baseline_fit_test: LackOfFit | None = None
    chosen_fit_test: LackOfFit | None = None
    second: SecondEffect | None = None     # a second effect named with the first (forward selection)
    calibration_flags: list = field(default_factory=list)   # what calibrate says the recordings cannot vouch for
    empirical: EmpiricalFit | None = None    # an empirical term of the located shape (physics outside the catalogue)
    temperature_revolutions: float = math.nan   # Pearson correlation of run temperature and revolutions
    rules: DiagnosisRules = DEFAULT_RULES     # the policy the verdict was reached by

    @property
    def confident(self) -> bool:
        """A named effect or adequacy backed by the final model passing the lack-of-fit test."""
        if self.verdict in (AMBIGUOUS, UNEXPLAINED, CANNOT_TELL):
            return False
        test = self.chosen_fit_test if self.chosen is not None else self.baseline_fit_test
        return test is None or not test.significant

    @property
    def chosen(self) -> Candidate | None:
        """The candidate the verdict names (None for adequate, ambiguous, unexplained)."""
        return self.best if self.best is not None and self.verdict == self.best.effect.id else None

    def named_effects(self) -> list:
        """``(effect, form, params)`` of each effect the verdict names: none, one, or two (both from the joint fit)."""
        if self.chosen is None:
            return []
        if self.second is None:
            return [(self.chosen.effect, self.chosen.form, cast(ModelFit, self.chosen.fit).params)]
        second = self.second
        return [(second.first_effect, second.first_form, second.first_params),
                (second.effect, second.form, second.params)]

    def named_descriptions(self) -> list[tuple[Effect, str, str]]:
        """``(effect, form, explanation)`` of each named effect (:meth:`named_effects`).

        A second effect's explanation is :attr:`SecondEffect.explanation` (its share of the RMS may be unresolved).
        """
        named = self.named_effects()
        texts = [self.second.explanation if rank == 1 and self.second is not None else effect.describe(params)
                 for rank, (effect, _, params) in enumerate(named)]
        return [(effect, form, text) for (effect, form, _), text in zip(named, texts)]

    def calibration(self) -> Calibration:
        """Calibration from the chosen model's constants, with the effect in ``extension`` (none if adequate).

        It carries the table's analysis band and domain (:attr:`.table.WindowTable.band`, ``domain``): the
        constants were fitted on the RMS of that band, and ``assess`` must take recordings in it.
        """
        fit = self.chosen.fit if self.chosen is not None else self.baseline
        assert fit is not None  # a chosen candidate earned its parameters, so it was fitted
        effect: Effect | None = self.chosen.effect if self.chosen is not None else None
        if self.chosen is not None and self.second is not None and self.second.combined is not None:
            fit, effect = self.second.fit, self.second.combined
        table = self.table
        assert table is not None  # diagnose_table always sets it
        covariance, scatter, residual_std, method = _constant_covariance(table, fit, effect)
        extension = {'effect': effect.id, 'params': _clean(fit.params)} if effect is not None else {}
        if self.chosen is not None and self.second is not None and self.second.combined is not None:
            # Every named effect, in the order the joint model applies them (assessment undoes them backwards);
            # 'effect' and 'params' stay the first's, so readers of single-effect files still find one.
            combined = self.second.combined
            effects = [{'effect': part.id, 'form': part.form, 'params': _clean(combined.params_of(fit.params, part))}
                       for part in (combined.first, combined.second)]
            named = self.second.first_effect.id
            first = next(item for item in effects if item['effect'] == named)
            extension = {'effect': first['effect'], 'params': first['params'], 'effects': effects}
        conditions = operating_conditions(table.speed, table.load)
        flags = calibration_flags(conditions, scatter, replicated_conditions(table.speed, table.load, table.run),
                                  fit.constants, covariance)
        return Calibration(constants=fit.constants, covariance=covariance, fit_rmse=fit.rmse,
                           residual_std=residual_std, windows_used=len(table), reference_theta=table.theta,
                           speed_levels=tuple(operating_levels(table.speed)),
                           load_levels=tuple(operating_levels(table.load)), sources=table.sources,
                           extension=extension, conditions=conditions, runs=int(table.runs.size),
                           standard_errors=method, flags=flags, scatter=scatter, band=table.band,
                           domain=table.domain)

    def as_json(self) -> dict:
        """The contract's ``diagnose`` document (plus location, notes and tied candidates)."""
        base = self.baseline
        c = base.constants
        best = None
        if self.best is not None:
            f = self.best.fit
            assert f is not None  # the best candidate is one of the fitted ones
            best = {'effect': self.best.effect.id, 'form': self.best.form, 'rmse': finite_or_none(f.rmse),
                    'cv_rmse': finite_or_none(f.cv_rmse), 'cv_run_rmse': finite_or_none(f.cv_run_rmse),
                    'params': _clean(f.params), 'explanation': self.best.effect.describe(f.params),
                    'gain': finite_or_none(self.best.gain), 'delta_bic': finite_or_none(self.best.delta_bic),
                    'status': self.best.status}
        effects = []
        if self.chosen is not None:
            keys = ('effect', 'form', 'params', 'explanation', 'gain', 'delta_bic', 'cv_rmse')
            assert best is not None  # chosen is the best candidate
            effects.append({key: best[key] for key in keys})
            if self.second is not None:
                effects[0].update(self.second.first_as_json())
                effects.append(self.second.as_json())
        table = self.table
        assert table is not None  # diagnose_table always sets it
        adequacy = {'baseline': self.baseline_fit_test.as_json() if self.baseline_fit_test else None,
                    'chosen': self.chosen_fit_test.as_json() if self.chosen_fit_test else None}
        return {'verdict': self.verdict, 'confident': self.confident, 'adequacy': adequacy, 'effects': effects,
                'flags': list(self.calibration_flags),
                'tied': list(self.tied), 'what_to_record': self.what_to_record,
                'baseline': {'rmse': finite_or_none(base.rmse), 'cv_rmse': finite_or_none(base.cv_rmse),
                             'cv_run_rmse': finite_or_none(base.cv_run_rmse),
                             'constants': c.by_name(),
                             'unphysical': base.unphysical(), 'effective_windows': finite_or_none(base.n_eff)},
                'best': best, 'candidates': [cand.as_json() for cand in self.candidates],
                'location': self.location.as_json(), 'notes': list(self.notes),
                'confounding': [c.as_json() for c in self.confounding],
                'empirical': self.empirical.as_json() if self.empirical is not None else None,
                'temperature_revolutions_correlation': finite_or_none(self.temperature_revolutions),
                'data': {'windows': len(table), 'runs': int(table.runs.size),
                         'recordings': int(np.unique(table.recording).size),
                         'speed_levels': operating_levels(table.speed), 'load_levels': operating_levels(table.load),
                         'reference_theta': table.theta, 'sources': list(table.sources),
                         'standstill_rms': finite_or_none(table.rest_rms), 'standstill_windows': table.rest_windows}}


def _clean(params: dict) -> dict:
    """JSON-safe copy: non-finite floats become None."""
    out: dict[str, Any] = {}
    for key, value in params.items():
        if isinstance(value, dict):
            out[key] = _clean(value)
        elif isinstance(value, (float, int, np.floating)):
            out[key] = finite_or_none(float(value))
        else:
            out[key] = value
    return out


def _constant_covariance(table: WindowTable, fit: ModelFit,
                         effect: Effect | None) -> tuple[np.ndarray, RunScatter, float, str]:
    """Covariance of (ln C_sys, C_F, C_lambda) with the effect parameters held, under the run-effect model.

    The Jacobian J of the log prediction stands for the design matrix of
    :func:`~prsm_lube_ros.estimation.calibration.run_level_covariance`.
    Returns (covariance, run scatter, residual std, how the covariance was computed).
    """
    scales = effect.scales(table) if effect is not None else {}
    jac = constants_jacobian(table, fit.vector, effect, scales)
    dof = max(len(table) - fit.n_params, 1)
    variance = float(fit.log_residual @ fit.log_residual) / dof
    try:
        covariance, scatter, method = run_level_covariance(jac, np.asarray(fit.log_residual, float), table.run)
    except np.linalg.LinAlgError:
        raise InputError('diagnose: the constants of the chosen model cannot be identified on these recordings '
                         '(singular fit); record more distinct speeds and loads') from None
    return covariance, scatter, math.sqrt(variance), method


def _delta_bic(candidate: ModelFit, reference: ModelFit) -> float:
    """BIC(candidate) - BIC(reference) with the candidate's effective sample size."""
    n_eff = candidate.n_eff
    own = bic(candidate.log_residual, candidate.n_params, n_eff)
    return own - bic(reference.log_residual, reference.n_params, n_eff)


def _choose_form(table: WindowTable, forms: Sequence[_E], folds: list[int], rules: DiagnosisRules) \
        -> tuple[_E, ModelFit, list[tuple[str, float]], list[str], dict[str, np.ndarray]]:
    """Fit every form (Effects of one ID) on all windows; the chosen form's fit (with held-out scores) and all BICs.

    Forms are compared on one effective sample size: each fit's own would favour the form that leaves the
    more structured residual (a higher intraclass correlation lowers n_eff and so the penalty).  Forms of a law
    swept within runs (``rules.within_run_share``) are compared on the deviations from run means
    (:func:`.fitting.within_run_residual`), where their shapes along the stroke differ, with the sample size of
    the best of them there (:func:`.fitting.within_run_sample_size`: a form that misses the shape leaves
    consecutive windows correlated, which says nothing of the scatter between windows).
    """
    fits = [fit_model(table, form, folds=[]) for form in forms]
    # A free fit that trades C_lambda below zero against the form's own parameters is fitted again with C_lambda
    # held physical: on few speeds a solution with the true constants may fit as well (resonance 183).
    fits = [_physical_refit(table, form, f) if f.unphysical() else f for form, f in zip(forms, fits)]
    # A fit a measurement contradicts, of a law of load that trades against C_F (Eq. 18), may have silenced the
    # contacts that way: it is fitted again with C_F held at 0 or above as well.
    fits = [_physical_refit(table, form, f, excitation=True)
            if form.trades_load_excitation and f.vector[1] < 0
            and form.measured_against(table, f.params, _predicted(table, f)) else f
            for form, f in zip(forms, fits)]
    residuals = [f.log_residual for f in fits]
    counts = [f.n_eff for f in fits]
    shape = forms[0].added if isinstance(forms[0], CombinedEffect) else forms[0]   # a pair's forms are the added's
    if _swept_within_runs(table, shape, rules):
        # A law swept along every run: its forms differ in the shape along the run, seen within runs.
        within = [within_run_residual(table, f.log_residual) for f in fits]
        residuals, counts = [w for w, _ in within], [within_run_sample_size(within)]
    n_common = min(counts)
    scores = [bic(r, f.n_params, n_common) for r, f in zip(residuals, fits)]
    # A form whose constants no actuator gives does not stand for the effect while another form's are physical.
    eligible = [i for i, f in enumerate(fits) if not f.unphysical()] or list(range(len(fits)))
    fewest = min(fits[i].n_params for i in eligible)
    simple = min((i for i in eligible if fits[i].n_params == fewest), key=lambda i: scores[i])
    richer = [i for i in eligible if fits[i].n_params > fewest]
    chosen = simple
    if richer:
        best_richer = min(richer, key=lambda i: scores[i])
        if scores[best_richer] <= scores[simple] - rules.form_margin:
            chosen = best_richer
    fit = score_held_out(table, fits[chosen], forms[chosen], folds) if folds else fits[chosen]
    ties = [forms[i].form for i in eligible
            if i != chosen and fits[i].n_params == fits[chosen].n_params
            and scores[i] - scores[chosen] < rules.form_tie]
    vectors = {form.form: f.vector[3:] for form, f in zip(forms, fits)}
    return (forms[chosen], fit, [(form.form, score - scores[chosen]) for form, score in zip(forms, scores)],
            ties, vectors)


def _predicted(table: WindowTable, fit: ModelFit) -> np.ndarray:
    """The fitted model's amplitude of each window, m/s^2 (the measured RMS times the fit's residual)."""
    return np.exp(table.log_rms + fit.log_residual)


def _physical_refit(table: WindowTable, form: Effect, free: ModelFit, excitation: bool = False) -> ModelFit:
    """``form`` fitted again with C_lambda held at 0 or above (:func:`.fitting.fit_vector`), from the free fit too.

    ``excitation``: C_F held at 0 or above as well (Eq. 18's load excitation), where a measurement
    contradicted the free fit (:meth:`.effects.Effect.measured_against`: the contacts silenced at load).

    A form's free fit may trade C_lambda against the form's own parameters
    where the plan does not pin both: a mode inside the band on three speeds
    draws its peak through three level means with C_lambda = -0.50, where the
    true constants (0.3) and a mode at the middle speed fit the means as well
    (the study case: ``docs/diagnosis-rules.md``, "forms").  The physical fit
    is the form's fit; when the free fit's constants were unphysical because
    the law does not hold, the physical one fits worse and does not earn.
    """
    starts = [free.vector, *form.starts()]
    return fit_model(table, form, folds=[], starts=starts, physical=True, excitation=excitation)


def _named_form(effect: Effect, params: dict[str, Any], table: WindowTable, location: Location | None,
                ties: Sequence[str]) -> str:
    """The form the fit shows, with the forms that fit as well (each named once)."""
    form = effect.form_name(params, table, location)
    others = [t for t in dict.fromkeys(ties) if t not in (form, effect.form)]
    return ' or '.join([form, *others]) + ' (the data fit these forms equally well)' if others else form


def _too_few_conditions(table: WindowTable, effect: Effect, location: Location) -> str:
    """Why an effect that acts only through speed and load cannot be tested on this plan ('' if it can).

    Its law is a function of the (speed, load) condition, so it needs at least
    as many conditions as the constants and its parameters; evidence from
    the spectrum still tests it, vibration measured at standstill does not
    (:meth:`.effects.Effect.standstill_evidence`).
    """
    if effect.covariate not in PLAN_COVARIATES:
        return ''
    conditions = operating_conditions(table.speed, table.load)
    needed = 3 + min(len(form.parameter_names) for form in effect.variants())
    if conditions >= needed:
        return ''
    if effect.spectral_evidence(table, location):      # not the standstill: measured at rest, it tests no law
        return ''
    return (f'{conditions} (speed, load) conditions for 3 constants and its {needed - 3} parameter(s): a law of '
            f'speed and load cannot be tested on so few conditions (record {needed - conditions} more)')


def evidence_tolerance(table: WindowTable, added_params: int, rules: DiagnosisRules = DEFAULT_RULES) -> float:
    """How much worse held-out runs an effect with independent evidence may predict: the cost of its estimate.

    A least-squares fit of p parameters on n independent units predicts a
    held-out unit with the mean squared error sigma^2 (1 + p/n); k parameters
    more, which the amplitudes cannot yet pin down (an effect the spectrum
    shows but that changes the run amplitudes less than their scatter), raise
    it by about k/n, the RMS error by k/(2n).  The units are the runs
    (:attr:`.table.WindowTable.runs`: windows of one run share its set-up
    scatter).  Never below ``rules.evidence_tolerance`` (the study case behind
    it: ``docs/diagnosis-rules.md``, "evidence").
    """
    runs = max(int(table.runs.size), 1)
    return max(rules.evidence_tolerance, added_params / (2.0 * runs))


def _evaluate(table: WindowTable, effect: Effect, baseline: ModelFit, location: Location,
              folds: list[int], rules: DiagnosisRules) -> Candidate:
    """Fit ``effect`` in each of its forms and decide whether it earns its parameters alone."""
    family = effect
    reason = effect.applicable(table) or _too_few_conditions(table, effect, location)
    if reason:
        return Candidate(CandidateFit(effect, None, form=effect.form, family=family),
                         (Decision('testable', Status.NOT_TESTABLE, reason),))
    if effect.requires_evidence and not effect.independent_evidence(table, location):
        against = effect.contrary_evidence(table, location)
        return Candidate(CandidateFit(effect, None, form=effect.form, family=family),
                         (Decision('requires_evidence', Status.REJECTED, 'named only where its signature shows '
                                   'outside the amplitudes (its law can mimic other effects there), and the recording '
                                   'shows none' + (f': {against}' if against else '')),))
    testable = [form for form in effect.variants() if not form.applicable(table)]
    effect, fit, forms, ties, vectors = _choose_form(table, testable, folds, rules)
    gain = 1.0 - fit.cv_rmse / baseline.cv_rmse if baseline.cv_rmse > 0 else math.nan
    delta = _delta_bic(fit, baseline)
    evidence = effect.independent_evidence(table, location, fit.params)
    form = _named_form(effect, fit.params, table, location, ties)
    if len(forms) == 1:
        forms = [(form, 0.0)]
    within_delta_bic = within_gain = math.nan
    if _swept_within_runs(table, effect, rules):
        within_delta_bic = within_run_delta_bic(table, fit.log_residual, baseline.log_residual,
                                                len(effect.parameter_names))
        within_gain = within_run_gain(table, fit.cv_log_residual, baseline.cv_log_residual)
    scores = CandidateFit(effect, fit, gain=gain, delta_bic=delta, evidence=evidence, form=form, forms=tuple(forms),
                          family=family, form_vectors=vectors, within_delta_bic=within_delta_bic,
                          within_gain=within_gain)
    return Candidate(scores, (_alone(table, scores, rules),))


def _alone(table: WindowTable, scores: CandidateFit, rules: DiagnosisRules) -> Decision:
    """Whether a fitted candidate earns its parameters alone: physical constants, then BIC and held-out, or evidence."""
    fit, gain, delta, evidence = scores.fit, scores.gain, scores.delta_bic, scores.evidence
    assert fit is not None  # only fitted candidates are judged
    k = len(scores.effect.parameter_names)
    unphysical = fit.unphysical()
    if unphysical:
        return Decision('physical_constants', Status.REJECTED, 'unphysical constants: ' + '; '.join(unphysical))
    measured = scores.effect.measured_against(table, fit.params, _predicted(table, fit))
    if measured:
        return Decision('measured_against', Status.REJECTED, 'the fit contradicts a measurement: ' + measured)
    if delta <= -rules.bic_margin and gain >= rules.min_gain:
        return Decision('bic_margin', Status.EARNS, f'held-out error {100 * gain:.0f} % lower, BIC {delta:+.0f}')
    if evidence and gain >= -(tolerance := evidence_tolerance(table, k, rules)):
        text = f'{evidence}; held-out error {100 * gain:+.1f} % lower'
        if gain < -rules.evidence_tolerance:
            text += (f' (within the {100 * tolerance:.1f} % that estimating {k} parameter(s) costs on '
                     f'{table.runs.size} runs)')
        return Decision('evidence_tolerance', Status.EARNS, text)
    return Decision('bic_margin', Status.REJECTED, f'does not earn its {k} parameter(s): held-out error '
                    f'{100 * gain:+.1f} % lower, BIC {delta:+.1f}')


def _pair_test(table: WindowTable, leader: Candidate, runner: Candidate, folds: list[int],
               rules: DiagnosisRules) -> tuple[bool, bool]:
    """Fit both effects together and say whether each adds to the other (BIC drop of rules.bic_margin)."""
    assert leader.fit is not None and runner.fit is not None  # both earn, so both were fitted
    both = CombinedEffect(leader.effect, runner.effect)
    first_vec = leader.fit.vector[3:] if both.first is leader.effect else runner.fit.vector[3:]
    second_vec = runner.fit.vector[3:] if both.second is runner.effect else leader.fit.vector[3:]
    scales = both.scales(table)
    starts = [np.r_[first_vec, second_vec]] + both.starts()[:4]
    vector = fit_vector(table, both, scales, starts=starts)
    residual = predict_log(table, vector, both, scales) - table.log_rms
    n_eff = effective_sample_size(residual, table.run)
    k = 3 + len(both.parameter_names)
    joint = bic(residual, k, n_eff)
    leader_adds = joint - bic(runner.fit.log_residual, runner.fit.n_params, n_eff) <= -rules.bic_margin
    runner_adds = joint - bic(leader.fit.log_residual, leader.fit.n_params, n_eff) <= -rules.bic_margin
    return leader_adds, runner_adds


def _earns_by_bic(pair: SecondEffect, margin: float, rules: DiagnosisRules) -> SecondEffect | None:
    """The BIC rule: BIC lower by ``margin`` than the first alone, and held-out error by ``rules.min_gain``.

    Returns the pair with its basis, or None.  The held-out error is read on
    windows, or on run amplitudes (windows pooled per run) with the windows'
    error no worse than ``rules.evidence_tolerance``: an effect between runs on
    top of the first (depletion beside a resonance) shows where the window
    scatter has averaged out, and only there when that scatter is large (see
    ``docs/diagnosis-rules.md``).
    """
    if not pair.delta_bic <= -margin:     # a NaN score earns nothing
        return None
    if pair.gain >= rules.min_gain:
        return replace(pair, basis=f'held-out error {100 * pair.gain:.0f} % lower than the first alone, '
                                   f'BIC {pair.delta_bic:+.0f}')
    if pair.run_gain >= rules.min_gain and pair.gain >= -rules.evidence_tolerance:
        return replace(pair, basis=f'held-out run amplitudes {100 * pair.run_gain:.0f} % closer than with the first '
                                   f'alone (windows {100 * pair.gain:+.1f} %), BIC {pair.delta_bic:+.0f}')
    return None


def _best_pair(table: WindowTable, combos: list[CombinedEffect], reference: ModelFit, other: Candidate,
               folds: list[int], location: Location, rules: DiagnosisRules) -> SecondEffect | None:
    """The best of ``combos`` by BIC with physical constants, as a :class:`SecondEffect` on ``reference``."""
    combos = [both for both in combos if not both.applicable(table)]
    if not combos or not reference.cv_rmse > 0:
        return None
    both, fit, _, ties, _ = _choose_form(table, combos, folds, rules)
    if fit.unphysical():
        return None
    kept = both.first if both.added is both.second else both.second
    params, first_params = both.params_of(fit.params, both.added), both.params_of(fit.params, kept)
    if both.measured_against(table, fit.params, _predicted(table, fit)):    # either effect's part contradicted
        return None
    gain = 1.0 - fit.cv_rmse / reference.cv_rmse
    run_gain = 1.0 - fit.cv_run_rmse / reference.cv_run_rmse if reference.cv_run_rmse > 0 else math.nan
    delta = _delta_bic(fit, reference)
    return SecondEffect(other, fit, params, gain, delta, both.added, _named_form(both.added, params, table, location,
                                                                                 ties),
                        kept, first_params, kept.form_name(first_params, table, location), combined=both,
                        run_gain=run_gain)


def _on_top(table: WindowTable, first: Candidate, other: Candidate, folds: list[int],
            location: Location, rules: DiagnosisRules) -> SecondEffect | None:
    """``other`` fitted on top of ``first`` (first's form held), every form of ``other``: :func:`_best_pair`."""
    family = other.scores.family
    assert family is not None and first.fit is not None  # set by _evaluate on fitted candidates
    combos = [CombinedEffect(first.effect, form, first.fit.vector[3:], other.scores.form_vectors.get(form.form))
              for form in family.variants()]
    return _best_pair(table, combos, first.fit, other, folds, location, rules)


def _add_second(table: WindowTable, first: Candidate, other: Candidate, folds: list[int], location: Location,
                left: Location, rules: DiagnosisRules,
                fitted: dict[str, SecondEffect | None] | None = None) -> SecondEffect | None:
    """``other`` on top of ``first`` (its form held): each form of ``other`` fitted with it, chosen by BIC.

    The pair names ``other`` when its constants are physical and, beside
    (1) a BIC drop of ``rules.second_bic_margin`` with the held-out error lower by
    ``rules.min_gain`` than the first alone (on windows or on run amplitudes,
    :func:`_earns_by_bic`), either (2) the first effect's residual
    ``left`` is located on ``other``'s covariate (a significance test of its
    own) and the pair lowers the held-out error by ``rules.min_gain`` with a BIC
    at most ``rules.located_bic_tolerance`` higher (a law swept within runs: or
    shows there on top of the first, :func:`_shows_within_runs`), or (3)
    ``other`` has evidence outside the amplitude fit (its spectrum signature,
    with the pair's parameters) and the pair predicts held-out runs no worse
    than :func:`evidence_tolerance` allows -- the rules a single effect earns by.
    ``fitted``, when given, keeps the pair fit by ``other``'s ID (None where no
    pair has physical constants), for a later rule that reads it without fitting again.
    """
    pair = _on_top(table, first, other, folds, location, rules)
    if fitted is not None:
        fitted[other.effect.id] = pair
    if pair is None:
        return None
    by_bic = _earns_by_bic(pair, rules.second_bic_margin, rules)
    if by_bic is not None:
        return by_bic
    if left.located == other.effect.covariate and pair.delta_bic < rules.located_bic_tolerance:
        shows = False
        if not pair.gain >= rules.min_gain:     # a NaN gain too
            shows, pair = _within_runs_on_top(table, first, pair, rules)
        if pair.gain >= rules.min_gain or shows:
            basis = (f'what {first.effect.id} leaves follows {left.located}; with it the held-out error is '
                     f'{100 * pair.gain:.1f} % lower, BIC {pair.delta_bic:+.1f}')
            if pair.gain < rules.min_gain:
                basis += '; ' + _within_runs_note(table, left.located, pair.within_delta_bic, pair.within_gain, rules)
            return replace(pair, route=2, basis=basis)
    return _earns_by_evidence(table, pair, location, rules)


def _within_runs_on_top(table: WindowTable, first: Candidate, pair: SecondEffect,
                        rules: DiagnosisRules) -> tuple[bool, SecondEffect]:
    """Whether ``pair``'s added law is swept within runs and shows there on top of ``first``; the pair scored so.

    Other laws are not scored within runs (``(False, pair)``).
    """
    if not _swept_within_runs(table, pair.effect, rules):
        return False, pair
    assert first.fit is not None    # a first effect was fitted
    pair = replace(pair, within_delta_bic=within_run_delta_bic(table, pair.fit.log_residual, first.fit.log_residual,
                                                               len(pair.effect.parameter_names)),
                   within_gain=within_run_gain(table, pair.fit.cv_log_residual, first.fit.cv_log_residual))
    return _shows_within_runs(table, pair.effect.covariate, (pair.within_delta_bic, pair.within_gain, pair.gain),
                              rules), pair


def _earns_by_evidence(table: WindowTable, pair: SecondEffect, location: Location,
                       rules: DiagnosisRules) -> SecondEffect | None:
    """The evidence rule: the added effect shows outside the amplitude fit and costs little held-out (or None).

    The added effect has evidence outside the amplitude fit with the pair's
    parameters, whatever its fit alone showed (that fit may have given its part
    to the first: a floor a resonance absorbed), and not the first effect's own
    signature (a resonance changes the spectral shape by itself, see
    :attr:`.effects.Effect.changes_spectral_shape`),
    and the pair predicts held-out runs no worse than the first alone by more
    than what estimating its parameters costs (:func:`evidence_tolerance`).
    """
    evidence = pair.effect.independent_evidence(table, location, pair.params, beside=pair.first_effect)
    if not (evidence and pair.gain >= -evidence_tolerance(table, len(pair.effect.parameter_names), rules)):
        return None
    return replace(pair, route=3, basis=f'{evidence}; held-out error {100 * pair.gain:+.1f} % lower than the first '
                                        'alone')


def _second_effect(table: WindowTable, first: Candidate, candidates: list[Candidate], folds: list[int],
                   location: Location, rules: DiagnosisRules) -> tuple[SecondEffect | None, list[SecondEffect]]:
    """Forward selection: the other candidate that best explains what ``first`` leaves, if one earns its place.

    Tried only when the first effect leaves a lack of fit or a located pattern,
    or when another candidate alone predicted held-out runs better than the
    paper's model by ``rules.min_gain`` (an effect drifting between replicate runs,
    depletion say, leaves no lack of fit in the condition means); otherwise only
    the candidates with evidence at standstill are tried
    (:meth:`.effects.Effect.standstill_evidence`: a floor measured with the
    screw still that a resonance's fit has absorbed).
    Returns ``(second or None, tied)``: two that earn by the BIC rule with BICs
    within ``rules.bic_margin`` of each other tie, and neither is named, unless
    :func:`_settle_tied_seconds` tells them apart (where what the first leaves
    is located, what shows outside the amplitude fit, what fitted alone); one
    named by a stronger rule of :func:`_add_second` goes before the others.
    When none earns: beside an impulsive first effect, the effect its windows'
    Gaussian part names (:func:`_second_in_gaussian_part`), else one with
    evidence no other effect makes (:func:`_exclusive_second`).
    """
    assert first.fit is not None  # the named candidate was fitted
    tried = candidates
    remaining = lack_of_fit(table, first.fit.log_residual, first.fit.n_params, rules)
    others_gain = any(c.fit is not None and c.effect.id != first.effect.id and c.gain >= rules.min_gain
                      for c in candidates)
    left = locate(table, first.fit.log_residual, rules)
    exclusive = [(c, signature) for c in candidates if c.fit is not None and c.effect.id != first.effect.id
                 and (signature := c.effect.exclusive_evidence(table, rules.exclusive_evidence_share))]
    if not remaining.significant and not others_gain and left.located == 'none':
        # Nothing left in the amplitudes: only a candidate seen where no first effect reaches, at standstill,
        # or with evidence no other effect makes.
        shown_ids = {c.effect.id for c, _ in exclusive}
        tried = [c for c in candidates if c.effect.standstill_evidence(table) or c.effect.id in shown_ids]
    earning = []
    fitted: dict[str, SecondEffect | None] = {}
    for cand in tried:
        if cand.fit is None or cand.effect.id == first.effect.id:
            continue
        second = _add_second(table, first, cand, folds, location, left, rules, fitted)
        if second is not None:
            earning.append(second)
    earning.sort(key=lambda second: (second.route, second.fit.cv_rmse))
    if len(earning) > 1 and earning[1].route == earning[0].route == 1 \
            and abs(earning[1].delta_bic - earning[0].delta_bic) < rules.bic_margin:
        return _settle_tied_seconds(table, first, earning[:2], left, location, rules)
    if not earning:     # the Gaussian part beside an impulsive first effect, then evidence no other effect makes
        in_part = _second_in_gaussian_part(table, first, candidates, fitted, rules)
        if in_part is not None or not exclusive:
            return in_part, []
        return _exclusive_second(first, *exclusive[0], fitted.get(exclusive[0][0].effect.id), rules), []
    return earning[0], []


def _settle_tied_seconds(table: WindowTable, first: Candidate, tied: list[SecondEffect], left: Location,
                         location: Location, rules: DiagnosisRules) -> tuple[SecondEffect | None, list[SecondEffect]]:
    """Of two second effects that earn alike by BIC, the one named, if any (:func:`_second_effect`).

    In this order: the one whose covariate what ``first`` leaves is located
    on, unless that is the first effect's own covariate (where its own law's
    misfit shows: a spall's growth fitted in revolutions leaves a pattern in
    revolutions whatever the second effect is) or the location does not hold
    with the other's covariate held (:func:`_location_holds`); else the one of
    the two only that shows outside the amplitude fit; where neither does, the
    one whose law alone fitted the recording better by ``rules.bic_margin`` of
    BIC, its covariate not the first effect's (:func:`_alone_decides`).
    ``(None, tied)`` when none of these tells them apart (both shown, say).
    """
    assert first.fit is not None    # a first effect was fitted
    located = [second for second in tied if second.candidate.effect.covariate == left.located]
    if len(located) == 1 and left.located != first.effect.covariate:
        other = tied[1] if located[0] is tied[0] else tied[0]
        if _location_holds(table, first.fit.log_residual, left.located, other.candidate.effect.covariate, rules):
            return replace(located[0], basis=located[0].basis + f'; what {first.effect.id} leaves follows '
                           f'{left.located}, as this effect does'), []
    shown = [(second, second.effect.independent_evidence(table, location, second.params,
                                                         beside=second.first_effect)) for second in tied]
    with_evidence = [(second, evidence) for second, evidence in shown if evidence]
    if len(with_evidence) == 1:
        (named, evidence), = with_evidence
        other = tied[1] if named is tied[0] else tied[0]
        return replace(named, basis=named.basis + f'; {evidence}; {other.effect.id} fits as well but shows '
                       'nothing outside the amplitude fit'), []
    if not with_evidence:
        return _alone_decides(first, tied, rules)
    return None, tied


def _location_holds(table: WindowTable, residual: np.ndarray, located: str, other: str,
                    rules: DiagnosisRules) -> bool:
    """Whether ``residual`` follows drift covariate ``located`` beyond what drift covariate ``other`` explains.

    Two drifts that move together over a recording (temperature rising with
    the revolutions while the rig warms up) both carry a pattern either one
    makes; the location tells two laws apart only where its covariate's trend
    stays significant (``rules.significance``) with the other's held out of
    both (:func:`.locate.partial_trend`).  A location on a covariate that is
    no drift (a speed, the stroke), or beside one, stands as found.
    """
    if located not in DRIFT_COVARIATES or other not in DRIFT_COVARIATES:
        return True
    test = partial_trend(table, residual, located, other)
    return test is not None and test.p_value < rules.significance


def _alone_decides(first: Candidate, tied: list[SecondEffect],
                   rules: DiagnosisRules) -> tuple[SecondEffect | None, list[SecondEffect]]:
    """Of two tied second effects neither located nor shown apart: the one whose law alone fitted far better.

    Each was fitted alone against the paper's model (its candidate's scores),
    where it could also take up part of the first effect's pattern: a law of
    the first effect's own covariate the most.  So the one whose BIC there is
    lower than the other's by ``rules.bic_margin`` (very strong evidence for its
    law over the other's) is named only when its covariate is not the first
    effect's: it fitted better although the other could imitate the first
    effect at least as well.  Otherwise ``(None, tied)``.
    """
    first_alone, second_alone = (second.candidate.delta_bic for second in tied)
    if not abs(first_alone - second_alone) >= rules.bic_margin:     # a NaN decides nothing
        return None, tied
    named, other = (tied[0], tied[1]) if first_alone < second_alone else (tied[1], tied[0])
    if named.candidate.effect.covariate == first.effect.covariate:
        return None, tied
    return replace(named, basis=named.basis + f'; alone, its law fits the recording better than '
                   f'{other.effect.id}\'s by BIC {named.candidate.delta_bic - other.candidate.delta_bic:+.0f}'), []


def _second_in_gaussian_part(table: WindowTable, first: Candidate, candidates: list[Candidate],
                             fitted: dict[str, SecondEffect | None], rules: DiagnosisRules) -> SecondEffect | None:
    """Beside an impulsive first effect: the effect the windows' Gaussian part names, diagnosed alone (or None).

    The first effect's power is in strikes (:attr:`.effects.Effect.impulsive`),
    which each window's Gaussian part leaves out
    (:meth:`.table.WindowTable.gaussian_part`: the contacts' vibration); on the
    whole RMS the first effect's free laws can take on another effect's part
    (a mode's fall with speed into a spall's exponents and the constants).
    When ``rules.gaussian_part_share`` of the windows carry the part, it is
    diagnosed alone, by the same rules, with every candidate's effect (all its
    forms) but the impulsive ones, and an effect it names
    is named beside the first: with the pair's joint fit on the whole RMS
    (``fitted``, by :func:`_add_second`) where that has physical constants,
    else with its share of the RMS unresolved.
    """
    if not first.effect.impulsive or len(table) == 0:
        return None
    contacts = table.gaussian_part()
    if len(contacts) < rules.gaussian_part_share * len(table):
        return None
    families = [c.scores.family for c in candidates if c.scores.family is not None]
    others = {effect.id: effect for effect in families if not effect.impulsive}
    try:
        part = diagnose_table(contacts, others, rules)
    except InputError:      # too few windows or runs carry the part to fit the constants
        return None
    named = part.chosen
    if named is None or named.effect.id not in others:
        return None
    basis = (f'in the windows\' Gaussian part (the band signal without {first.effect.id}\'s strikes), diagnosed '
             f'alone, {named.effect.id} ({named.form}) earns ({named.reason}); on the whole RMS '
             f'{first.effect.id}\'s free laws take its part')
    pair = fitted.get(named.effect.id)
    if pair is not None:
        return replace(pair, route=5, basis=basis + f'; the pair there: held-out error {100 * pair.gain:+.1f} % '
                       f'lower than {first.effect.id} alone, BIC {pair.delta_bic:+.1f}')
    own = next((c for c in candidates if c.effect.id == named.effect.id), named)
    return _unresolved_second(first, own, named.effect, named.form, None, route=5,
                              basis=basis + '; no fit of the pair on the whole RMS has physical constants')


def _unresolved_second(first: Candidate, other: Candidate, effect: Effect, form: str, pair: SecondEffect | None,
                       route: int, basis: str) -> SecondEffect:
    """``effect`` (of candidate ``other``, in ``form``) named beside ``first`` with its share of the RMS unresolved.

    The first effect's fit stays the model; ``pair`` (the pair fit that was not
    kept, None when none has physical constants) gives the gain and BIC.
    """
    assert first.fit is not None
    return SecondEffect(other, first.fit, {}, math.nan if pair is None else pair.gain,
                        math.nan if pair is None else pair.delta_bic, effect, form, first.effect,
                        dict(first.fit.params), first.form, route=route, unresolved=True, basis=basis)


def _exclusive_second(first: Candidate, other: Candidate, evidence: str, pair: SecondEffect | None,
                      rules: DiagnosisRules) -> SecondEffect:
    """``other`` named beside ``first`` by evidence no other effect makes, its share of the RMS unresolved.

    ``other`` shows in ``rules.exclusive_evidence_share`` of the windows or more
    a signature no other candidate makes (:meth:`.effects.Effect.exclusive_evidence`:
    impulsive strikes beside Gaussian oil loss, modes, stiffness or a
    background), but no rule of :func:`_add_second` keeps its amplitude law
    (beside an effect carrying most of the RMS, a small impulsive power is
    within the run scatter).  The evidence names it; the first effect's fit
    stays the model (and the calibration), and the pair's held-out gain and
    BIC (``pair``, fitted by :func:`_add_second`; None when no pair has
    physical constants) are given in the basis.  ``evidence``: its
    :meth:`.effects.Effect.exclusive_evidence`.
    """
    scored = (f'its amplitude law beside {first.effect.id} has no fit with physical constants' if pair is None else
              f'its amplitude law added to {first.effect.id}: held-out error {100 * pair.gain:+.1f} % lower, '
              f'BIC {pair.delta_bic:+.1f}, not kept')
    return _unresolved_second(first, other, other.effect, other.form, pair, route=4,
                              basis=f'{evidence}, in {100 * rules.exclusive_evidence_share:.0f} % of the windows '
                                    f'or more (per operating condition), which no other effect makes; {scored}')


def _pair_when_none_earns(table: WindowTable, ranked: list[Candidate], baseline: ModelFit, folds: list[int],
                          location: Location, rules: DiagnosisRules) -> tuple[Candidate, SecondEffect] | None:
    """Two effects that only together explain the mismatch: ``(first, second)`` or None.

    Among the ``rules.pair_pool`` candidates with evidence outside the amplitude
    fit first, then the largest held-out gains alone, each pair is fitted (the
    first of the pool first); a pair counts when the second adds to the first
    by the BIC rule or the evidence rule of :func:`_add_second`, and the pair
    earns its parameters over the paper's model and over the second alone.
    """
    pool = sorted([c for c in ranked if c.fit is not None and math.isfinite(c.gain)],
                  key=lambda c: (not c.evidence, -c.gain))
    pool = pool[:rules.pair_pool]
    best = None
    for i, first in enumerate(pool):
        for other in pool[i + 1:]:
            # the pool holds fitted candidates only
            first_family, other_family = first.scores.family, other.scores.family
            assert first_family is not None and other_family is not None
            assert first.fit is not None and other.fit is not None
            combos = [CombinedEffect(a, b, first.scores.form_vectors.get(a.form),
                                     other.scores.form_vectors.get(b.form))
                      for a in first_family.variants()
                      for b in other_family.variants()]
            pair = _best_pair(table, combos, first.fit, other, folds, location, rules)
            second = None if pair is None else (_earns_by_bic(pair, rules.bic_margin, rules)
                                                or _earns_by_evidence(table, pair, location, rules))
            if second is None:
                continue
            joint = second.fit
            earns = (_delta_bic(joint, baseline) <= -rules.bic_margin
                     and _delta_bic(joint, other.fit) <= -rules.bic_margin
                     and 1.0 - joint.cv_rmse / baseline.cv_rmse >= rules.min_gain)
            if earns and (best is None or joint.cv_rmse < best[1].fit.cv_rmse):
                best = (first, second)
    return best


def _tie_both_shown(table: WindowTable, best: Candidate, runner: Candidate, folds: list[int],
                    location: Location, rules: DiagnosisRules) -> SecondEffect | None:
    """Two tied candidates that each show outside the amplitude fit, beside the other: ``runner`` on ``best``, or None.

    Two effects of which each explains the amplitudes' mismatch alone, and
    neither adds to the other by BIC, still both show when each has evidence
    the other's law cannot give (a floor measured at standstill, a band fixed
    in Hz that follows a transfer; ``docs/diagnosis-rules.md``, "ties").  Both are named when the evidence of
    each holds with the pair's parameters beside the other (the evidence rule
    of a second effect, :func:`_earns_by_evidence`, both ways round).
    """
    if not (best.evidence and runner.evidence):
        return None
    on_top = _on_top(table, best, runner, folds, location, rules)
    pair = None if on_top is None else _earns_by_evidence(table, on_top, location, rules)
    if pair is None:
        return None
    first_shown = pair.first_effect.independent_evidence(table, location, pair.first_params, beside=pair.effect)
    if not first_shown:
        return None
    return replace(pair, basis=pair.basis + f'; and {pair.first_effect.id} beside it: {first_shown}')


def _spectral_tiebreak(table: WindowTable, location: Location, first: Candidate,
                       second: Candidate) -> tuple[Candidate, str] | None:
    """The candidate to drop from a tie on evidence outside the amplitude fit, with the evidence against it; or None.

    Where both have evidence, only evidence that holds beside the rival
    counts: what the rival's law produces by itself (a spectral shape change
    beside an effect that changes the shape,
    :attr:`.effects.Effect.changes_spectral_shape`) cannot tell the two apart,
    as for a second effect (:func:`_earns_by_evidence`).
    """
    # tied candidates both earn, so both were fitted
    against = [cand.effect.contrary_evidence(table, location, cast(ModelFit, cand.fit).params)
               for cand in (first, second)]
    support = [bool(first.evidence), bool(second.evidence)]
    if all(support):
        support = [bool(cand.effect.independent_evidence(table, location, cast(ModelFit, cand.fit).params,
                                                         beside=rival.effect))
                   for cand, rival in ((first, second), (second, first))]
    if support[0] and not support[1]:
        return second, against[1]
    if support[1] and not support[0]:
        return first, against[0]
    if against[0] and not against[1]:
        return first, against[0]
    if against[1] and not against[0]:
        return second, against[1]
    return None


@dataclass(frozen=True)
class Confounding:
    """Two run-level covariates that move together: an operating variable and a drift covariate."""

    variable: str       # 'speed' or 'load'
    follows: str        # 'revolutions', 'time' or 'temperature'
    spearman: float     # over runs

    @property
    def note(self) -> str:
        """The finding in words, with what to record instead."""
        trend = 'rises' if self.spearman > 0 else 'falls'
        return (f'run order is confounded with {self.variable}: {self.follows} {trend} with {self.variable} '
                f'(Spearman {self.spearman:+.2f} over runs), so effects that follow {self.follows} look like '
                f'effects of {self.variable}; record the runs in random order')

    def as_json(self) -> dict:
        """Plain mapping."""
        return {'variable': self.variable, 'follows': self.follows, 'spearman': finite_or_none(self.spearman)}


def confounding(table: WindowTable, rules: DiagnosisRules = DEFAULT_RULES) -> list[Confounding]:
    """Run-level covariates that move together (|Spearman| >= ``rules.confounded``): a set-point and a drift."""
    from scipy.stats import spearmanr
    drifts = [name for name in DRIFT_COVARIATES if name != 'temperature' or table.has_temperature]
    names = list(PLAN_COVARIATES) + drifts
    means = {name: table.run_means(name) for name in names}
    for name in PLAN_COVARIATES:
        levels: np.ndarray = np.array(operating_levels(means[name]))
        means[name] = levels[np.argmin(np.abs(means[name][:, None] - levels[None, :]), axis=1)]
    found = []
    for a in PLAN_COVARIATES:
        for b in drifts:
            x, y = means[a], means[b]
            ok = np.isfinite(x) & np.isfinite(y)
            if ok.sum() < 4 or np.ptp(x[ok]) == 0 or np.ptp(y[ok]) == 0:
                continue
            rho = float(spearmanr(x[ok], y[ok]).statistic)
            if abs(rho) >= rules.confounded:
                found.append(Confounding(a, b, rho))
    return found


def _empirical(table: WindowTable, baseline: ModelFit, location: Location, folds: list[int],
               rules: DiagnosisRules) -> EmpiricalFit | None:
    """The empirical term (of each significant located shape) that predicts held-out runs best, or None."""
    best = None
    for term in empirical_terms(table, baseline.log_residual, location, rules.significance, rules.min_segment_runs):
        fit = fit_model(table, term, folds)
        gain = 1.0 - fit.cv_rmse / baseline.cv_rmse if baseline.cv_rmse > 0 else math.nan
        candidate = EmpiricalFit(term, fit, gain, _delta_bic(fit, baseline), rules=rules)
        if best is None or (candidate.earns, -fit.cv_rmse) > (best.earns, -best.fit.cv_rmse):
            best = candidate
    return best


def drift_correlation(table: WindowTable, first: str = 'temperature', second: str = 'revolutions') -> float:
    """Pearson correlation over runs of two drift covariates (NaN when one is missing or constant)."""
    if 'temperature' in (first, second) and not table.has_temperature:
        return math.nan
    x, y = table.run_means(first), table.run_means(second)
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 3 or np.ptp(x[ok]) == 0 or np.ptp(y[ok]) == 0:
        return math.nan
    return float(np.corrcoef(x[ok], y[ok])[0, 1])


def same_shape_covariates(table: WindowTable, covariates: Collection[str],
                          rules: DiagnosisRules = DEFAULT_RULES) -> set[str]:
    """``covariates`` and the drift covariates whose run means are collinear with one of them (|r| >= rules.collinear).

    A smooth curve in time, when time and revolutions rise together over runs
    (one session after another, each from rest), is a smooth curve in
    revolutions too: it says the law of revolutions is approximate, not that
    the physics is missing (``docs/diagnosis-rules.md``, "physics outside the catalogue").
    """
    out = set(covariates)
    for drift in DRIFT_COVARIATES:
        if drift not in out and any(other in DRIFT_COVARIATES
                                    and abs(drift_correlation(table, drift, other)) >= rules.collinear
                                    for other in covariates):
            out.add(drift)
    return out


def _held_out_tiebreak(table: WindowTable, first: Candidate, second: Candidate,
                       rules: DiagnosisRules) -> tuple[Candidate, float] | None:
    """The candidate to drop from a tie between laws of two drift covariates the recording does not tie, and their r.

    When the two follow different recorded drift covariates (:data:`DRIFT_COVARIATES`:
    temperature and revolutions, say) and these are not collinear over runs
    (|r| below ``rules.collinear``), held-out runs decide: the one predicting
    them worse is dropped.
    """
    a, b = first.effect.covariate, second.effect.covariate
    if a == b or a not in DRIFT_COVARIATES or b not in DRIFT_COVARIATES:
        return None
    correlation = drift_correlation(table, a, b)
    if not abs(correlation) < rules.collinear:
        return None
    assert first.fit is not None and second.fit is not None  # tied candidates both earn, so both were fitted
    return (first if first.fit.cv_rmse > second.fit.cv_rmse else second), correlation


def _settle_tie(best: Candidate, runner: Candidate, loser: Candidate, notes: list, decision: Decision,
                decided_by: str) -> Candidate:
    """Drop ``loser`` of two candidates that fit the amplitudes equally well by ``decision``; note why; the winner.

    ``decision.text`` may name the winner as ``{winner}``.
    """
    winner = runner if loser is best else best
    loser.decide(replace(decision, text=decision.text.replace('{winner}', winner.effect.id)))
    notes.append(f'{best.effect.id} and {runner.effect.id} fit the amplitudes equally well; {decided_by}: '
                 f'{winner.effect.id}')
    return winner


def _separation_advice(a: Effect, b: Effect) -> str:
    return (f'to separate {a.id} from {b.id}, record {a.to_separate}; for {b.id}: {b.to_separate}')


def _mismatch_note(location: Location, test: LackOfFit, pattern: bool) -> str:
    """What is real about an unexplained mismatch, saying only what was shown."""
    parts = [location.summary] if pattern else []
    if test.significant:
        parts.append(test.finding + ('' if pattern else '; no covariate carries it'))
    if not parts:
        parts.append('the paper\'s model fits with unphysical constants')
    return f'the mismatch is real ({"; ".join(parts)}) but no candidate explains it'


def _unexplained_advice(pattern: bool, test: LackOfFit) -> str:
    if pattern:
        return 'a candidate for the located mismatch is missing from the catalogue'
    if test.lack_of_fit:
        return ('the condition means depart from the model in a way no candidate and no recorded covariate '
                'follows; record more (speed, load) conditions to see its shape')
    if test.excess_scatter:
        return ('repeated runs differ by more than set-up scatter and no recorded covariate follows it; record '
                'temperature and keep the sensor mounting unchanged between runs to find what varies')
    return 'the constants are unphysical and no candidate makes them physical'


def _untestable_advice(test: LackOfFit) -> str:
    return REPEAT_ADVICE if test.dof_pure <= 0 else 'record more (speed, load) conditions'


@dataclass
class _Outcome:
    """The verdict as :func:`diagnose_table` builds it, step by step."""

    verdict: Verdict = ADEQUATE
    best: Candidate | None = None
    second: SecondEffect | None = None
    tied: list[str] = field(default_factory=list)
    advice: str = ''
    notes: list[str] = field(default_factory=list)
    empirical: EmpiricalFit | None = None


def diagnose_table(table: WindowTable, effects: dict | None = None, rules: DiagnosisRules = DEFAULT_RULES) -> Diagnosis:
    """Run the whole diagnosis on a window table (see module doc), every decision by ``rules``.

    ``effects``: the candidates by ID (default: every registered effect);
    ``rules``: the policy (:class:`.rules.DiagnosisRules`; ``docs/diagnosis-rules.md``).
    """
    check_identifiable(table.speed, table.load)
    effects = registered() if effects is None else effects
    folds = cv_folds(table)
    if len(folds) < 3:
        raise InputError(f'diagnose: {len(folds)} run(s) can be held out with the constants still identifiable; '
                         'record each speed and load in two runs or more (6 runs or more in all)')
    baseline = fit_model(table, None, folds)
    baseline_test = lack_of_fit(table, baseline.log_residual, baseline.n_params, rules)
    location = locate(table, baseline.log_residual, rules)
    confounded_with = confounding(table, rules)
    correlation = drift_correlation(table)
    out = _Outcome(notes=_plan_notes(table, baseline, folds, confounded_with, correlation, rules))
    candidates = [_evaluate(table, effect, baseline, location, folds, rules) for effect in effects.values()]
    ranked = sorted([c for c in candidates if c.fit is not None], key=lambda c: cast(ModelFit, c.fit).cv_rmse)
    earning = [c for c in ranked if c.status == Status.EARNS]
    out.best = earning[0] if earning else (ranked[0] if ranked else None)
    conditions = operating_conditions(table.speed, table.load)
    out.empirical = _empirical(table, baseline, location, folds, rules)
    if earning:
        _settle_earning(table, earning, out, folds, location, rules)
    else:
        _when_none_earns(table, ranked, baseline, baseline_test, location, folds, conditions, out, rules)
    _qualify_verdict(out, bool(confounded_with), conditions, baseline_test)
    _let_empirical_overrule(table, out, rules)
    chosen_test = _name_second_and_test(table, out, candidates, folds, location, rules)
    return Diagnosis(verdict=out.verdict, baseline=baseline, candidates=candidates, best=out.best,
                     location=location, tied=out.tied, notes=out.notes, what_to_record=out.advice, table=table,
                     confounding=confounded_with, baseline_fit_test=baseline_test, chosen_fit_test=chosen_test,
                     second=out.second, empirical=out.empirical if out.verdict == UNEXPLAINED else None,
                     temperature_revolutions=correlation, rules=rules)


def _plan_notes(table: WindowTable, baseline: ModelFit, folds: list[int], confounded_with: list[Confounding],
                correlation: float, rules: DiagnosisRules) -> list[str]:
    """What the plan and the paper's model say before any candidate: unphysical constants, confounding, ..."""
    notes = []
    if baseline.unphysical():
        notes.append('the paper\'s model fits with unphysical constants (' + '; '.join(baseline.unphysical())
                     + '): evidence that its form misses something')
    notes.extend(c.note for c in confounded_with)
    if len(folds) < table.runs.size:
        notes.append(f'{table.runs.size - len(folds)} run(s) not held out: without them the constants '
                     'would not be identifiable')
    if math.isfinite(correlation):
        notes.append(f'temperature and revolutions over runs: r = {correlation:+.2f} '
                     f'({"collinear" if abs(correlation) >= rules.collinear else "not collinear"})')
    return notes


def _settle_earning(table: WindowTable, earning: list[Candidate], out: _Outcome, folds: list[int], location: Location,
                    rules: DiagnosisRules) -> None:
    """Among candidates that earn alone: the one named, or a tie (``ambiguous``), each runner-up with its reason."""
    best = earning[0]
    out.verdict = Verdict(best.effect.id)
    for runner in earning[1:]:
        close = (runner.gain >= rules.tie_ratio * best.gain
                 or abs(runner.delta_bic - best.delta_bic) < rules.bic_margin)
        if not close:
            runner.decide(Decision('tie_ratio', Status.DROPPED, f'explains less than {best.effect.id}'))
            continue
        leader_adds, runner_adds = _pair_test(table, best, runner, folds, rules)
        if leader_adds and not runner_adds:
            runner.decide(Decision('bic_margin', Status.DROPPED, f'adds nothing given {best.effect.id}'))
        elif runner_adds and not leader_adds:
            best.decide(Decision('bic_margin', Status.DROPPED, f'adds nothing given {runner.effect.id}'))
            best, out.verdict = runner, Verdict(runner.effect.id)
        elif runner_adds and leader_adds:
            out.notes.append(f'{runner.effect.id} adds to {best.effect.id} as well: both effects may be present')
        elif (held_out := _held_out_tiebreak(table, best, runner, rules)) is not None:
            loser, correlation = held_out
            first, second = sorted((best.effect.covariate, runner.effect.covariate), reverse=True)
            collinearity = f'{first} and {second} not collinear, r = {correlation:+.2f} over runs'
            best = _settle_tie(best, runner, loser, out.notes,
                               Decision('collinear', Status.DROPPED, f'fits the amplitudes as well as {{winner}} but '
                                        f'predicts held-out runs worse ({collinearity})'),
                               f'{collinearity}, so the held-out runs decide')
            out.verdict = Verdict(best.effect.id)
        elif (both_shown := _tie_both_shown(table, best, runner, folds, location, rules)) is not None:
            out.second = both_shown
            out.notes.append(f'{best.effect.id} and {runner.effect.id} fit the amplitudes equally well and neither '
                             'adds by BIC given the other, but each shows outside the amplitude fit beside the '
                             'other: both are named')
        elif (spectral := _spectral_tiebreak(table, location, best, runner)) is not None:
            loser, against = spectral
            best = _settle_tie(best, runner, loser, out.notes,
                               Decision('evidence', Status.DROPPED, 'fits as well as {winner} but '
                                        + (against or 'the other has independent evidence')),
                               'decided by evidence from outside the fit')
            out.verdict = Verdict(best.effect.id)
        else:
            _tie(table, best, runner, out)
            break
    out.best = best


def _tie(table: WindowTable, best: Candidate, runner: Candidate, out: _Outcome) -> None:
    """Two candidates the recording cannot tell apart: ``ambiguous``, with what to record."""
    out.tied = [best.effect.id, runner.effect.id]
    out.verdict = AMBIGUOUS
    out.advice = _separation_advice(best.effect, runner.effect)
    collinear = ''
    covariates = sorted((best.effect.covariate, runner.effect.covariate), reverse=True)
    if covariates[0] != covariates[1] and set(covariates) <= set(DRIFT_COVARIATES):
        correlation = drift_correlation(table, *covariates)
        if math.isfinite(correlation):
            collinear = (f' ({covariates[0]} and {covariates[1]} are collinear over runs, r = {correlation:+.2f}; '
                         f'pauses that change {covariates[0]} while {covariates[1]} stand still separate them)')
    out.notes.append(f'{best.effect.id} and {runner.effect.id} explain the recording equally well and '
                     'neither adds anything given the other: the recording cannot tell them apart' + collinear)


def _swept_within_runs(table: WindowTable, effect: Effect, rules: DiagnosisRules) -> bool:
    """True when ``effect``'s covariate varies mostly within runs (``rules.within_run_share``: position)."""
    return within_run_share(table, effect.covariate) >= rules.within_run_share


def _with_time_within_runs(table: WindowTable, covariate: str, rules: DiagnosisRules) -> float:
    """Pearson r of ``covariate`` and time within runs when collinear (|r| >= ``rules.collinear``), else NaN."""
    r = within_run_correlation(table, covariate)
    return r if abs(r) >= rules.collinear else math.nan


def _shows_within_runs(table: WindowTable, covariate: str, scores: tuple[float, float, float],
                       rules: DiagnosisRules) -> bool:
    """True when a law swept within runs shows there; ``scores``: within-run BIC and gain, held-out gain.

    The BIC on the windows' deviations from their run means is lower by
    ``rules.bic_margin`` and held-out runs are predicted better, on their shape
    along the run and on their windows (the BIC counted by runs charges the
    law's parameters against runs it does not change: it is not asked).  Within runs the law is
    seen against the scatter between windows (sensor noise, contact events),
    which a weak shape along the stroke reduces by little even where it is
    certain; the held-out gains only have to show that the shape found
    carries over to runs it was not fitted on.  Where every traverse runs one
    way, ``covariate`` and time are collinear within runs and a drift during
    each traverse has the law's shape: the held-out shape must then be closer
    by ``rules.min_gain`` (the study cases: ``docs/diagnosis-rules.md``, "within runs").
    """
    within_delta_bic, within_gain, gain = scores
    if not (within_delta_bic <= -rules.bic_margin and gain > 0):     # NaN: not scored within runs
        return False
    return within_gain > (rules.min_gain if math.isfinite(_with_time_within_runs(table, covariate, rules)) else 0.0)


def _within_runs_note(table: WindowTable, covariate: str, within_delta_bic: float, within_gain: float,
                      rules: DiagnosisRules) -> str:
    """What a law swept within runs shows there, in words (and when time within runs shows the same)."""
    note = (f'within runs (the windows\' deviations from their run means, the set-up scatter between runs left out) '
            f'BIC {within_delta_bic:+.0f}, the shape of held-out runs {100 * within_gain:.1f} % closer')
    r = _with_time_within_runs(table, covariate, rules)
    if math.isfinite(r):
        note += (f'; {covariate} and time are collinear within runs (r = {r:+.2f}: every traverse one way), so a '
                 'drift during each traverse would look the same: traverses out and back tell them apart')
    return note


def _located_by_bic(cand: Candidate, rules: DiagnosisRules) -> bool:
    """The located law's rule on all windows: a BIC drop of ``rules.located_law_bic``, held-out ``rules.min_gain``."""
    return cand.delta_bic <= -rules.located_law_bic and cand.gain >= rules.min_gain


def _located_law(table: WindowTable, ranked: list[Candidate], location: Location,
                 empirical: EmpiricalFit | None, rules: DiagnosisRules) -> Candidate | None:
    """The candidate whose law is the mismatch located on its covariate, when none earns alone (None if none is).

    The located test has already shown structure in that covariate
    (revolutions, temperature, position: not speed or load, whose few levels
    a law of two or three parameters follows whatever the physics); a
    candidate that follows it is
    named with a BIC drop of ``rules.located_law_bic`` (instead of
    ``rules.bic_margin``) and a held-out error lower by ``rules.min_gain``
    (:func:`_located_by_bic`), or a law swept within runs by what it shows
    there (:func:`_shows_within_runs`), when its constants are physical, its
    fit leaves no significant pattern in the covariate (:func:`.locate.covariate_tests` on its residual), and the
    empirical term chosen for the located shapes (``empirical``,
    :func:`_empirical`) does not beat it by the rule that makes a named effect
    give way (:meth:`EmpiricalFit.beats`: a smooth curve in the law's own
    covariate never does, and a step must predict held-out runs better with
    the lower BIC): a catalogue law is named only where a shape no law has
    does not explain the mismatch better.  Of several, the one predicting
    held-out runs best.
    """
    best: Candidate | None = None
    for cand in ranked:
        fit = cand.fit
        if fit is None or cand.effect.covariate in PLAN_COVARIATES or cand.effect.covariate != location.located \
                or fit.unphysical():
            continue
        if not (_located_by_bic(cand, rules) or _shows_within_runs(table, cand.effect.covariate, (
                cand.scores.within_delta_bic, cand.scores.within_gain, cand.gain), rules)):
            continue
        shapes = same_shape_covariates(table, {cand.effect.covariate}, rules)
        if empirical is not None and empirical.beats(fit, shapes):
            continue
        if any(t.covariate == location.located and t.p_value < rules.significance
               for t in covariate_tests(table, fit.log_residual, rules)):
            continue
        if best is None or fit.cv_rmse < cast(ModelFit, best.fit).cv_rmse:
            best = cand
    return best


def _against_physical_null(table: WindowTable, ranked: list[Candidate], baseline: ModelFit, location: Location,
                           folds: list[int], rules: DiagnosisRules) -> tuple[Candidate, ModelFit] | None:
    """The candidate that explains why the paper's model needs unphysical constants, and that null (None if none).

    A candidate is fitted with C_lambda held at 0 or above where its free fit
    was unphysical (:func:`_physical_refit`): the model it extends is then the
    paper's with C_lambda held physical too, not the free fit whose negative
    C_lambda (a film that raises the vibration) absorbed part of the effect's
    law of speed (a mode above the speeds run rises with speed, as a thinning
    film does not).  A candidate the BIC margin rejected against the free fit
    is named when, with C_lambda at 0 or above itself, against the physical
    null it lowers the BIC by ``rules.bic_margin`` and the held-out error by
    ``rules.min_gain``, and against the free fit it is no worse by either (BIC
    and held-out error no higher: where the recording's own constants are
    unphysical, no effect at all, a law of speed gains much on the null held
    physical but nothing on the free fit); and where the mismatch is located
    on a covariate, the candidate's law is of that covariate.  Of several, the
    one predicting held-out runs best.  The decision reads ``physical_null``.
    """
    null = fit_model(table, None, folds, physical=True)
    best: tuple[Candidate, float, float] | None = None
    for cand in ranked:
        fit = cand.fit
        if fit is None or cand.decisions[-1].rule != 'bic_margin' or fit.vector[2] < 0.0 \
                or not (cand.gain >= 0.0 and cand.delta_bic <= 0.0) \
                or location.located not in ('none', 'spectrum', cand.effect.covariate):
            continue
        gain = 1.0 - fit.cv_rmse / null.cv_rmse if null.cv_rmse > 0 else math.nan
        delta = _delta_bic(fit, null)
        if delta <= -rules.bic_margin and gain >= rules.min_gain and (
                best is None or fit.cv_rmse < cast(ModelFit, best[0].fit).cv_rmse):
            best = (cand, gain, delta)
    if best is None:
        return None
    cand, gain, delta = best
    cand.decide(Decision('physical_null', Status.EARNS, f'the paper\'s model needs unphysical constants '
                         f'({"; ".join(baseline.unphysical())}); against it held physical, held-out error '
                         f'{100 * gain:.0f} % lower, BIC {delta:+.0f}, and held-out error {100 * cand.gain:+.1f} % '
                         'lower than the unphysical fit', restart=True))
    return cand, null


def _when_none_earns(table: WindowTable, ranked: list[Candidate], baseline: ModelFit, baseline_test: LackOfFit,
                     location: Location, folds: list[int], conditions: int, out: _Outcome,
                     rules: DiagnosisRules) -> None:
    """No candidate earns alone: a located mismatch's law, two that only together explain it, unexplained, adequate.

    ``out.empirical``: the empirical term of the located shapes (:func:`_empirical`), which a law must beat.
    """
    pattern = location.located not in ('none', 'spectrum')
    mismatch = baseline_test.significant or pattern or bool(baseline.unphysical())
    if mismatch and not pattern and not form_testable(conditions):
        # Three conditions fit the constants exactly: run scatter or unphysical constants are no evidence
        # against the form on such a plan (unit-to-unit scatter moves the constants anywhere).
        mismatch = False
        found = baseline_test.finding or 'the constants are unphysical'
        out.notes.append(f'{found}; on {conditions} conditions this may be scatter between units or set-ups as '
                         'well as a model error')
    located = _located_law(table, ranked, location, out.empirical, rules) if mismatch and pattern else None
    # Two effects may leave the condition means on the model and nothing located, yet one alone predicts held-out
    # runs better (docs/diagnosis-rules.md, "pairs"): the gate of _second_effect.
    gains = any(c.fit is not None and c.gain >= rules.min_gain and not c.fit.unphysical() for c in ranked)
    together = (_pair_when_none_earns(table, ranked, baseline, folds, location, rules)
                if (mismatch or gains) and located is None else None)
    physical = (_against_physical_null(table, ranked, baseline, location, folds, rules)
                if mismatch and located is None and together is None and baseline.unphysical() else None)
    if physical is not None:
        out.best, null = physical
        out.verdict = Verdict(out.best.effect.id)
        out.notes.append(f'the paper\'s model fits only with unphysical constants; held physical it predicts held-out '
                         f'runs with {100 * null.cv_rmse:.2f} % error, and {out.best.effect.id} (physical constants) '
                         f'with {100 * cast(ModelFit, out.best.fit).cv_rmse:.2f} %')
    elif located is not None:
        out.best = located
        fit = cast(ModelFit, located.fit)
        text = (f'named as the law of the mismatch located on {location.located}: its fit leaves no '
                f'pattern there and the empirical term of the located shape does not explain it better; '
                f'held-out error {100 * located.gain:.1f} % lower, BIC {located.delta_bic:+.1f}')
        if _located_by_bic(located, rules):
            text += f' ({rules.located_law_bic:g} suffices once located)'
        else:
            text += '; ' + _within_runs_note(table, location.located, located.scores.within_delta_bic,
                                             located.scores.within_gain, rules)
        located.decide(Decision('located_law_bic', Status.EARNS, text, restart=True))
        out.verdict = Verdict(located.effect.id)
        out.notes.append(f'no candidate earns by the BIC margin, but the mismatch follows {location.located} and '
                         f'{located.effect.id}\'s law of {location.located} explains it (held-out error '
                         f'{100 * fit.cv_rmse:.2f} % against {100 * baseline.cv_rmse:.2f} % for the paper\'s model)')
    elif together is not None:
        out.best, out.second = together
        out.best.decide(Decision('pair_pool', Status.EARNS, f'with {out.second.effect.id} it does: the two explain '
                                 'the mismatch only together'))
        out.verdict = Verdict(out.best.effect.id)
    elif mismatch:
        out.verdict = UNEXPLAINED
        out.advice = _unexplained_advice(pattern, baseline_test)
        out.notes.append(_mismatch_note(location, baseline_test, pattern))


def _qualify_verdict(out: _Outcome, confounded: bool, conditions: int, baseline_test: LackOfFit) -> None:
    """What the plan cannot confirm: confounded run order, too few conditions, no lack-of-fit test."""
    if out.verdict == AMBIGUOUS and confounded:
        out.advice = 'runs in random order of speed and load; ' + out.advice
    if out.verdict == ADEQUATE and confounded:
        out.verdict = AMBIGUOUS
        out.advice = 'the same conditions with the runs in random order of speed and load'
        out.notes.append('the paper\'s model fits, but with the run order confounded with speed or load an effect '
                         'that follows time, revolutions or temperature would be absorbed by the speed and load '
                         'laws: adequacy cannot be confirmed')
    if out.verdict == ADEQUATE and not form_testable(conditions):
        out.verdict = CANNOT_TELL
        out.advice = form_advice(conditions)
        out.notes.append(f'the paper\'s model fits, but {form_flag(conditions)}: adequacy cannot be confirmed')
    if out.verdict in (ADEQUATE, CANNOT_TELL) and not baseline_test.testable and form_testable(conditions):
        out.verdict = CANNOT_TELL
        out.advice = _untestable_advice(baseline_test)
        out.notes.append(f'no lack-of-fit test on this plan: {baseline_test.reason}; adequacy cannot be confirmed')
    elif out.verdict == CANNOT_TELL and baseline_test.dof_pure <= 0:
        out.advice += f'; {REPEAT_ADVICE}'
        out.notes.append(f'no lack-of-fit test on this plan: {baseline_test.reason}')


def _let_empirical_overrule(table: WindowTable, out: _Outcome, rules: DiagnosisRules) -> None:
    """A named (or tied) effect gives way to an empirical term that predicts held-out runs better.

    Not to a smooth term in a covariate the named effects follow, or in one
    collinear with it over runs (:func:`same_shape_covariates`; a note says so).
    """
    best, empirical = out.best, out.empirical
    if empirical is not None and best is not None and out.verdict in (best.effect.id, AMBIGUOUS):
        second = out.second if out.verdict == best.effect.id else None
        named_fit = second.fit if second is not None else cast(ModelFit, best.fit)
        followed = {best.effect.covariate} | ({second.effect.covariate} if second is not None else set())
        followed |= {registered()[name].covariate for name in out.tied if name in registered()}
        collinear = same_shape_covariates(table, followed, rules) - followed
        if empirical.term.covariate in collinear and empirical.beats(named_fit, followed):
            out.notes.append(f'an empirical {empirical.term.form} in {empirical.term.covariate} predicts held-out '
                             f'runs better ({100 * empirical.fit.cv_rmse:.2f} % against '
                             f'{100 * named_fit.cv_rmse:.2f} %), but {empirical.term.covariate} is collinear over '
                             f'runs with what {best.effect.id} follows: a curve in one is a curve in the other')
        if empirical.beats(named_fit, followed | collinear):
            empirical = out.empirical = replace(empirical, overrules=best.effect.id)
            best.decide(Decision('empirical', Status.DROPPED, f'predicts held-out runs worse than an empirical '
                                 f'{empirical.term.form} in {empirical.term.covariate} (held-out error '
                                 f'{100 * named_fit.cv_rmse:.2f} % against {100 * empirical.fit.cv_rmse:.2f} %): the '
                                 'located shape is not its law'))
            out.verdict, out.second, out.tied = UNEXPLAINED, None, []
            out.advice = 'a candidate for the located mismatch is missing from the catalogue'
            out.notes.append(f'{best.effect.id} is not named: an empirical {empirical.term.form} in '
                             f'{empirical.term.covariate} predicts held-out runs better')
    if out.verdict == UNEXPLAINED and empirical is not None and empirical.earns:
        out.notes.append(empirical.note)


def _name_second_and_test(table: WindowTable, out: _Outcome, candidates: list[Candidate], folds: list[int],
                          location: Location, rules: DiagnosisRules) -> LackOfFit | None:
    """With one effect named: the second effect (forward selection) and the lack of fit of what is named."""
    best = out.best
    if best is None or out.verdict != best.effect.id:
        return None
    if out.second is None:
        out.second, tie = _second_effect(table, best, candidates, folds, location, rules)
        if tie:
            a, b = tie
            out.notes.append(f'{best.effect.id} leaves a mismatch that {a.effect.id} and {b.effect.id} explain '
                             'equally well on top of it: no second effect is named')
            out.advice = _separation_advice(a.effect, b.effect)
    second = out.second
    named = best.effect.id if second is None else f'{best.effect.id} with {second.effect.id}'
    final = best.fit if second is None else second.fit
    assert final is not None  # the named candidate was fitted
    if second is not None:
        out.notes.append(f'two effects at once: {second.effect.id} ({second.form}) explains part of what '
                         f'{best.effect.id} leaves: {second.basis}')
    chosen_test = lack_of_fit(table, final.log_residual, final.n_params, rules)
    if chosen_test.significant:
        out.notes.append(f'{named} leaves a misfit ({chosen_test.finding}): it explains part of the mismatch, '
                         'not all')
    return chosen_test
