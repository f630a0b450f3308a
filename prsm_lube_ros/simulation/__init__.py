# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Simulated rigs that write contract recordings with a known truth, for the demo, tests and studies.

Owns: the rig's configuration (``rig_config``), its drive program
(``drive``), the acceleration signal streamed or live (``rig_acceleration``), the
recordings and ``truth.json`` (``recordings``), which effects act and
their drawn strengths (``effects``; the laws are
:mod:`prsm_lube_ros.physics.effects`) and a fleet in service (``fleet``).
May import the base layer, :mod:`..physics`, :mod:`..recording` and
:mod:`..estimation`; no ROS.  (The second simulator, of window tables made
by other means, builds diagnosis tables and so lives in
:mod:`prsm_lube_ros.experiments.synthetic_tables`.)

The rig simulator in detail: the simulated test rig of the paper.

The rig turns the screw of the default actuator through the paper's
experiment (Sec. 3.1): single-direction feed over the 180 mm stroke with
acceleration and deceleration ramps, three speeds x two loads, after each of
three lubrication steps; between runs the nut returns to the start at a fixed
rewind speed with the load actuator off.  It records what a real rig would:
4 kHz nut acceleration (``VibrationBlock``), screw joint states, axial load
and temperature, as rosbag2 bags (:mod:`prsm_lube_ros.recording.writer`), and writes
the truth (theta per stage, constants, schedule, effects) to ``truth.json``.

The acceleration is a time signal whose RMS follows Eq. 22
(:func:`prsm_lube_ros.physics.vibration_model.acceleration_amplitude`) with the
simulator's true constants, built from unit-RMS components mixed by power
shares and scaled sample by sample by the target amplitude A(t) of the
instantaneous speed and load:

* thread-contact excitation: white noise through a lightly damped structural
  mode (second-order resonator, gain normalised by its impulse-response energy);
* rotation-order harmonics (1x and the roller-pass order of Eq. 1), their
  phase the order times the screw angle, hence continuous through speed changes;
* sensor noise, white, small against the signal.

Optional physical effects (:mod:`prsm_lube_ros.simulation.effects`) change the truth.
Everything streams in chunks of about one second, so memory stays flat.
Same seed, same configuration => identical samples.  No ROS import.
"""
