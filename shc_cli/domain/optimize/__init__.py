"""``shc optimize``: a multi-objective search (Optuna) over simulated runs, resumable from its SQLite storage.

:mod:`~shc_cli.domain.optimize.checks` checks a study before any run, :mod:`~shc_cli.domain.optimize.evaluate`
turns a trial's runs into its objectives and constraints, :mod:`~shc_cli.domain.optimize.storage` opens Optuna's
storage and sampler, :mod:`~shc_cli.domain.optimize.outputs` writes the tables, Pareto robot files and
:mod:`~shc_cli.domain.optimize.plots`, and :mod:`~shc_cli.domain.optimize.loop` is the ask/tell loop.
"""
