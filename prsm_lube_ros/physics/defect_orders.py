# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Defect orders: how often a surface defect is struck, in multiples of the screw speed.

A spall or pit on a rolling surface is struck once by every contact that
passes over it, so the strikes repeat at a fixed multiple of the shaft speed:
the defect's *order*.  The envelope of the vibration (the strikes ringing the
structure) then shows a line at that order and its harmonics.

Planetary roller screw (Eq. 1-2 of the paper; ``N`` rollers, K_P and K_R the
carrier and roller-spin ratios):

* carrier (roller revolution about the screw, Eq. 1): ``K_P = omega_P / omega_S = d_S / (2 (d_S + d_R))``;
* screw raceway pass: each of the N rollers passes a point of the screw thread
  once per relative revolution, ``N (1 - K_P)``;
* nut raceway pass: the nut is fixed, the rollers revolve at K_P, ``N K_P``;
* roller defect: ``K_R = omega_R / omega_S`` (Eq. 2), a point of the roller
  touches the screw and the nut once per spin each, ``2 K_R``.

With the default actuator (d_S 24 mm, d_R 8 mm, 10 rollers) these are 6.25,
3.75, 3.75 and 0.375: the nut raceway and the roller defect share an order, so
a line there names both (:func:`label_order` joins them with " or ").

Rolling-element support bearings, when their geometry is configured (``z``
rolling elements of diameter ``d`` on pitch diameter ``D``, contact angle
``phi``; orders per revolution of the shaft they carry, outer ring fixed):

* BPFO ``z/2 (1 - d/D cos phi)``, BPFI ``z/2 (1 + d/D cos phi)``,
* BSF ``D/(2d) (1 - (d/D cos phi)^2)`` (a ball defect strikes one race per spin; the line shows at 2 BSF too),
* FTF ``1/2 (1 - d/D cos phi)``.

All orders are dimensionless (Hz per Hz of screw rotation).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import TYPE_CHECKING

from .kinematics import roller_revolution_speed, roller_rotation_speed

if TYPE_CHECKING:
    from collections.abc import Sequence

    from .actuator import Actuator

__all__ = ['BEARING_COMPONENTS', 'DefectOrder', 'ORDER_TOLERANCE', 'PRSM_COMPONENTS', 'SHARED_ORDER_TOLERANCE',
           'bearing_defect_orders', 'defect_orders', 'label_order', 'prsm_defect_orders', 'shared_orders']

#: Components of the roller screw with a defect order.
PRSM_COMPONENTS = ('screw raceway', 'nut raceway', 'roller', 'carrier')
#: Components of a support bearing with a defect order.
BEARING_COMPONENTS = ('support bearing outer race', 'support bearing inner race', 'support bearing rolling element',
                      'support bearing cage')
#: Relative distance within which a measured order points at a defect order (slip of rolling elements is 1-2 %).
ORDER_TOLERANCE = 0.03
#: Relative distance within which two defect orders count as one (a line there cannot tell them apart).
SHARED_ORDER_TOLERANCE = 0.01


@dataclass(frozen=True)
class DefectOrder:
    """One component's defect order: strikes per screw revolution."""

    order: float
    component: str


def prsm_defect_orders(actuator: Actuator) -> tuple[DefectOrder, ...]:
    """The roller screw's defect orders from Eq. 1-2 and its geometry (see module doc)."""
    d_s, d_r, rollers = actuator.screw_mean_diameter, actuator.roller_mean_diameter, actuator.roller_count
    k_p = float(roller_revolution_speed(1.0, d_s, d_r))     # Eq. 1 at omega_S = 1
    k_r = float(roller_rotation_speed(1.0, d_s, d_r))       # Eq. 2 at omega_S = 1
    return (DefectOrder(rollers * (1.0 - k_p), 'screw raceway'), DefectOrder(rollers * k_p, 'nut raceway'),
            DefectOrder(2.0 * k_r, 'roller'), DefectOrder(k_p, 'carrier'))


def bearing_defect_orders(rolling_elements: int, element_diameter: float, pitch_diameter: float,
                          contact_angle: float = 0.0) -> tuple[DefectOrder, ...]:
    """BPFO, BPFI, BSF and FTF of a rolling-element bearing (diameters in m, contact angle in rad)."""
    if rolling_elements <= 0 or not 0 < element_diameter < pitch_diameter:
        raise ValueError('a support bearing needs rolling elements > 0 and 0 < element diameter < pitch diameter')
    ratio = element_diameter / pitch_diameter * math.cos(contact_angle)
    z = float(rolling_elements)
    return (DefectOrder(z / 2.0 * (1.0 - ratio), BEARING_COMPONENTS[0]),
            DefectOrder(z / 2.0 * (1.0 + ratio), BEARING_COMPONENTS[1]),
            DefectOrder(pitch_diameter / (2.0 * element_diameter) * (1.0 - ratio ** 2), BEARING_COMPONENTS[2]),
            DefectOrder(0.5 * (1.0 - ratio), BEARING_COMPONENTS[3]))


def defect_orders(actuator: Actuator) -> tuple[DefectOrder, ...]:
    """Every defect order of the actuator: the roller screw's and, when configured, its support bearing's."""
    orders = prsm_defect_orders(actuator) if actuator.screw_defect_orders else ()
    if actuator.support_bearing_elements > 0:
        orders += bearing_defect_orders(actuator.support_bearing_elements, actuator.support_bearing_element_diameter,
                                        actuator.support_bearing_pitch_diameter,
                                        actuator.support_bearing_contact_angle)
    return orders


def shared_orders(orders: Sequence[DefectOrder],
                  tolerance: float = SHARED_ORDER_TOLERANCE) -> list[tuple[DefectOrder, ...]]:
    """Groups of defect orders closer than ``tolerance`` (relative): components a line cannot tell apart."""
    groups: list[list[DefectOrder]] = []
    for item in sorted(orders, key=lambda o: o.order):
        if groups and abs(item.order - groups[-1][0].order) <= tolerance * groups[-1][0].order:
            groups[-1].append(item)
        else:
            groups.append([item])
    return [tuple(g) for g in groups if len(g) > 1]


def label_order(order: float, orders: Sequence[DefectOrder], resolution: float = 0.0,
                harmonics: int = 3) -> str:
    """The component(s) a measured envelope line at ``order`` points at, '' when none.

    A line matches defect order ``o`` or its harmonic ``h o`` (h up to
    ``harmonics``) within ``max(ORDER_TOLERANCE h o, resolution)``, the
    spectrum's resolution in orders; the fundamental is preferred, then the
    nearest.  Components sharing the order are all named, joined by " or ";
    a harmonic is named as such ("2x screw raceway").
    """
    for harmonic in range(1, harmonics + 1):
        near = [item for item in orders
                if abs(order - harmonic * item.order) <= max(ORDER_TOLERANCE * harmonic * item.order, resolution)]
        if not near:
            continue
        nearest = min(near, key=lambda item: abs(order - harmonic * item.order))
        names = [item.component for item in near
                 if abs(item.order - nearest.order) <= SHARED_ORDER_TOLERANCE * nearest.order]
        text = ' or '.join(dict.fromkeys(names))
        return text if harmonic == 1 else f'{harmonic}x {text}'
    return ''
