"""shc's version, a leaf every layer may import (the package's ``__init__`` is the public facade above the API)."""

__version__ = "0.1.0"
