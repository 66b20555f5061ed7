"""``shc fit``: the servo model's parameters identified from run logs (run-hw or simulate) by replaying their
recorded joint commands open-loop in a physics engine and matching what was measured.

:mod:`~shc_cli.domain.fit.params` names the parameters (the robot file's ``[servo]`` fields) and their bounds,
:mod:`~shc_cli.domain.fit.recording` reads a run's commands and measurements, :mod:`~shc_cli.domain.fit.rollout`
replays the commands in the engine, :mod:`~shc_cli.domain.fit.solve` is the bounded least squares with its
uncertainties, :mod:`~shc_cli.domain.fit.outputs` writes the override robot file, ``fit.json`` and the plots,
:mod:`~shc_cli.domain.fit.synthetic` turns a simulated run into what a servo bus would have logged (tests,
benchmarks) and :mod:`~shc_cli.domain.fit.run` is the whole fit (:func:`~shc_cli.domain.fit.run.fit`).
"""
