"""The options of ``shc ros`` (:class:`NodeConfig`), apart from the node so that its parts (the shared session, the
bus backend) can name them without importing the node."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

NodeBackend = Literal["none", "mujoco", "pybullet", "bus"]
BACKENDS = ("none", "mujoco", "pybullet", "bus")
SERVER = "server"
"""The robot name that reads the robot from the parameter server (``/syropod/parameters`` …)."""


@dataclass(frozen=True)
class NodeConfig:
    """Options of ``shc ros``.

    Attributes:
        robot: robot file or bundled name, or ``"server"``: OpenSHC's parameters from the parameter server.
        backend: ``none`` (outputs only) or a physics engine.
        name: the node's name.
        master_uri: the ROS master (None: ``$ROS_MASTER_URI``).
        duration: stop after this many seconds of wall time (None: until Ctrl-C / SIGTERM / rosnode kill).
        out: the run directory (None: ``runs/<timestamp>-ros``).
        individual: publish the per-joint command topics (default: as the robot's parameters say, else on).
        combined: publish ``/desired_joint_states``.
        overwrite: replace an existing run directory.
        namespace: the parameter tree read for ``robot = "server"``.
        live: also stream the session on a Foxglove WebSocket server on 127.0.0.1:``live_port``.
        path: a path file to walk once the robot runs (more paths and goals arrive on ``<name>/path`` and
            ``/move_base_simple/goal``: :mod:`shc_cli.ros.path_remote`).
        joint_states_timeout: backend ``none``: how long to wait at start-up for ``/joint_states`` to give every
            joint [s] (OpenSHC's ``ACQUISTION_TIME``, 10 s; 0: do not wait, start from the joints' defaults unless
            they are already there).
        ports, baud, dry_run, stop_state, on_fault, on_stop, profile_velocity: backend ``bus``: the servo buses and
            their safety, as ``run-hw``'s options (:class:`~shc_cli.domain.hardware.HardwareConfig`).
    """

    robot: str = "bullet"
    backend: NodeBackend = "none"
    name: str = "/shc"
    master_uri: str | None = None
    duration: float | None = None
    out: Path | None = None
    individual: bool = True
    combined: bool = True
    overwrite: bool = False
    namespace: str = "/syropod"
    live: bool = False
    live_port: int = 8765
    path: Path | None = None
    ports: tuple[str, ...] = ()
    baud: int | None = None
    dry_run: bool = False
    stop_state: str = "packed"
    on_fault: str = "torque-off"
    on_stop: str = "torque-off"
    profile_velocity: bool = False
    joint_states_timeout: float = 10.0

    def __post_init__(self) -> None:
        from shc_cli.errors import Issue, SpecError, check_choice
        from shc_cli.loop.input_sources import STATES

        check_choice("--backend", self.backend, BACKENDS, "a backend")
        for option, value in (("--on-fault", self.on_fault), ("--on-stop", self.on_stop)):
            check_choice(option, value, ("hold", "torque-off"), "hold or torque-off")
        check_choice("--stop-state", self.stop_state, tuple(STATES), "a robot state")
        if not self.joint_states_timeout >= 0.0:
            raise SpecError([Issue(None, None, "--joint-states-timeout", f"{self.joint_states_timeout:g} is negative",
                                   "give seconds ≥ 0 (0: do not wait for /joint_states)")])
        if (self.backend == "bus") != bool(self.ports):
            problem = ("the bus backend needs its serial ports" if self.ports == () else
                       f"--port is for the bus backend, not '{self.backend}'")
            raise SpecError([Issue(None, None, "--port", problem, "give --backend bus with --port DEV (once per "
                                   "bus, bus 0 first)")])
