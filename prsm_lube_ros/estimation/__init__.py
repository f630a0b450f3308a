# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""From batches to theta_Oil: windows, calibration, assessment and health, live and offline alike.

Owns: cutting input batches into windows on an absolute time grid
(``windowing``), the least-squares fit of C_sys, C_F and C_lambda
(``calibration``) and its file (``calibration_file``), theta_Oil with its
uncertainty per window and run (``assessment``), a calibrated model
extension applied in assessment (``extension``), the diagnostic level with
hysteresis (``health``), and the offline pipeline from recordings to
results (``pipeline``).  May import the base layer, :mod:`..physics` and
:mod:`..recording`; no ROS.
"""
