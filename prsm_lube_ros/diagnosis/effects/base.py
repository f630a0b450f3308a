# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""What a candidate effect is: its physics, its parameters and how it changes Eq. 22.

Every candidate extends Eq. 22 in one of two places, or both:

* ``film_factor``: a factor on ``theta_Oil C_lambda omega^0.68 F^-0.073``
  in the exponent of Eq. 22 (the film thickness, Eq. 9-12, changes);
* ``log_gain``: a term added to ``ln A_0`` (the response to the same
  excitation changes, or vibration from elsewhere adds to it).

So the extended model is ``ln A = ln A_22(theta f) + gain`` where ``A_22`` is
Eq. 22 with theta_Oil scaled by ``f``.  Effects describe themselves with
physical parameters (a ``dict`` of floats, SI units) so a calibration can store
them; during a fit they work on an internal vector ``p`` inside ``bounds``,
converted by :meth:`Effect.to_params` with ``scales`` taken once from the data
(reference load, stroke, ...), so fits on subsets of the data stay comparable.

The covariates an effect reads come from any object with the window table's
attribute names (``speed``, ``load``, ``position``, ``revolutions``,
``temperature``, ``time``), arrays or floats.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TYPE_CHECKING, TypeVar

import numpy as np

from ...physics.effects import Extension

if TYPE_CHECKING:
    from ..locate import Location
    from ..table import WindowTable


__all__ = ['Effect', 'register', 'registered']


