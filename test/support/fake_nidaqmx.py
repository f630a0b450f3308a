# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A fake ``nidaqmx`` module with the names the sensor bridge uses, for tests without a card."""
import time
import types

import numpy as np


class FakeTask:
    """Records the configuration; read() returns block k as g values k + i/1000."""

    instances = []
    fail_on = None          # 'create' | 'channel' | 'read'

    def __init__(self):
        if FakeTask.fail_on == 'create':
            raise RuntimeError('Could not find an installation of NI-DAQmx.\nPlease install the driver.')
        FakeTask.instances.append(self)
        self.channel_args, self.timing_args, self.read_sizes = None, None, []
        self.started = self.stopped = self.closed = False
        self.channel = types.SimpleNamespace()
        outer = self

        class Channels:
            def add_ai_accel_chan(self, physical_channel, **kwargs):
                if FakeTask.fail_on == 'channel':
                    raise RuntimeError(f'Device identifier is invalid: {physical_channel}')
                outer.channel_args = dict(kwargs, physical_channel=physical_channel)
                return outer.channel

        class Timing:
            def cfg_samp_clk_timing(self, rate, sample_mode=None, samps_per_chan=None):
                outer.timing_args = (rate, sample_mode, samps_per_chan)

        self.ai_channels, self.timing = Channels(), Timing()

    def start(self):
        self.started = True

    def read(self, number_of_samples_per_channel, timeout):
        if FakeTask.fail_on == 'read' and self.read_sizes:
            raise RuntimeError('The application is not able to keep up with the hardware acquisition.')
        k = len(self.read_sizes)
        self.read_sizes.append(number_of_samples_per_channel)
        time.sleep(0.005)
        return list(k + np.arange(number_of_samples_per_channel) / 1000.0)

    def stop(self):
        self.stopped = True

    def close(self):
        self.closed = True


def fake_nidaqmx():
    """Modules nidaqmx and nidaqmx.constants with the names the bridge uses (old sensitivity name)."""
    def enum(name, *members):
        return type(name, (), {m: f'{name}.{m}' for m in members})
    constants = types.ModuleType('nidaqmx.constants')
    constants.AccelUnits = enum('AccelUnits', 'G', 'METERS_PER_SECOND_SQUARED')
    constants.AccelSensitivityUnits = enum('AccelSensitivityUnits', 'M_VOLTS_PER_G', 'VOLTS_PER_G')
    constants.ExcitationSource = enum('ExcitationSource', 'INTERNAL', 'EXTERNAL', 'NONE')
    constants.Coupling = enum('Coupling', 'AC', 'DC')
    constants.AcquisitionType = enum('AcquisitionType', 'CONTINUOUS', 'FINITE')
    module = types.ModuleType('nidaqmx')
    module.Task = FakeTask
    module.constants = constants
    return {'nidaqmx': module, 'nidaqmx.constants': constants}
