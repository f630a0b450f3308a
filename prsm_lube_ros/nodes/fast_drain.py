# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The estimator's fast input drain: the one place that leans on rclpy internals.

The estimator keeps its high-rate auxiliary subscriptions (joint states, load,
temperature) out of the executor's wait set and takes their queued messages
itself.  That needs three things rclpy does not promise:

* executors ask ``CallbackGroup.can_execute`` before waiting on an entity
  (a group that always says no is never waited on);
* ``Subscription.handle`` is a context-managed C handle with
  ``take_message(msg_type, raw)`` returning ``(msg, info)`` or None;
* ``Subscription.msg_type`` and ``Subscription.raw``.

:class:`FastDrain` checks all of it once at start-up.  When anything is
missing it says so in one loud warning line and the node falls back to plain
subscription callbacks (slower, same windows); it never drains silently into
nothing.
"""
from __future__ import annotations

from collections.abc import Iterator
import inspect
from typing import Any

from rclpy.callback_groups import CallbackGroup, ReentrantCallbackGroup
from rclpy.executors import Executor
from rclpy.impl.rcutils_logger import RcutilsLogger
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription


__all__ = ['DrainedCallbackGroup', 'FastDrain', 'missing_api']


class DrainedCallbackGroup(ReentrantCallbackGroup):
    """Callback group whose entities the executor never waits on: the node takes their messages itself."""

    def can_execute(self, entity: object) -> bool:  # type: ignore[override, unused-ignore]  # Kilted: Literal[True]
        """Always False: executors leave the group's entities out of their wait sets."""
        return False


def missing_api() -> str:
    """What of the private rclpy API the drain needs is missing ('' when everything is there)."""
    missing = []
    if not hasattr(getattr(_rclpy, 'Subscription', None), 'take_message'):
        missing.append('_rclpy.Subscription.take_message')
    if not isinstance(getattr(Subscription, 'handle', None), property):
        missing.append('Subscription.handle')
    if not callable(getattr(CallbackGroup, 'can_execute', None)):
        missing.append('CallbackGroup.can_execute')
    else:
        try:
            if 'can_execute' not in inspect.getsource(Executor):
                missing.append('executors asking CallbackGroup.can_execute')
        except (OSError, TypeError):      # no source to read: trust the method being there
            pass
    return ', '.join(missing)


def _never_called(msg: object) -> None:
    """Callback of a subscription in :class:`DrainedCallbackGroup` (its queue is drained, not spun)."""


class FastDrain:
    """Start-up check of the drain API plus the drain itself; ``enabled`` False means plain callbacks."""

    def __init__(self, logger: RcutilsLogger) -> None:
        self._logger = logger
        missing = missing_api()
        self.enabled = not missing
        self.group = DrainedCallbackGroup() if self.enabled else None
        self.never_called = _never_called
        self._failed = False
        if missing:
            logger.warning(f'FAST DRAIN OFF: this rclpy lacks {missing}; joint states, load and temperature '
                           'are taken through plain subscription callbacks instead (more CPU, same windows)')

    def drain(self, subscription: Subscription | None, limit: int) -> Iterator[Any]:
        """Messages already queued on ``subscription`` (at most ``limit``), oldest first; none when disabled."""
        if not self.enabled or subscription is None:
            return
        handle = getattr(subscription, 'handle', None)
        if handle is None or not hasattr(handle, 'take_message'):
            if not self._failed:
                self._failed = True
                self._logger.error(f'fast drain: {subscription.topic_name} has no take_message; its queued '
                                   'messages are not taken (please report)')
            return
        for _ in range(limit):
            with handle:
                taken = handle.take_message(subscription.msg_type, subscription.raw)
            if taken is None:
                return
            yield taken[0]
