# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""End-to-end experiments: the paper's demonstration and the diagnosis study.

Owns: ``paper_demo`` (simulate the paper's experiment, calibrate, assess,
check the claims, write figures) and ``diagnose_study`` (concealed effects
over many seeds, the confusion table).  May import every layer below the
command line and the nodes; no ROS.
"""
