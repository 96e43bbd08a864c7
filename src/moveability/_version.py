"""The package's version: the one place it is written (pyproject.toml reads it
from here), so that no command pays for ``importlib.metadata`` to print it."""

__version__ = "0.1.0"
