# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""ROS 2 nodes: thin shells around the pure modules of :mod:`prsm_lube_ros`.

Owns: the sensor bridge and the lubrication estimator, their parameters,
sources and message conversion.  Importing this package imports nothing from
ROS; the node modules do (``rclpy`` and the generated ``prsm_lube_ros.msg`` /
``prsm_lube_ros.srv``).  May import every layer but :mod:`..cli`.
"""
