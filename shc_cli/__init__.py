"""shc: OpenSHC's multilegged gait controller in Python, and the tools around it."""

__version__ = "0.1.0"
