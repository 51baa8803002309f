"""admittance: force-sensorless admittance control of robot arms, from Python.

Thin bindings of the Rust crates (crates/python; docs/python.md): rigid-body dynamics of an
arm loaded from its URDF, the paper's neural controller and the baselines, the
external-torque observers, the admittance model with its reference saturation, and the
learned observer's network (train, grow, save, load), the whole 1 kHz loop
(`ClosedLoop`), and scenario runs (`run`). Arrays are float64 numpy arrays; any
array-like is accepted and checked for shape.
"""

from . import _admittance
from ._admittance import *  # noqa: F401,F403  (every name is the native module's; stubs: _admittance.pyi)
from ._admittance import __version__  # noqa: F401

#: The native module's public names (classes, functions, the exception), named once in
#: crates/python/src/lib.rs.
__all__ = sorted(name for name in vars(_admittance) if not name.startswith("_")) + ["__version__"]
