# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Low-level reading of recordings: the MCAP container and the contract's CDR messages.

The public entry point is :mod:`prsm_lube_ros.bag_reader`.
"""
