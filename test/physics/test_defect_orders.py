# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Defect orders from Eq. 1-2 and the geometry; lines labelled with the component they point at."""
import math

import pytest

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.physics.actuator import Actuator, load_actuator
from prsm_lube_ros.physics.defect_orders import (bearing_defect_orders, defect_orders, label_order,
                                                 prsm_defect_orders, shared_orders)

CONFIG = __import__('pathlib').Path(__file__).resolve().parents[2] / 'config'


def test_the_default_roller_screw_has_the_orders_the_issue_names():
    orders = {o.component: o.order for o in prsm_defect_orders(Actuator())}
    assert orders == pytest.approx({'screw raceway': 6.25, 'nut raceway': 3.75, 'roller': 3.75, 'carrier': 0.375})


def test_orders_follow_the_geometry():
    actuator = Actuator(roller_mean_diameter=0.006, roller_count=12)
    orders = {o.component: o.order for o in prsm_defect_orders(actuator)}
    k_p = 0.024 / (2 * (0.024 + 0.006))
    assert orders['carrier'] == pytest.approx(k_p)
    assert orders['screw raceway'] == pytest.approx(12 * (1 - k_p))
    assert orders['nut raceway'] == pytest.approx(12 * k_p)


def test_shared_orders_are_named_together():
    groups = shared_orders(prsm_defect_orders(Actuator()))
    assert [sorted(o.component for o in g) for g in groups] == [['nut raceway', 'roller']]
    assert label_order(3.76, prsm_defect_orders(Actuator())) == 'nut raceway or roller'


def test_lines_are_labelled_by_fundamental_then_harmonic_and_nothing_else():
    orders = prsm_defect_orders(Actuator())
    assert label_order(6.3, orders) == 'screw raceway'
    assert label_order(12.5, orders) == '2x screw raceway'
    assert label_order(5.0, orders) == ''
    assert label_order(5.0, orders, resolution=1.3) != ''    # a coarse spectrum cannot tell 5.0 from 6.25


def test_support_bearing_orders_of_the_pronostia_bearing():
    orders = {o.component: o.order for o in bearing_defect_orders(13, 0.0035, 0.0256)}
    assert orders['support bearing outer race'] == pytest.approx(5.61, abs=0.01)
    assert orders['support bearing inner race'] == pytest.approx(7.39, abs=0.01)
    assert orders['support bearing cage'] == pytest.approx(0.432, abs=0.001)
    femto = load_actuator(CONFIG / 'femto_pronostia_bearing.yaml')
    assert {o.component for o in defect_orders(femto)} == set(orders)   # no roller-screw orders on that rig
    assert len(defect_orders(Actuator())) == 4                          # no bearing configured by default


@pytest.mark.parametrize('changes', [{'support_bearing_elements': -1},
                                     {'support_bearing_elements': 9, 'support_bearing_element_diameter': 0.01,
                                      'support_bearing_pitch_diameter': 0.005},
                                     {'support_bearing_elements': 9, 'support_bearing_element_diameter': 0.001,
                                      'support_bearing_pitch_diameter': 0.005,
                                      'support_bearing_contact_angle': math.pi}])
def test_a_support_bearing_no_bearing_has_is_refused_in_one_line(changes):
    with pytest.raises(InputError, match='support bearing'):
        Actuator(**changes)
