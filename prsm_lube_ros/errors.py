# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The one exception type for problems with what a user gave us.

An :class:`InputError` carries a single line that names the input (a file, a
topic, a parameter) and what is wrong with it.  Command-line tools print that
line and exit non-zero; nodes log it and keep running.  Anything else that
escapes is a bug in this package, not a user error.
"""


class InputError(ValueError):
    """Bad input, described in one line that names the input."""

    def __init__(self, message: str):
        super().__init__(' '.join(str(message).split()))
