# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""End-to-end experiments: the paper's demonstration and the diagnosis study.

Owns: ``paper_demo`` (simulate the paper's experiment, calibrate, assess,
check the claims, write figures), ``diagnose_study`` (concealed effects
over many seeds, the confusion table), ``synthetic_tables`` (the second
simulator: diagnosis window tables made without a time signal) and
``fleet_study`` (forecasts against the simulated truth).  May import every layer below the
command line and the nodes; no ROS.
"""
