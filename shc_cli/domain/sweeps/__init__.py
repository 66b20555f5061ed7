"""Sweeps: a grid of simulations run in parallel (``shc sweep``), and the run machinery ``shc optimize`` shares.

:mod:`~shc_cli.domain.sweeps.points` runs one point (a row, never an exception for a failed run),
:mod:`~shc_cli.domain.sweeps.pool` runs many (this process, worker processes or Dask),
:mod:`~shc_cli.domain.sweeps.checks` checks a sweep's or a study's robots and gaits before any run,
:mod:`~shc_cli.domain.sweeps.results` writes the tables, :mod:`~shc_cli.domain.sweeps.run` is ``shc sweep``.
"""
