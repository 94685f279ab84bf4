"""Frictionless contact between elastic bodies with non-matching meshes (INTERNODES).

The Python face of the ``internodes`` solver: the same case keys, checks, solve and result files
as the command line ``internodes solve CASE``, with results as NumPy arrays.

    import internodes
    case = internodes.Case.from_toml("geo/hemisphere_on_block.toml")
    result = internodes.solve(case)
    result.raise_for_status()
    print(result.summary["contact"]["force_primary"])

Progress goes to the ``logging`` logger ``internodes`` (silent unless configured, e.g.
``logging.basicConfig(level=logging.INFO)``), at the command line's levels: ``INFO`` its default
log, ``DEBUG`` its ``-v``, ``internodes.TRACE`` its ``-vv``. See docs/python.md.
"""

import logging

from ._internodes import *  # noqa: F403 (the native module's classes and solve())
from ._internodes import __version__
from .export import to_meshio

# A library's logger stays silent until the application configures logging.
logging.getLogger(__name__).addHandler(logging.NullHandler())

#: The level of the coupled Krylov solves' lines, below ``logging.DEBUG``: the command line's
#: ``-vv`` (``logging.basicConfig(level=internodes.TRACE)`` prints them).
TRACE = 5
