# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Actuator geometry, materials and lubricant: the inputs of the paper's model.

Every quantity is SI (m, rad, N, Pa, Pa*s, 1/Pa); temperatures are degC as in
the contract's ``sensor_msgs/Temperature``.  :func:`load_actuator` reads the
``actuator:`` mapping of a YAML file such as ``config/actuator.yaml``; fields a
file leaves out keep the contract's default actuator values.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, replace
import math
from pathlib import Path
from typing import Any, TYPE_CHECKING

from ..config_file import build, coerce_fields, read_section
from ..errors import InputError
from ..validation import require_all_positive

if TYPE_CHECKING:
    import numpy as np


__all__ = ['Actuator', 'load_actuator']


@dataclass(frozen=True)
class Actuator:
    """One planetary roller screw and what it is made of."""

    name: str = 'prsm_default'
    screw_mean_diameter: float = 0.024
    roller_mean_diameter: float = 0.008
    lead: float = 0.005
    flank_angle: float = math.radians(45.0)
    roller_count: int = 10
    threads_per_roller: int = 12
    nut_travel: float = 0.18
    youngs_modulus: float = 2.06e11
    poisson_ratio: float = 0.3
    oil_viscosity: float = 0.1
    oil_reference_temperature: float = 40.0
    pressure_viscosity_coefficient: float = 2.0e-8
    viscosity_temperature_coefficient: float = 0.03
    composite_roughness: float = 4.0e-7
    shaft_root_diameter: float = 0.0215
    shaft_fixed_end_offset: float = 0.03
    #: Support bearing of the screw (for its defect orders, :mod:`.defect_orders`): rolling elements (0: not
    #: configured), their diameter and pitch diameter in m, contact angle in rad.
    support_bearing_elements: int = 0
    support_bearing_element_diameter: float = 0.0
    support_bearing_pitch_diameter: float = 0.0
    support_bearing_contact_angle: float = 0.0
    #: Whether the roller screw's own defect orders label envelope lines (False: a bearing test rig without one).
    screw_defect_orders: bool = True

    def __post_init__(self) -> None:
        """Reject geometry that no roller screw has."""
        positive = ('screw_mean_diameter', 'roller_mean_diameter', 'lead',
                    'roller_count', 'threads_per_roller', 'nut_travel',
                    'youngs_modulus', 'oil_viscosity',
                    'pressure_viscosity_coefficient', 'viscosity_temperature_coefficient',
                    'composite_roughness',
                    'shaft_root_diameter')
        require_all_positive('actuator', **{key: getattr(self, key) for key in positive})
        if not 0.0 < self.flank_angle < math.pi / 2:
            raise InputError(
                f'actuator flank_angle must lie between 0 and pi/2 rad, got {self.flank_angle!r}')
        if self.support_bearing_elements < 0 or (self.support_bearing_elements > 0 and not (
                0.0 < self.support_bearing_element_diameter < self.support_bearing_pitch_diameter
                and 0.0 <= self.support_bearing_contact_angle < math.pi / 2)):
            raise InputError('actuator support bearing needs support_bearing_elements >= 0 and, when > 0, '
                             '0 < support_bearing_element_diameter < support_bearing_pitch_diameter and '
                             'support_bearing_contact_angle in [0, pi/2) rad')
        if not 0.0 <= self.poisson_ratio < 0.5:
            raise InputError(
                f'actuator poisson_ratio must lie in [0, 0.5), got {self.poisson_ratio!r}')

    @property
    def lead_angle(self) -> float:
        """Lead angle of the screw alpha_S in rad: tan(alpha_S) = lead / (pi d_S)."""
        return math.atan(self.lead / (math.pi * self.screw_mean_diameter))

    def nut_travel_from_angle(self, angle: np.ndarray | float,
                              angle_at_motion_start: np.ndarray | float) -> np.ndarray | float:
        """Nut travel in m from screw angles in rad (CONTRACT.md).

        ``lead * (angle - angle_at_motion_start) / (2 pi)``; works on arrays.
        """
        return self.lead * (angle - angle_at_motion_start) / (2.0 * math.pi)

    def as_dict(self) -> dict[str, Any]:
        """Plain mapping, as written under ``actuator:`` in YAML."""
        return asdict(self)

    def with_changes(self, **changes: Any) -> Actuator:
        """Copy with some fields replaced (validated again)."""
        return replace(self, **changes)


def load_actuator(path: str | Path | None = None) -> Actuator:
    """Read an actuator from YAML; ``None`` gives the contract's default actuator.

    Raises :class:`InputError` naming the file for anything unreadable.
    """
    if path is None:
        return Actuator()
    values = read_section(path, ['actuator'], 'actuator file')
    return build(path, Actuator, coerce_fields(path, Actuator, values, label='actuator'))
