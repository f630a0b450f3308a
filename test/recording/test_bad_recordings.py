# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A recording carrying every bad input of the foundation issue, assessed end to end.

A clean simulated stage is copied message by message with defects written in:
NaN and inf samples, an empty block, zero and negative sample rates, a block
stamped 2 s back, a gap of lost blocks, and a whole run at zero load.  The
assessment must finish, report each kind in one line naming the recording,
mark the affected windows NaN with a reason, and assess the rest as before.
"""
import json
import math

import numpy as np
import pytest
from rosbags.rosbag2 import Reader, StoragePlugin, Writer

from prsm_lube_ros.cli import main
from prsm_lube_ros.recording.typestore import contract_typestore


@pytest.fixture(scope='module')
def recordings(tmp_path_factory):
    root = tmp_path_factory.mktemp('bad')
    config = root / 'sim.yaml'
    config.write_text('rig_simulator:\n  plan:\n    stage_thetas: [1.0, 0.8]\n')
    assert main(['simulate', str(root / 'sim'), '--config', str(config), '--seed', '5']) == 0
    clean = root / 'sim' / 'stage_2'
    damaged = root / 'damaged'
    defects = copy_with_defects(clean, damaged)
    calib = root / 'calib.yaml'
    assert main(['calibrate', str(root / 'sim' / 'stage_1'), '--out', str(calib)]) == 0
    return clean, damaged, calib, defects


def copy_with_defects(source, target):
    """Copy a bag, damaging chosen vibration blocks and one run's load; returns what was done."""
    store = contract_typestore()
    defects = {}
    with Reader(source) as reader:
        vib = [c for c in reader.connections if c.topic.endswith('/vibration')][0]
        load = [c for c in reader.connections if c.topic.endswith('/axial_load')][0]
        blocks = [*reader.messages(connections=[vib])]
        zero_load_until = blocks[0][1] + 30_000_000_000  # the first run (100 r/min, ~23 s) and its rewind
        with Writer(target, version=Writer.VERSION_LATEST, storage_plugin=StoragePlugin.MCAP) as writer:
            conns = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=store) for c in reader.connections}
            index = 0
            old_block = None
            for conn, log_time, raw in reader.messages():
                msg = store.deserialize_cdr(raw, conn.msgtype)
                if conn.id == vib.id:
                    index += 1
                    if index == 40:
                        samples = msg.samples.copy()
                        samples[:7] = np.nan
                        samples[7] = np.inf
                        msg.samples = samples
                        defects['nonfinite'] = msg.header.stamp.sec
                    elif index == 60:
                        msg.samples = np.zeros(0, np.float32)
                    elif index == 80:
                        msg.sample_rate = 0.0
                    elif index == 81:
                        msg.sample_rate = -4000.0
                    elif 100 <= index < 106:
                        continue   # lost blocks
                    elif index == 20:
                        old_block = raw
                    elif index == 45:   # a block stamped 2.5 s back arrives
                        writer.write(conns[conn.id], log_time, old_block)
                elif conn.id == load.id and log_time <= zero_load_until:
                    msg.wrench.force.z = 0.0
                writer.write(conns[conn.id], log_time, store.serialize_cdr(msg, conn.msgtype))
    return defects


def assess(bag, calib, out, capfd):
    status = main(['assess', str(bag), '--calibration', str(calib), '--json', str(out)])
    err = capfd.readouterr().err
    return status, json.loads(out.read_text()), [line for line in err.splitlines() if line.strip()]


def test_every_defect_is_reported_in_one_line_and_nothing_crashes(recordings, tmp_path, capfd):
    clean, damaged, calib, _ = recordings
    status, document, lines = assess(damaged, calib, tmp_path / 'a.json', capfd)
    assert status == 0
    assert 'Traceback' not in '\n'.join(lines)
    assert all(str(damaged) in line for line in lines)
    text = '\n'.join(lines)
    for needle in ('NaN or inf sample', 'empty block', 'sample_rate', 'stamps going backwards'):
        assert sum(needle in line for line in lines) == 1, (needle, text)


def test_damaged_windows_are_nan_with_their_reason_and_the_rest_is_unchanged(recordings, tmp_path, capfd):
    clean, damaged, calib, _ = recordings
    _, reference, _ = assess(clean, calib, tmp_path / 'clean.json', capfd)
    _, document, _ = assess(damaged, calib, tmp_path / 'damaged.json', capfd)
    # The zero-load run is not assessed, with the reason in words.
    zero_load = [r for r in document['unassessed_runs'] if r['axial_load'] < 1.0 and r['screw_speed'] < 12]
    assert zero_load and 'axial load' in zero_load[0]['reason']
    # The gap of six lost blocks leaves its window unassessed, not a crash or a biased RMS.
    all_windows = reference['windows']
    lost = [w for w in document['windows'] if 'blocks lost' in (w['reason'] or '')]
    assert len(lost) >= 1 and all(w['theta_oil'] is None for w in lost)
    # Runs away from the damage keep their theta.
    damaged_runs = {round(r['start']): r for r in document['runs']}
    same = [r for r in reference['runs'] if round(r['start']) in damaged_runs]
    assert len(same) >= 4 and len(all_windows) > 0
    for run in same:
        other = damaged_runs[round(run['start'])]
        assert other['theta_oil'] == pytest.approx(run['theta_oil'], abs=0.01)
        assert math.isfinite(other['theta_oil_std'])
