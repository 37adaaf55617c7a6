"""An rclpy test client (ROS 2 Jazzy, Fast DDS) shared by the rclpy tests.

rclpy 7.1.6 pitfalls avoided: a private Context, an own SingleThreadedExecutor polled with
spin_once and wall-clock deadlines, no spin_until_future_complete with service futures, no
EventsExecutor. Only use inside scripts/netns-isolate."""

from __future__ import annotations

import time

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

TIMEOUT = 10.0
# Closing waits for QUIET s without a change in the graph, at most QUIET_MAX s (see close).
QUIET, QUIET_MAX = 0.5, 5.0


class RclpyAgent:
    """An rclpy node with its own context and executor; everything waits by polling spin_once
    until a wall-clock deadline."""

    def __init__(self, domain: int):
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = Node("composuite_test_agent", context=self.context,
                         start_parameter_services=False, enable_rosout=False)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def close(self) -> None:
        self.until_discovery_is_quiet()
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)

    def until_discovery_is_quiet(self) -> None:
        """Spin until the ROS graph this node sees has not changed for QUIET s (at most
        QUIET_MAX s). Deleting the node deletes its Fast DDS participant, and Fast DDS 2.14 (the
        Jazzy wheels') can deadlock there if a discovery callback runs at that moment: seen in
        a fresh-clone test run, the main thread spinning in DomainParticipant::set_listener(nullptr) called
        by rmw's destroy_participant, a receive thread blocked in
        MyRTPSParticipantListener::onWriterDiscovery — for good, with the GIL held. Those
        callbacks come while remote endpoints are still being discovered (a test that closes
        its agent right after the first services answer, with three environments' worth of
        endpoints still arriving), so the agent waits for discovery to settle first."""
        node = self.node

        def graph():
            topics = node.get_topic_names_and_types()
            return (tuple((name, tuple(types), node.count_publishers(name), node.count_subscribers(name))
                          for name, types in topics),
                    tuple(sorted((name, tuple(types)) for name, types in node.get_service_names_and_types())),
                    tuple(sorted(node.get_node_names_and_namespaces())))

        deadline = time.monotonic() + QUIET_MAX
        last, since = graph(), time.monotonic()
        while time.monotonic() - since < QUIET and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.05)
            now = graph()
            if now != last:
                last, since = now, time.monotonic()

    def spin_until(self, condition, timeout: float = TIMEOUT, what: str = "a condition"):
        deadline = time.monotonic() + timeout
        while True:
            value = condition()
            if value:
                return value
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise AssertionError(f"timed out after {timeout} s waiting for {what}")
            self.executor.spin_once(timeout_sec=min(remaining, 0.05))

    def call(self, client, request, timeout: float = TIMEOUT, attempt: float = 3.0):
        """A service call: wait for the server, send, spin until the reply (no
        spin_until_future_complete: its 7.1.6 slow-down with service futures). A reply sent
        before the server's reply writer matched this client is lost (each side sees the
        match on its own): after `attempt` s without one, ask again, until `timeout`."""
        assert client.wait_for_service(timeout_sec=timeout), f"service {client.srv_name} not available"
        deadline = time.monotonic() + timeout
        while True:
            future = client.call_async(request)
            try:
                self.spin_until(future.done, min(attempt, max(deadline - time.monotonic(), 0.01)),
                                f"the reply of {client.srv_name}")
                return future.result()
            except AssertionError:
                client.remove_pending_request(future)
                if time.monotonic() >= deadline:
                    raise
