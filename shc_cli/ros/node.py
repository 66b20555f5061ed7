"""A ROS 1 node in pure Python: the master and slave XML-RPC APIs and TCPROS, without a ROS installation.

ROS 1 has no client library on PyPI, and shc must drop into a ROS system with only its own install. A node here
is what rospy's is on the wire (wiki.ros.org/ROS/Master_API, /ROS/Slave_API, /ROS/TCPROS):

* an XML-RPC server (the *slave API*) the master and other nodes call: ``requestTopic`` hands a subscriber the
  TCPROS address of this node's publisher, ``publisherUpdate`` tells a subscriber where the publishers of its
  topic are, ``getPid``/``getBusInfo``/``shutdown`` serve ``rosnode``;
* one TCP server for every topic it publishes: a subscriber connects, sends its header (topic, type, md5sum),
  gets ours (with the message definition, which ``rosbag record`` stores) and then the messages;
* one TCP connection per (subscribed topic, publisher), each read by its own thread that deserialises the
  messages and hands them to the topic's callback;
* registration with the master (``registerPublisher``/``registerSubscriber``, undone on :meth:`RosNode.close`)
  and its parameter server (``getParam``).

Messages are serialised by ``rosbags`` (the ROS 1 Noetic type store, plus the types shc registers, e.g.
OpenSHC's ``LegState``); md5sums and message definitions are computed from the same definitions, so they equal
what ``genmsg`` computes for the ``.msg`` files (``tests/test_ros_node.py`` checks against Debian's genmsg).
"""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import threading
import xmlrpc.client
from collections.abc import Callable
from dataclasses import dataclass, field
from socketserver import ThreadingMixIn
from typing import TYPE_CHECKING
from xmlrpc.server import SimpleXMLRPCRequestHandler, SimpleXMLRPCServer

from shc_cli.errors import ShcError
from shc_cli.ros import tcpros

if TYPE_CHECKING:
    from shc_cli.ros.messages import MessageTypes
    from shc_cli.ros.transport import ParameterSink
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

Callback = Callable[[object], None]
"""A subscription's callback: called with each deserialised message (a rosbags message dataclass)."""


class RosError(ShcError):
    """The ROS master could not be reached or refused a call."""


@dataclass
class _Publication:
    topic: str
    msgtype: str
    latch: bool
    connections: list[socket.socket] = field(default_factory=list)
    last: bytes | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)


@dataclass
class _Subscription:
    topic: str
    msgtype: str
    callback: Callback
    publishers: set[str] = field(default_factory=set)
    sockets: list[socket.socket] = field(default_factory=list)


class _Quiet(SimpleXMLRPCRequestHandler):
    def log_message(self, format: str, *args: object) -> None:
        log.debug("xmlrpc: " + format, *args)


class _Server(ThreadingMixIn, SimpleXMLRPCServer):
    daemon_threads = True
    allow_reuse_address = True


class Publisher:
    """One advertised topic: :meth:`publish` sends a message to every connected subscriber."""

    def __init__(self, node: RosNode, publication: _Publication) -> None:
        self._node, self._pub = node, publication

    @property
    def topic(self) -> str:
        """The topic's full name."""
        return self._pub.topic

    @property
    def subscriber_count(self) -> int:
        """How many subscribers are connected now."""
        return len(self._pub.connections)

    def publish(self, message: object) -> None:
        """Serialise ``message`` (a rosbags message of the topic's type) and send it to every subscriber."""
        self.publish_raw(self._node.types.serialize(message, self._pub.msgtype))

    def publish_raw(self, payload: bytes) -> None:
        """Send already serialised bytes to every subscriber (a subscriber that went away is dropped)."""
        data = tcpros.frame(payload)
        with self._pub.lock:
            if self._pub.latch:
                self._pub.last = data
            for sock in list(self._pub.connections):
                try:
                    sock.sendall(data)
                except OSError:
                    self._pub.connections.remove(sock)
                    sock.close()


