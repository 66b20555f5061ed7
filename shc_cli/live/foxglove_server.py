"""A run's topics on a Foxglove WebSocket server (``foxglove-sdk``), as ROS 1 messages with their definitions.

The topics and schemas are those of ``shc export bag`` and ``shc ros`` (the same rosbags type store: OpenSHC's
LegState, sensor_msgs/JointState, tf2_msgs/TFMessage …): each topic is a Foxglove channel whose schema is the ROS 1
message definition (encoding ``ros1msg``) and whose messages are ROS 1 serialised (``ros1``), so Foxglove and any
client of the Foxglove WebSocket protocol decode them as they decode a ROS 1 bag. The server listens on 127.0.0.1
only; the SDK speaks the subprotocol ``foxglove.sdk.v1``.
"""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING, Any

from shc_cli.errors import ShcError

if TYPE_CHECKING:
    from shc_cli.ros.messages import MessageTypes

log = logging.getLogger(__name__)

DEFAULT_PORT = 8765
"""Foxglove's usual WebSocket port."""


class LiveChannel:
    """One topic: :meth:`publish` serialises a rosbags message and logs it on the channel (stamped now)."""

    def __init__(self, types: MessageTypes, channel: Any, msgtype: str) -> None:
        self._types, self._channel, self._msgtype = types, channel, msgtype

    @property
    def subscriber_count(self) -> int:
        """1 while any client is connected (the SDK does not count per channel), else 0."""
        return int(bool(self._channel.has_sinks()))

    def publish(self, message: object) -> None:
        """Serialise and send (nothing is serialised while no client listens)."""
        if self._channel.has_sinks():
            self._channel.log(self._types.serialize(message, self._msgtype), log_time=time.time_ns())


class FoxgloveTransport:
    """A Foxglove WebSocket server whose :meth:`advertise` gives channels with the ``RosNode`` publisher interface.

    Args:
        types: the message types (definitions and serialisation).
        port: the TCP port on 127.0.0.1 (0: any free port; :attr:`port` tells which).
        name: the server's name shown to clients.

    Raises:
        ShcError: the port cannot be opened.
    """

    def __init__(self, types: MessageTypes, port: int = DEFAULT_PORT, name: str = "shc") -> None:
        import foxglove

        self.types = types
        try:
            self._server = foxglove.start_server(name=name, host="127.0.0.1", port=port)
        except Exception as exc:  # the SDK raises its own error types for a port in use
            raise ShcError(f"--live: cannot open the Foxglove server on 127.0.0.1:{port} ({exc}); choose another "
                           "--live-port") from None
        self.port = int(self._server.port)
        self._channels: list[Any] = []
        log.info("live: Foxglove WebSocket server on ws://127.0.0.1:%d", self.port)

    @property
    def url(self) -> str:
        """The WebSocket URL clients connect to."""
        return f"ws://127.0.0.1:{self.port}"

    def advertise(self, topic: str, msgtype: str, latch: bool = False) -> LiveChannel:
        """A channel for ``topic`` with the ROS 1 definition of ``msgtype`` as its schema."""
        import foxglove

        definition, _ = self.types.definition(msgtype)
        schema = foxglove.Schema(name=self.types.ros_name(msgtype), encoding="ros1msg", data=definition.encode())
        channel = foxglove.Channel(topic, schema=schema, message_encoding="ros1")
        self._channels.append(channel)
        return LiveChannel(self.types, channel, msgtype)

    def close(self) -> None:
        """Close the channels and stop the server."""
        for channel in self._channels:
            channel.close()
        self._server.stop()

    def __enter__(self) -> FoxgloveTransport:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
