# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The paper's physics, Eq. 1-23, and the laws of the effects it leaves out.

Owns: the actuator geometry (``actuator``), kinematics (Eq. 1-7), the
Hamrock-Dowson film and its starved form (Eq. 8-12, ``film``), Hertzian
contact (Eq. 16-17, ``contact``), the one-degree-of-freedom vibration model
and the lubrication index (Eq. 13-15, 18-23, ``vibration_model``), and one
module per physical effect (``effects/``), shared by the simulator, the
diagnosis and assessment.  SI units throughout; each equation is named by its
number in a docstring.  May import only the base layer (``errors``,
``validation``, ``config_file``, ``contract``) and numpy/scipy; no ROS.

Types: the laws take scalars or numpy arrays and broadcast.  An argument the
law turns into an array first is annotated ``npt.ArrayLike``; one it computes
with as given is ``np.ndarray | float``.  What comes back is a float for
scalar arguments and an array otherwise, annotated ``np.ndarray | float``
(numpy hands back a numpy scalar, a float, for 0-d results).  The Eq. 22/23
functions that the estimation and diagnosis call with arrays carry overloads
saying so.
"""
