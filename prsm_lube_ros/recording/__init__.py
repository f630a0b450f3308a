# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Recordings in and out: rosbag2 folders, bare MCAP and sqlite3 files.

Owns: the streaming reader (``reader``: recordings in, numpy batches of the
contract's topics out), the MCAP container parser (``mcap_file``), the
rosbag2 sqlite3 storage reader (``sqlite_file``), bulk CDR decoding of the
contract's messages (``cdr``), the batch types every layer above consumes
(``batches``), the contract bag writer (``writer``) and the rosbags type
store with the contract's interfaces (``typestore``).  May import only the
base layer; no physics, no ROS.
"""
