"""shc: OpenSHC's multilegged gait controller in Python, and the tools around it.

The public Python API (docs/python-api.md), imported lazily so ``import shc_cli`` and ``shc --help`` stay fast::

    import shc_cli
    run = shc_cli.simulate("bullet", gait="tripod", duration=20)
    run.summary.cot, run.log.position, run.path
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

from shc_cli.version import __version__ as __version__

_EXPORTS = {
    "Run": "shc_cli.api", "SweepResult": "shc_cli.api", "analyze": "shc_cli.api", "load_gait": "shc_cli.api",
    "load_robot": "shc_cli.api", "open_run": "shc_cli.api", "plan": "shc_cli.api", "simulate": "shc_cli.api",
    "sweep": "shc_cli.api", "optimize": "shc_cli.api", "fit": "shc_cli.api", "StudyResult": "shc_cli.api",
    "SimulationConfig": "shc_cli.domain.config",
    "RunLog": "shc_cli.record.runread", "RunSummary": "shc_cli.record.summary",
    "Controller": "shc_cli.control.controller", "Command": "shc_cli.control.controller",
    "RobotState": "shc_cli.control.controller",
    "ShcError": "shc_cli.errors", "SpecError": "shc_cli.errors",
}
"""Public name → the module that defines it."""

__all__ = ["Command", "Controller", "RobotState", "Run", "RunLog", "RunSummary", "ShcError", "SimulationConfig",
           "SpecError", "StudyResult", "SweepResult", "__version__", "analyze", "fit", "load_gait", "load_robot",
           "open_run", "optimize", "plan", "simulate", "sweep"]

if TYPE_CHECKING:
    from shc_cli.api import (
        Run,
        StudyResult,
        SweepResult,
        analyze,
        fit,
        load_gait,
        load_robot,
        open_run,
        optimize,
        plan,
        simulate,
        sweep,
    )
    from shc_cli.control.controller import Command, Controller, RobotState
    from shc_cli.domain.config import SimulationConfig
    from shc_cli.errors import ShcError, SpecError
    from shc_cli.record.runread import RunLog
    from shc_cli.record.summary import RunSummary


def __getattr__(name: str) -> Any:
    """Import a public name's module on first use."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'shc_cli' has no attribute '{name}'")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))
