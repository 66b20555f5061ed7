"""The domain layer: what a run, a sweep or a study is, between the run loop and the public API.

Its functions take validated options (:class:`~shc_cli.domain.config.SimulationConfig`), return result objects
(a run directory and its summary) and never print (``logging`` only); :mod:`shc_cli.api` is a thin facade over it
and the commands print what it returns.
"""
