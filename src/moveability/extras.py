"""The optional dependency groups, and the one-line error when one is missing.

The core (the analysis, ``regions``, ``locate``, ``feasible``, ``plan``,
``export``) needs numpy, scipy, numba and click. The rest comes in extras::

    pip install "moveability[plot]"     # figures, report, sweep maps: matplotlib
    pip install "moveability[sweep]"    # parallel sweeps, Dask, Parquet tables
    pip install "moveability[custom]"   # user-defined mechanisms: sympy
    pip install "moveability[all]"      # all of them

A feature calls :func:`require` before it starts, so that a missing extra is
refused at once (:class:`~moveability.errors.MissingExtraError`, one line
naming the extra), not after a long computation.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from .errors import MissingExtraError

__all__ = ["EXTRAS", "require"]

#: the modules of each extra
EXTRAS: dict[str, tuple[str, ...]] = {
    "plot": ("matplotlib",),
    "sweep": ("joblib", "dask", "distributed", "pyarrow"),
    "custom": ("sympy",),
}


def require(module: str, extra: str, feature: str) -> ModuleType:
    """Import ``module`` of the extra ``extra``, or say in one line how to install it.

    Parameters
    ----------
    module : str
        The module to import.
    extra : str
        The extra that installs it (a key of :data:`EXTRAS`).
    feature : str
        What needs it, in words, for the message.

    Returns
    -------
    module
        The imported module.

    Raises
    ------
    MissingExtraError
        When the module is not installed.

    Examples
    --------
    >>> require("numpy", "core", "arrays").__name__
    'numpy'
    >>> require("no_such_module_here", "plot", "figures")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
        ...
    moveability.errors.MissingExtraError: no_such_module_here is not installed (figures): ...
    """
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as error:
        missing = error.name or module
        if missing.split(".")[0] != module.split(".")[0]:
            raise  # the module is there but broken: not a missing extra
        raise MissingExtraError(extra, feature, module) from None
