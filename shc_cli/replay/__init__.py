"""``shc replay``: drive the controller with a recorded OpenSHC run's inputs and compare every cycle's outputs.

The parts are separable, so any loop can replay a run:

* :mod:`shc_cli.replay.source` (with :mod:`~shc_cli.replay.recording` and :mod:`~shc_cli.replay.bagfile`): a
  recording or a bag → per-cycle arrays (:class:`~shc_cli.replay.source.Recorded`);
* :mod:`shc_cli.replay.states`: the state requests, inferred from the data (robust to stalls);
* :mod:`shc_cli.replay.recorded_inputs`: the per-cycle command source for the controller;
* :mod:`shc_cli.replay.compare`: the comparison, which consumes the controller's outputs.

:func:`~shc_cli.replay.run.replay` (:mod:`shc_cli.replay.run`) runs them through the one run loop
(:class:`~shc_cli.loop.run_loop.RunLoop`) on the kinematic backend: the recorded inputs are the loop's input source
(state requests included, so the loop does no start-up of its own) and the comparison is its per-cycle observer.
"""

from shc_cli.replay.run import Replay, initial_joints, replay

__all__ = ["Replay", "initial_joints", "replay"]
