# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A private ROS graph side for tests: its own rclpy context, an executor spinning in a thread, torn down whole."""
import threading


class SpinningContext:
    """An rclpy context on ``domain_id`` whose nodes a SingleThreadedExecutor spins in a background thread.

    ``probe_name`` adds a plain node for test publishers and subscriptions.
    Exceptions a callback raises while spinning are kept in ``errors`` (a
    node would have crashed); :meth:`close` stops spinning, destroys every
    node and shuts the context down.
    """

    def __init__(self, domain_id: int, probe_name: str = ''):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.nodes = []
        self.errors = []
        self.closing = False
        self.probe = rclpy.create_node(probe_name, context=self.context) if probe_name else None
        if self.probe is not None:
            self.executor.add_node(self.probe)
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self):
        try:
            self.executor.spin()
        except Exception as exc:      # a callback that raised: the node would have crashed
            if not self.closing:
                self.errors.append(exc)

    def add(self, node):
        """Spin ``node`` in this context (destroyed on close)."""
        self.nodes.append(node)
        self.executor.add_node(node)
        return node

    def close(self):
        """Stop spinning, destroy every node, shut the context down."""
        import rclpy
        self.closing = True
        self.executor.shutdown(timeout_sec=5)
        self.thread.join(timeout=5)
        for node in self.nodes + ([self.probe] if self.probe is not None else []):
            node.destroy_node()
        rclpy.try_shutdown(context=self.context)


#: Sends per idempotent request.  A service can answer before DDS has matched its response writer with
#: the client's reader; rmw_fastrtps then drops the answer ("failed to send response (timeout)", seen on
#: Kilted under load), so a request nothing has answered is simply sent again.
ATTEMPTS = 3


def answered(send, what: str, timeout: float, attempts: int = ATTEMPTS):
    """The result of the future ``send()`` returns, sending again (up to ``attempts``) when none comes.

    ``send`` must make an idempotent request (a get, a list, a set to the
    same value, a refused call): a late answer to an earlier send is dropped.
    """
    import threading
    for _ in range(attempts):
        future = send()
        done = threading.Event()
        future.add_done_callback(lambda _: done.set())
        if done.wait(timeout):
            return future.result()
        future.cancel()
    raise AssertionError(f'no answer to {what} after {attempts} sends')


def torn_down(side: SpinningContext):
    """Fixture body: yield ``side`` to one test, then close it and fail if a callback raised meanwhile."""
    try:
        yield side
    finally:
        side.close()
    assert not side.errors, f'executor raised: {side.errors}'