class Effect(Extension):
    """A candidate physical effect the paper's model leaves out, with how to fit it (subclass and register it).

    How it changes Eq. 22 comes from the effect's law module
    (:class:`prsm_lube_ros.physics.effects.Extension`); this class adds what a fit needs.
    """

    #: Effect ID (CONTRACT.md names the known ones).
    id: str = ''
    #: One-line name.
    title: str = ''
    #: The physics, in words.
    physics: str = ''
    #: How it extends Eq. 22, as text.
    equations: str = ''
    #: Names of the internal fit parameters, in order.
    parameter_names: tuple[str, ...] = ()
    #: The covariate its mismatch follows (a column of the window table or 'speed').
    covariate: str = ''
    #: What to record so this effect can be told apart from the others.
    to_separate: str = ''
    #: Name of this physical form of the effect (each of :meth:`variants` has its own).
    form: str = ''
    #: The law alone changes the spectrum's shape between speeds (a gain that depends on the frequency in Hz).
    changes_spectral_shape: bool = False
    #: The law can mimic other effects in the amplitudes (free exponents of speed, load and revolutions), so the
    #: effect is a candidate only where :meth:`independent_evidence` shows its signature on the recording.
    requires_evidence: bool = False
    #: The law adds power beside the contacts' (A^2 = A_22^2 + B^2): its gain depends on the amplitude it is added
    #: to, so a combination of two effects applies it last (:class:`~prsm_lube_ros.diagnosis.combined.CombinedEffect`).
    adds_power: bool = False
    #: The law has a free law of load (an exponent of F) that a fit can trade against the load excitation C_F of
    #: Eq. 18: a fit of it that a measurement contradicts (:meth:`measured_against`) with C_F below 0 is fitted
    #: again with C_F held at 0 or above before it is judged.
    trades_load_excitation: bool = False
    #: The law's power is in strikes, sparse in time: each window's Gaussian part (``gaussian_rms``) leaves it out,
    #: so beside it the engine seeks a second effect there too (:meth:`.WindowTable.gaussian_part`).
    impulsive: bool = False

    def applicable(self, table: WindowTable) -> str:
        """Empty when the recordings can test this effect, else why not (in words)."""
        return ''

    def scales(self, table: WindowTable) -> dict[str, Any]:
        """Data scales fixed once per diagnosis (reference values the parameters refer to)."""
        return {}

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the internal parameter vector."""
        return np.zeros(0), np.zeros(0)

    def starts(self) -> Sequence[np.ndarray]:
        """Initial internal parameter vectors for a multi-start fit."""
        return [np.zeros(0)]

    def to_params(self, p: np.ndarray, scales: dict[str, Any]) -> dict[str, Any]:
        """Physical parameters (SI) from the internal vector and the data scales."""
        return dict(scales)

    def describe(self, params: dict[str, Any]) -> str:
        """The fitted effect in words, with its size."""
        return self.physics

    def variants(self) -> Sequence[Effect]:
        """Physical forms of this effect (same id), each fitted; the engine chooses one by BIC.

        A form with more parameters than the best of the fewest-parameter forms
        must lower the BIC by the engine's form margin to be chosen.
        """
        return [self]

    def form_name(self, params: dict[str, Any], table: WindowTable, location: Location | None) -> str:
        """The form the fitted parameters and the data show (default :attr:`form`)."""
        return self.form

    def independent_evidence(self, table: WindowTable, location: Location | None,
                             params: dict[str, Any] | None = None, beside: Effect | None = None) -> str:
        """Evidence for the effect from outside the amplitude fit; empty when none.

        :meth:`spectral_evidence`, else :meth:`standstill_evidence`.
        """
        return self.spectral_evidence(table, location, params, beside) or self.standstill_evidence(table)

    def spectral_evidence(self, table: WindowTable, location: Location | None,
                          params: dict[str, Any] | None = None, beside: Effect | None = None) -> str:
        """Evidence for the effect in the recorded spectra; empty when none.

        ``params`` (the fitted parameters, when there is a fit) lets the evidence
        be checked against what the fitted law predicts; ``beside`` is the effect
        fitted with this one, whose own signature the evidence must not be.
        """
        return ''

    def standstill_evidence(self, table: WindowTable) -> str:
        """Evidence read with the screw still, which no law of the contacts explains; empty when none.

        Part of :meth:`independent_evidence` that holds beside any effect, so
        the engine seeks the effect as a second one even when the first leaves
        nothing in the amplitudes.  It measures, it does not test a law of
        speed and load: it makes no such law testable on too few conditions.
        """
        return ''

    def contrary_evidence(self, table: WindowTable, location: Location | None,
                          params: dict[str, Any] | None = None) -> str:
        """Evidence against the effect from outside the amplitude fit (its signature testable but absent)."""
        return ''

    def measured_against(self, table: WindowTable, params: dict[str, Any],
                         predicted: np.ndarray | None = None) -> str:
        """A figure the fitted law predicts and the recording measures directly, far from it; empty when none.

        ``predicted``: the fitted model's amplitude of each window (m/s^2, the
        paper's constants with every effect of the fit), None when not at hand.

        Unlike :meth:`contrary_evidence` (a signature that could show and does
        not, which decides ties), this is a measurement the fitted ``params``
        themselves contradict, as unphysical constants are: a fit so
        contradicted is not named, alone or beside another effect.
        """
        return ''

    def exclusive_evidence(self, table: WindowTable, share: float) -> str:
        """Evidence outside the amplitude fit that no other effect of the catalogue makes, in ``share`` or more of it.

        Empty when none.  A signature only this effect has (impulsive strikes,
        where oil loss, a mode, stiffness and a background all vibrate
        Gaussian), seen in ``share`` of the windows or more
        (:attr:`.rules.DiagnosisRules.exclusive_evidence_share`), names the
        effect beside a first one even when its amplitude law does not improve
        the held-out error: its share of the RMS is then left unresolved
        (``docs/diagnosis-rules.md``, "evidence no other effect makes").
        Default: none.
        """
        return ''


_REGISTRY: dict[str, Effect] = {}
_E = TypeVar('_E', bound=Effect)


def register(effect_class: type[_E]) -> type[_E]:
    """Class decorator: add an :class:`Effect` subclass (instantiated) to the registry under its ``id``."""
    effect = effect_class()
    if not effect.id:
        raise ValueError(f'{effect_class.__name__} has no id')
    _REGISTRY[effect.id] = effect
    return effect_class


def registered() -> dict[str, Effect]:
    """All registered effects by ID, in registration order."""
    return dict(_REGISTRY)
