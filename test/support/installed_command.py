# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The installed ``prsm-lube`` command as a user runs it: a whole process, output captured."""
import shutil
import subprocess


def prsm_lube(*args, timeout=600):
    """Run ``prsm-lube ARGS...`` (found on PATH, as installed) and return the completed process."""
    command = shutil.which('prsm-lube')
    assert command, 'the installed prsm-lube command is not on PATH'
    return subprocess.run([command, *map(str, args)], capture_output=True, text=True, timeout=timeout)
