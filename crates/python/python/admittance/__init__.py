"""admittance: force-sensorless admittance control of robot arms, from Python.

Thin bindings of the Rust crates (crates/python; docs/python.md): rigid-body dynamics of an
arm loaded from its URDF, the paper's neural controller and the baselines, the
external-torque observers, the admittance model with its reference saturation, and the
learned observer's network (train, grow, save, load), and scenario runs (`run`). Arrays are float64 numpy arrays; any
array-like is accepted and checked for shape.
"""

from ._admittance import (
    Admittance,
    ComputedTorqueController,
    Controller,
    HybridObserver,
    Identification,
    InputConditioner,
    LearnedObserver,
    Model,
    MomentumObserver,
    Network,
    NeuralController,
    Observer,
    OracleObserver,
    PdController,
    RunFailed,
    __version__,
    aba,
    coriolis,
    crba,
    excitation,
    gravity,
    identify,
    import_bag,
    load_identification,
    load_network,
    rnea,
    run,
    tip_jacobian,
    tip_pose,
    train,
)

__all__ = [
    "Admittance",
    "ComputedTorqueController",
    "Controller",
    "HybridObserver",
    "Identification",
    "InputConditioner",
    "LearnedObserver",
    "Model",
    "MomentumObserver",
    "Network",
    "NeuralController",
    "Observer",
    "OracleObserver",
    "PdController",
    "RunFailed",
    "__version__",
    "aba",
    "coriolis",
    "crba",
    "excitation",
    "gravity",
    "identify",
    "import_bag",
    "load_identification",
    "load_network",
    "rnea",
    "run",
    "tip_jacobian",
    "tip_pose",
    "train",
]