class RosNode:
    """A ROS 1 node registered with the master at ``master_uri`` (default ``$ROS_MASTER_URI``).

    Args:
        name: the node's name, e.g. ``/shc`` (a leading ``/`` is added).
        types: the message types it may publish or subscribe (:class:`~shc_cli.ros.messages.MessageTypes`).
        master_uri: ``http://host:port/`` of the master.
        host: the address other nodes reach this one at (``$ROS_IP``/``$ROS_HOSTNAME``, else 127.0.0.1).

    Raises:
        RosError: the master does not answer.
    """

    goal_topic = "/move_base_simple/goal"
    """Where a goal pose arrives: RViz's "2D Nav Goal" (:mod:`shc_cli.ros.path_remote`)."""
    program = "shc ros"

    def __init__(self, name: str, types: MessageTypes, master_uri: str | None = None, host: str | None = None) -> None:
        self.name = name if name.startswith("/") else "/" + name
        self.types = types
        self.master_uri = master_uri or os.environ.get("ROS_MASTER_URI", "http://127.0.0.1:11311/")
        self.host = host or os.environ.get("ROS_IP") or os.environ.get("ROS_HOSTNAME") or "127.0.0.1"
        self._master = xmlrpc.client.ServerProxy(self.master_uri, allow_none=True)
        self._publications: dict[str, _Publication] = {}
        self._subscriptions: dict[str, _Subscription] = {}
        self._closed = threading.Event()
        self._lock = threading.Lock()
        self._tcp = socket.create_server((self.host, 0))
        self.tcp_port = self._tcp.getsockname()[1]
        self._xmlrpc = _Server((self.host, 0), requestHandler=_Quiet, allow_none=True, logRequests=False)
        self.uri = f"http://{self.host}:{self._xmlrpc.server_address[1]}/"
        for method in ("getBusStats", "getBusInfo", "getMasterUri", "shutdown", "getPid", "getSubscriptions",
                       "getPublications", "paramUpdate", "publisherUpdate", "requestTopic"):
            self._xmlrpc.register_function(getattr(self, method), method)
        self._threads = [threading.Thread(target=self._xmlrpc.serve_forever, name="ros-xmlrpc", daemon=True),
                         threading.Thread(target=self._accept, name="ros-tcpros", daemon=True)]
        for thread in self._threads:
            thread.start()
        try:
            self._call("getPid")
        except RosError:
            self.close()
            raise

    # ---- the master ----------------------------------------------------------------------------------------

    def _call(self, method: str, *args: object) -> object:
        try:
            code, message, value = getattr(self._master, method)(self.name, *args)
        except (OSError, xmlrpc.client.Error) as exc:
            raise RosError(f"ROS master at {self.master_uri} did not answer {method} ({exc}); start roscore or set "
                           "ROS_MASTER_URI") from exc
        if code != 1:
            raise RosError(f"ROS master refused {method}{args[:1]}: {message}")
        return value

    def advertise(self, topic: str, msgtype: str, latch: bool = False) -> Publisher:
        """Register a publisher of ``topic`` (ROS type ``pkg/Msg`` or rosbags' ``pkg/msg/Msg``)."""
        topic, msgtype = self.resolve(topic), self.types.ros_name(msgtype)
        publication = _Publication(topic, msgtype, latch)
        with self._lock:
            self._publications[topic] = publication
        self._call("registerPublisher", topic, msgtype, self.uri)
        return Publisher(self, publication)

    def subscribe(self, topic: str, msgtype: str, callback: Callback) -> None:
        """Register a subscriber of ``topic``: ``callback(message)`` runs on a reader thread for each message."""
        topic, msgtype = self.resolve(topic), self.types.ros_name(msgtype)
        subscription = _Subscription(topic, msgtype, callback)
        with self._lock:
            self._subscriptions[topic] = subscription
        publishers = self._call("registerSubscriber", topic, msgtype, self.uri)
        assert isinstance(publishers, list)
        self._connect_publishers(subscription, [str(p) for p in publishers])

    def serve_parameters(self, robot: Robot, remote: ParameterSink) -> None:
        """Nothing: on ROS 1 OpenSHC's dynamic parameters change through the remote's parameter adjustment."""

    def get_param(self, key: str) -> object:
        """A parameter (a whole tree as nested dicts) from the master's parameter server."""
        return self._call("getParam", self.resolve(key))

    def has_param(self, key: str) -> bool:
        """Whether the parameter server has ``key``."""
        return bool(self._call("hasParam", self.resolve(key)))

    def resolve(self, name: str) -> str:
        """A global name: ``~x`` is in the node's namespace, ``x`` and ``/x`` are global (shc runs in ``/``)."""
        if name.startswith("~"):
            return f"{self.name}/{name[1:]}"
        return name if name.startswith("/") else "/" + name

    def close(self) -> None:
        """Unregister from the master, close every connection and stop the servers (idempotent)."""
        if self._closed.is_set():
            return
        self._closed.set()
        for topic in list(self._publications):
            self._quietly("unregisterPublisher", topic, self.uri)
        for topic, sub in list(self._subscriptions.items()):
            self._quietly("unregisterSubscriber", topic, self.uri)
            for sock in sub.sockets:
                _close(sock)
        for pub in self._publications.values():
            for sock in pub.connections:
                _close(sock)
        self._xmlrpc.shutdown()
        self._xmlrpc.server_close()
        _close(self._tcp)

    def _quietly(self, method: str, *args: object) -> None:
        try:
            self._call(method, *args)
        except RosError as exc:
            log.debug("%s", exc)

    def __enter__(self) -> RosNode:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- the slave API (called by the master and other nodes) ------------------------------------------------

    def getBusStats(self, caller_id: str) -> list[object]:
        return [1, "", [[], [], []]]

    def getBusInfo(self, caller_id: str) -> list[object]:
        info: list[list[object]] = []
        for pub in self._publications.values():
            info.extend([len(info), "", "o", "TCPROS", pub.topic, True] for _ in pub.connections)
        for sub in self._subscriptions.values():
            info.extend([len(info), p, "i", "TCPROS", sub.topic, True] for p in sub.publishers)
        return [1, "", info]

    def getMasterUri(self, caller_id: str) -> list[object]:
        return [1, "", self.master_uri]

    def shutdown(self, caller_id: str, msg: str = "") -> list[object]:
        log.info("shutdown requested by %s: %s", caller_id, msg)
        threading.Thread(target=self.close, daemon=True).start()
        return [1, "shutdown", 0]

    def getPid(self, caller_id: str) -> list[object]:
        return [1, "", os.getpid()]

    def getSubscriptions(self, caller_id: str) -> list[object]:
        return [1, "", [[s.topic, s.msgtype] for s in self._subscriptions.values()]]

    def getPublications(self, caller_id: str) -> list[object]:
        return [1, "", [[p.topic, p.msgtype] for p in self._publications.values()]]

    def paramUpdate(self, caller_id: str, key: str, value: object) -> list[object]:
        return [1, "", 0]

    def publisherUpdate(self, caller_id: str, topic: str, publishers: list[str]) -> list[object]:
        subscription = self._subscriptions.get(topic)
        if subscription is not None:
            self._connect_publishers(subscription, publishers)
        return [1, "", 0]

    def requestTopic(self, caller_id: str, topic: str, protocols: list[list[object]]) -> list[object]:
        if topic not in self._publications:
            return [-1, f"not a publisher of {topic}", []]
        if not any(p and p[0] == "TCPROS" for p in protocols):
            return [0, "only TCPROS", []]
        return [1, "ready on TCPROS", ["TCPROS", self.host, self.tcp_port]]

    # ---- TCPROS ---------------------------------------------------------------------------------------------

    def _accept(self) -> None:
        while not self._closed.is_set():
            try:
                sock, _ = self._tcp.accept()
            except OSError:
                return
            threading.Thread(target=self._serve_subscriber, args=(sock,), name="ros-pub", daemon=True).start()

    def _serve_subscriber(self, sock: socket.socket) -> None:
        try:
            sock.settimeout(5.0)
            header = tcpros.read_header(sock)
            pub = self._publications.get(header.get("topic", ""))
            if pub is None:
                sock.sendall(tcpros.encode_header({"error": f"no publisher of {header.get('topic')}"}))
                _close(sock)
                return
            definition, md5 = self.types.definition(pub.msgtype)
            if header.get("md5sum", "*") not in ("*", md5):
                sock.sendall(tcpros.encode_header({"error": f"md5sum {header.get('md5sum')} does not match "
                                                            f"{pub.msgtype} ({md5})"}))
                _close(sock)
                return
            sock.settimeout(None)
            if header.get("tcp_nodelay") == "1":
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            reply = {"callerid": self.name, "md5sum": md5, "type": pub.msgtype, "message_definition": definition,
                     "latching": "1" if pub.latch else "0", "topic": pub.topic}
            with pub.lock:
                sock.sendall(tcpros.encode_header(reply))
                if pub.last is not None:
                    sock.sendall(pub.last)
                pub.connections.append(sock)
        except (OSError, tcpros.TcprosError) as exc:
            log.debug("subscriber connection failed: %s", exc)
            _close(sock)

    def _connect_publishers(self, sub: _Subscription, publishers: list[str]) -> None:
        for uri in publishers:
            if uri in sub.publishers or (uri == self.uri and sub.topic not in self._publications):
                continue
            sub.publishers.add(uri)
            threading.Thread(target=self._read_publisher, args=(sub, uri), name="ros-sub", daemon=True).start()

    def _read_publisher(self, sub: _Subscription, uri: str) -> None:
        try:
            answer = xmlrpc.client.ServerProxy(uri).requestTopic(self.name, sub.topic, [["TCPROS"]])
            if not isinstance(answer, list) or answer[0] != 1 or len(answer[2]) < 3:
                raise tcpros.TcprosError(f"{uri} refused {sub.topic}: {answer!r}")
            _, host, port = answer[2][:3]
            sock = socket.create_connection((str(host), int(port)), timeout=5.0)
            sub.sockets.append(sock)
            _, md5 = self.types.definition(sub.msgtype)
            sock.sendall(tcpros.encode_header({"callerid": self.name, "topic": sub.topic, "md5sum": md5,
                                               "type": sub.msgtype, "tcp_nodelay": "1"}))
            tcpros.read_header(sock)
            sock.settimeout(None)
            while not self._closed.is_set():
                raw = tcpros.read_frame(sock)
                try:
                    sub.callback(self.types.deserialize(raw, sub.msgtype))
                except Exception:  # a bad message or callback must not end the subscription silently
                    log.exception("message on %s from %s", sub.topic, uri)
        except (OSError, xmlrpc.client.Error, tcpros.TcprosError) as exc:
            if not self._closed.is_set():
                log.info("subscription %s from %s ended: %s", sub.topic, uri, exc)
        finally:
            sub.publishers.discard(uri)


def _close(sock: socket.socket) -> None:
    with contextlib.suppress(OSError):
        sock.shutdown(socket.SHUT_RDWR)
    sock.close()
