# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Waiting on a live ROS graph in tests: poll with a deadline (never a bare sleep), stop node processes."""
import signal
import subprocess
import time


def wait_for(predicate, timeout, what):
    """Poll ``predicate`` until true; fail with ``what`` after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.02)
    raise AssertionError(f'timed out after {timeout} s waiting for: {what}')


def settle(items, quiet=1.0, timeout=20.0):
    """Wait until ``items`` stops growing for ``quiet`` s (or ``timeout`` s pass)."""
    deadline = time.monotonic() + timeout
    count, since = len(items), time.monotonic()
    while time.monotonic() < deadline:
        time.sleep(0.05)
        if len(items) != count:
            count, since = len(items), time.monotonic()
        elif time.monotonic() - since > quiet:
            return


def stop_process(process, signum=signal.SIGINT):
    """``signum`` (Ctrl-C by default), then the process's stderr (killed if it hangs)."""
    if process.poll() is None:
        process.send_signal(signum)
    try:
        _, stderr = process.communicate(timeout=15)
    except subprocess.TimeoutExpired:
        process.kill()
        _, stderr = process.communicate()
    return stderr
