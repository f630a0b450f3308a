# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Starting and stopping a node process: bad configuration is one line, Ctrl-C a clean exit.

rclpy's own signal handlers shut the context down from a thread of their
own while the executor may be inside a callback (taking or publishing a
message); that race ends a node with SIGSEGV now and then (seen on Kilted in
CI: exit -11 after Ctrl-C, and reported upstream against rclpy).  The node
processes therefore start rclpy with ``SignalHandlerOptions.NO`` and catch
SIGINT and SIGTERM themselves: the handler only sets a flag, the spin loop
(``spin_once`` with a short timeout) sees it between callbacks, and the
executor, the nodes and the context are torn down in that order, on the main
thread, with nothing else running.
"""
from __future__ import annotations

import gc
import signal
import sys
import threading
from typing import Any
from collections.abc import Callable, Sequence

import rclpy
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from ..errors import InputError

__all__ = ['EXIT_BAD_INPUT', 'STOP_POLL_PERIOD', 'autostart', 'build_node', 'freeze_startup_objects', 'init_ros',
           'run_node', 'spin_until_stopped']

#: Exit status of a node whose configuration or source cannot be used.
EXIT_BAD_INPUT = 2
#: Longest wait of the spin loop before it looks at the stop flag again [s].
STOP_POLL_PERIOD = 0.1

_stop_requested = threading.Event()


def init_ros(args: Sequence[str] | None = None) -> None:
    """``rclpy.init`` without rclpy's signal handlers; SIGINT/SIGTERM set the stop flag instead.

    Off the main thread (a node started inside a test or another program)
    signals stay with whoever owns them.
    """
    _stop_requested.clear()
    rclpy.init(args=None if args is None else list(args), signal_handler_options=SignalHandlerOptions.NO)
    if threading.current_thread() is threading.main_thread():
        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, _request_stop)


def _request_stop(signum: int, frame: object) -> None:
    """Signal handler: ask the spin loop to stop; a second signal of the kind ends the process at once.

    Nothing else happens here (it may run between any two bytecodes).  The
    default disposition is put back so that a teardown that hangs (a blocked
    hardware read, say) still yields to a second Ctrl-C.
    """
    _stop_requested.set()
    signal.signal(signum, signal.SIG_DFL)


def autostart(node: LifecycleNode) -> None:
    """A lifecycle node's ``autostart``: configure, then activate; InputError when a step does not succeed."""
    if node.trigger_configure() != TransitionCallbackReturn.SUCCESS:
        raise InputError('autostart: configure failed (see the log line before)')
    if node.trigger_activate() != TransitionCallbackReturn.SUCCESS:
        raise InputError('autostart: activate failed (see the log line before)')


def build_node(factory: Callable[[], Node], node_name: str) -> Node | None:
    """``factory()``; on :class:`InputError` print ``<node_name>: error: <line>``, shut rclpy down, return None."""
    try:
        return factory()
    except InputError as exc:
        print(f'{node_name}: error: {exc}', file=sys.stderr)
        rclpy.try_shutdown()
        return None


def freeze_startup_objects() -> None:
    """Move everything alive now out of the garbage collector's generations (``gc.freeze``).

    A node process's start-up objects (modules, rclpy, the node and its
    tables) live until it exits; left in the oldest generation, every full
    collection walks them again: 20-30 ms each from 64 actuators on, in the
    middle of a callback, 0.9-2.7 ms once frozen (``benchmarks/live_latency.py``,
    its full-collection column).  Cycles made later are collected as before.
    """
    gc.collect()
    gc.freeze()


def run_node(factory: Callable[[], Node], node_name: str, args: Sequence[str] | None = None,
             done: Callable[[Any], bool] = lambda node: False,
             exit_status: Callable[[Any], int] = lambda node: 0) -> int:
    """A node process from start to end: :func:`init_ros`, :func:`build_node`, :func:`spin_until_stopped`.

    Returns :data:`EXIT_BAD_INPUT` when the node cannot be built, else
    ``exit_status(node)`` once a stop signal or ``done(node)`` ended it.
    """
    init_ros(args)
    node = build_node(factory, node_name)
    if node is None:
        return EXIT_BAD_INPUT
    freeze_startup_objects()
    spin_until_stopped([node], done=lambda: done(node))
    return exit_status(node)


def spin_until_stopped(nodes: Sequence[Node], done: Callable[[], bool] = lambda: False,
                       executor: Executor | None = None) -> None:
    """Spin ``nodes`` until a stop signal, ``done()``, or shutdown; then tear everything down in order.

    The executor is shut down first (no callback runs after it), then each
    node is destroyed, then the context; all on the calling thread.
    """
    executor = executor or SingleThreadedExecutor()
    for node in nodes:
        executor.add_node(node)
    try:
        while rclpy.ok() and not _stop_requested.is_set() and not done():
            executor.spin_once(timeout_sec=STOP_POLL_PERIOD)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown()
