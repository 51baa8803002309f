"""Type stubs of the native module ``admittance._admittance`` (re-exported by ``admittance``).

Conventions: SI units; joint vectors are float64 arrays of shape ``(n,)`` in the chain order
of the model (``Model.joint_names``); any array-like is accepted and converted, and an
argument of the wrong shape is a ``ValueError`` naming it and the expected shape. Functions
return new arrays unless ``out=`` names a writeable float64 array of the result's shape, which
is then written and returned.
"""

import pathlib
from os import PathLike
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike

#: The signal chain's low-pass cut-off (Hz) every front end defaults to (crates/loop).
DEFAULT_SIGNAL_CUTOFF_HZ: float
#: The Coulomb widths (rad/s) ``identify`` chooses among when none is given; 0.01 first.
COULOMB_WIDTH_CANDIDATES: list[float]
#: How far beyond a joint's training range (a share of its span) a position counts as
#: outside it (``Identification.range_excursions``, the loop's ``outside_training_range``).
TRAINING_RANGE_MARGIN: float
#: How far beyond a joint's highest training speed (a share of it) a speed counts as faster
#: than trained (``Identification.speed_excursions``, the loop's ``faster_than_training``).
TRAINING_SPEED_MARGIN: float
#: The zero-phase low-pass (Hz) on the acceleration ``identify`` regresses the inertial
#: torque on when none is given (at least twice the input conditioning's cut-off).
FIT_ACCELERATION_HZ: float
Vector = npt.Vector
Matrix = npt.Vector
StrPath = Union[str, "PathLike[str]"]
Config = Mapping[str, Any]
#: Free-motion data: a CSV path, or a dict with ``t`` ``(N,)`` and ``q``, ``qdot``, ``qddot``,
#: ``tau`` as ``(N, n)`` arrays (or the CSV column names ``q.JOINT`` ... as ``(N,)`` arrays).
FreeMotionData = Union[StrPath, Mapping[str, ArrayLike]]

__version__: str
#: Gaussian nodes of an observer's network unless told otherwise (the paper's 1000).
DEFAULT_NODES: int

class Model:
    """A serial arm loaded from a URDF: the chain from a base link to a tip link.

    Immutable; build it once and pass it to the dynamics functions, controllers and observers.
    """

    @staticmethod
    def from_urdf(
        path: StrPath,
        base: Optional[str] = None,
        tip: Optional[str] = None,
        *,
        strict: bool = False,
        lock: Optional[Mapping[str, float]] = None,
        drop: Optional[Sequence[str]] = None,
    ) -> "Model":
        """Loads the chain between ``base`` (default: the root link) and ``tip`` (default: the
        arm's hand, past gripper fingers). Branches off the chain are held at 0 (or ``lock``)
        with their mass, or left out (``drop``); impossible inertias load with a warning
        (``warnings``) unless ``strict``. A bad file is a ``ValueError`` naming the file, line
        and element; a missing one an ``OSError``."""
    @property
    def warnings(self) -> list[str]:
        """What the loader accepted with a warning (``file:line: element: problem``)."""
    @staticmethod
    def from_urdf_string(
        text: str, base: Optional[str] = None, tip: Optional[str] = None, source: str = "<string>"
    ) -> "Model":
        """Loads the chain from URDF text (``source`` names it in error messages)."""
    @property
    def n(self) -> int:
        """Number of moving joints."""
    @property
    def joint_names(self) -> list[str]:
        """Names of the moving joints, in chain order."""
    @property
    def lower(self) -> Vector:
        """Lower position limits ``(n,)`` (``-inf`` where the URDF gives none)."""
    @property
    def upper(self) -> Vector:
        """Upper position limits ``(n,)`` (``inf`` where the URDF gives none)."""
    @property
    def velocity_limit(self) -> Vector:
        """Velocity limits ``(n,)`` (``inf`` where the URDF gives none)."""
    @property
    def effort_limit(self) -> Vector:
        """Effort limits ``(n,)`` (``inf`` where the URDF gives none)."""
    @property
    def gravity(self) -> Vector:
        """Gravity in the base frame ``(3,)``, m/s^2."""
    @property
    def base_link(self) -> str:
        """The base link's name."""
    @property
    def tip_link(self) -> str:
        """The tip frame's name."""
    @property
    def total_moving_mass(self) -> float:
        """Total mass of the moving bodies, kg."""
    def with_gravity(self, g: ArrayLike) -> "Model":
        """A copy with gravity ``g`` ``(3,)`` in the base frame."""
    def with_scaled_inertias(self, scale: float) -> "Model":
        """A copy with every body's mass and inertia multiplied by ``scale`` (> 0)."""

def rnea(m: Model, q: ArrayLike, v: ArrayLike, a: ArrayLike, *, out: Optional[Vector] = None) -> Vector:
    """Inverse dynamics ``tau = M(q) a + C(q, v) v + G(q)``, ``(n,)``."""

def crba(m: Model, q: ArrayLike, *, out: Optional[Matrix] = None) -> Matrix:
    """Joint-space inertia matrix ``M(q)``, ``(n, n)``."""

def gravity(m: Model, q: ArrayLike, *, out: Optional[Vector] = None) -> Vector:
    """Gravity torque ``G(q)``, ``(n,)``."""

def coriolis(m: Model, q: ArrayLike, v: ArrayLike, *, out: Optional[Matrix] = None) -> Matrix:
    """Coriolis matrix ``C(q, v)`` with ``dM/dt = C + C^T``, ``(n, n)``."""

def tip_pose(m: Model, q: ArrayLike) -> Tuple[Vector, Matrix]:
    """Pose of the tip frame in the base frame: ``(position (3,), rotation (3, 3))``."""

def tip_jacobian(m: Model, q: ArrayLike, *, out: Optional[Matrix] = None) -> Matrix:
    """Geometric Jacobian of the tip, ``(6, n)``: linear rows first, base axes, at the tip's
    origin."""

def aba(m: Model, q: ArrayLike, v: ArrayLike, tau: ArrayLike, *, out: Optional[Vector] = None) -> Vector:
    """Forward dynamics ``qddot = M(q)^-1 (tau - C(q, v) v - G(q))``, ``(n,)``."""

class Controller:
    """A joint-torque controller (base of the three controllers; not constructed directly).

    ``step`` never raises on bad numbers: on a non-finite or stale measurement, a non-finite
    reference or estimate, or an invalid ``dt`` it returns the safe hold (nominal gravity at the
    last valid position minus damping, within the effort limits), freezes adaptation and
    records the fault in ``fault`` / ``fault_count``.
    """

    def step(
        self,
        t: float,
        q: ArrayLike,
        qdot: ArrayLike,
        q_ref: ArrayLike,
        qdot_ref: ArrayLike,
        qddot_ref: ArrayLike,
        tau_ext_hat: ArrayLike,
        dt: float,
        *,
        out: Optional[Vector] = None,
    ) -> Vector:
        """One control step of length ``dt``: the commanded torque ``(n,)``, finite and within
        the effort limits."""
    def reset(self) -> None:
        """Back to the state just after construction (learned weights included)."""
    @property
    def name(self) -> str:
        """``"nn"``, ``"pd"``, ``"pd_gravity"`` or ``"computed_torque"``."""
    @property
    def n(self) -> int:
        """Number of joints."""
    @property
    def fault(self) -> Optional[str]:
        """What the last ``step`` faulted on (and held safely instead), or ``None``."""
    @property
    def fault_count(self) -> int:
        """Steps that faulted since construction or ``reset``."""

class NeuralController(Controller):
    """The paper's adaptive RBF neural controller with deadzone compensation on the nominal
    model ``m``. ``config``: the keys of a scenario's ``[controller.neural]`` table (``k1``,
    ``k2``, ``f``, ``deadzone_compensation``, ``deadzone_network``, ``deadzone_inverse``,
    ``adaptation``, ``track_relevance``, ``safe_hold``); ``None``: the paper's experiment A."""

    def __init__(self, m: Model, config: Optional[Config] = None) -> None: ...

class PdController(Controller):
    """Joint PD (plus the nominal gravity with ``gravity_compensation``). ``config``: the keys of
    ``[controller.pd]``: ``kp``, ``kd`` (a number or one per joint), ``gravity_compensation``,
    ``safe_hold``."""

    def __init__(self, m: Model, config: Config) -> None: ...

class ComputedTorqueController(Controller):
    """Computed torque with the nominal model ``m``. ``config``: the keys of
    ``[controller.computed_torque]``: ``kp``, ``kd``, ``safe_hold``."""

    def __init__(self, m: Model, config: Config) -> None: ...

class Observer:
    """An external-torque observer (base of the observers; not constructed directly). The
    estimate is the torque the environment applies to the robot.

    ``update`` never raises on bad numbers: on a non-finite input (or one beyond +-1e12, the
    bound of free-motion data) or an invalid ``dt`` it returns zeros and records the fault in
    ``fault`` / ``fault_count``.
    """

    def update(
        self,
        t: float,
        q: ArrayLike,
        qdot: ArrayLike,
        qddot: ArrayLike,
        tau: ArrayLike,
        dt: float,
        *,
        out: Optional[Vector] = None,
    ) -> Vector:
        """One update with the sample at ``t`` of a period ``dt``: the estimate ``(n,)``.
        ``tau`` is the commanded torque (for a learned network: the torque signal of its
        training data)."""
    def reset(self) -> None:
        """Back to the state just after construction."""
    @property
    def name(self) -> str:
        """``"momentum"``, ``"learned"``, ``"hybrid"`` or ``"oracle"``."""
    @property
    def n(self) -> int:
        """Number of joints."""
    @property
    def fault(self) -> Optional[str]:
        """What the last ``update`` faulted on (its estimate was zero), or ``None``."""
    @property
    def fault_count(self) -> int:
        """Updates that faulted since construction or ``reset``."""

class MomentumObserver(Observer):
    """The generalised-momentum observer on the nominal model ``m``: a first-order lag of the
    external torque (less unmodelled friction) with time constant ``1 / gain`` (default 50
    1/s). ``gain``: a number or one per joint; or ``config``: the keys of
    ``[observer.momentum]``."""

    def __init__(
        self,
        m: Union[Model, "Identification"],
        gain: Optional[Union[float, ArrayLike]] = None,
        config: Optional[Config] = None,
    ) -> None: ...

class LearnedObserver(Observer):
    """The paper's learned observer ``LP(f_hat(q, qdot, qddot) - tau)`` with a network from
    ``train`` or ``load_network`` and a first-order low-pass at ``cutoff_hz`` (0: none)."""

    def __init__(self, network: "Network", cutoff_hz: float = 0.0) -> None: ...

class HybridObserver(Observer):
    """The momentum observer on the nominal model ``m`` with the torque corrected by a
    network trained on what ``m`` misses (``train(..., nominal=m)``)."""

    def __init__(
        self,
        m: Union[Model, "Identification"],
        network: "Network",
        gain: Optional[Union[float, ArrayLike]] = None,
        config: Optional[Config] = None,
    ) -> None: ...

class OracleObserver(Observer):
    """Returns the true external torque given by ``set_true_value`` (simulation only)."""

    def __init__(self, n: int) -> None: ...
    def set_true_value(self, tau_ext: ArrayLike) -> None:
        """Sets the value ``(n,)`` the next ``update`` returns."""

class InputConditioner:
    """The observers' second input filter: a 2nd-order Butterworth low-pass at ``cutoff_hz`` on
    angles and torques sampled at ``rate_hz``, the filtered angles differentiated twice (the
    ``input_filter_hz`` of ``train`` and of the scenario files)."""

    def __init__(self, n: int, cutoff_hz: float, rate_hz: float) -> None: ...
    def update(self, q: ArrayLike, tau: ArrayLike) -> Tuple[Vector, Vector, Vector, Vector]:
        """One sample; returns the conditioned ``(q, qdot, qddot, tau)``."""
    @property
    def n(self) -> int:
        """Number of joints."""

class EstimateLowPass:
    """The estimate's first-order low-pass of the loop (``observer.cutoff_hz``): ``y += alpha
    (x - y)`` per joint from rest, ``alpha = dt / (dt + 1 / (2 pi cutoff_hz))`` at
    ``rate_hz``; 0 passes the estimate through."""

    def __init__(self, n: int, cutoff_hz: float, rate_hz: float) -> None: ...
    def update(self, raw: ArrayLike) -> Vector:
        """One sample of the raw estimate ``(n,)``; returns the filtered estimate."""
    def filter(self, raw: ArrayLike) -> Matrix:
        """The rows of ``raw`` ``(N, n)`` in order, continuing from the filter's state;
        returns the filtered ``(N, n)``."""
    def reset(self) -> None:
        """Back to rest (zero)."""
    @property
    def n(self) -> int:
        """Number of joints."""

class Admittance:
    """The admittance model ``M_d (q_a'' - q_d'') + C_d (q_a' - q_d') + G_d (q_a - q_d) =
    tau_ext_hat`` with the smooth saturation of the reference.

    ``damping``, ``stiffness``, ``mass`` (optional): a number or one per joint. ``rho``: the
    saturation's linear fraction (``None``: no saturation). ``bound``: ``None`` takes the range
    from the joint limits of ``m`` (joints without finite limits unsaturated); a number or one
    per joint is the half-range about 0 (``inf``: unsaturated). ``step`` never raises on bad
    numbers: it holds the last reference and records the fault.
    """

    def __init__(
        self,
        m: Model,
        damping: Union[float, ArrayLike],
        stiffness: Union[float, ArrayLike],
        mass: Optional[Union[float, ArrayLike]] = None,
        rho: Optional[float] = 0.95,
        bound: Optional[Union[float, ArrayLike]] = None,
        deadband: Optional[Union[float, ArrayLike]] = None,
    ) -> None: ...
    @staticmethod
    def from_config(m: Model, config: Config) -> "Admittance":
        """From the keys of a scenario's ``[admittance]`` table (``damping``, ``stiffness``,
        ``inertia``, ``saturation = {rho, centre, half_range}``)."""
    def step(
        self,
        q_d: ArrayLike,
        qdot_d: ArrayLike,
        qddot_d: ArrayLike,
        tau_ext_hat: ArrayLike,
        dt: float,
        *,
        out: Optional[Tuple[Vector, Vector, Vector]] = None,
    ) -> Tuple[Vector, Vector, Vector]:
        """Advances by ``dt``; returns the compliant reference ``(q_r, qdot_r, qddot_r)``."""
    def reset(self) -> None:
        """Back to zero deviation."""
    @property
    def q_a(self) -> Vector:
        """The unsaturated admittance state after the last step."""
    @property
    def deviation(self) -> Vector:
        """``q_a - q_d`` after the last step."""
    @property
    def n(self) -> int:
        """Number of joints."""
    @property
    def fault(self) -> Optional[str]:
        """What the last ``step`` faulted on, or ``None``."""
    @property
    def fault_count(self) -> int:
        """Steps that faulted since construction or ``reset``."""

class RobotLoop:
    """The robot's loop of a deployment folder (``admittance deploy``): the loop the C ABI's
    ``adm_create`` builds. Raw measured angles and torques in, through the plausibility gates
    and the signal chain; command, estimate, reference and a status out. Never trains."""
    @staticmethod
    def load(path: str, overrides: Optional[List[str]] = None, *, wrench: bool = False) -> "RobotLoop": ...
    def step(self, t: float, q: ArrayLike, tau: Optional[ArrayLike] = None, *, qdot: Optional[ArrayLike] = None,
             q_d: Optional[ArrayLike] = None, qdot_d: Optional[ArrayLike] = None,
             qddot_d: Optional[ArrayLike] = None) -> Tuple[Vector, Vector]: ...
    @property
    def status(self) -> Optional[Dict[str, Any]]: ...
    @property
    def implausible_samples(self) -> int: ...
    @property
    def n(self) -> int: ...
    @property
    def joints(self) -> List[str]: ...
    @property
    def dt(self) -> float: ...
    @property
    def reference(self) -> Tuple[Vector, Vector, Vector]: ...
    @property
    def wrench(self) -> Optional[Tuple[Vector, Vector]]: ...
    @property
    def contact_wrench(self) -> Optional[Tuple[Vector, Vector]]: ...

class ClosedLoop:
    """One control period of the Rust loop (``admittance_loop::ClosedLoop``): the encoder
    angles through the sensors' low-pass and differentiation (``sensor_cutoff_hz``, default ``DEFAULT_SIGNAL_CUTOFF_HZ``; 0: none),
    the observer stage (input conditioning, estimate low-pass, warm-up), the admittance model
    and the controller, exactly as a scenario's variant runs them.

    ``config``: a dict with the keys of a scenario's loop tables (``control_rate_hz``,
    ``controller``, ``admittance`` or ``task_admittance``, ``observer``); ``network``: the
    trained network of a ``learned`` or ``hybrid`` observer. A bad key or value is a
    ``ValueError`` naming its dotted key. ``step`` never raises on bad numbers.
    """

    def __init__(
        self,
        m: Model,
        config: Config,
        network: Optional["Network"] = None,
        *,
        sensor_cutoff_hz: float = 20.0,
    ) -> None: ...
    def step(
        self,
        t: float,
        q: ArrayLike,
        tau: Optional[ArrayLike],
        q_d: ArrayLike,
        qdot_d: ArrayLike,
        qddot_d: ArrayLike,
        tau_ext: Optional[ArrayLike] = None,
        *,
        out: Optional[Tuple[Vector, Vector]] = None,
    ) -> Tuple[Vector, Vector]:
        """One period at ``t``: ``q`` the encoder angles, ``tau`` the torque applied over the
        period that ended (``None``: the loop's last command), the desired trajectory, and
        ``tau_ext`` the true external torque (read by an ``oracle`` observer only). Returns
        ``(torque, estimate)``: the command and the external-torque estimate."""
    @property
    def n(self) -> int:
        """Number of joints."""
    @property
    def dt(self) -> float:
        """The control period (s)."""
    @property
    def torque(self) -> Vector:
        """The command of the last step."""
    @property
    def estimate(self) -> Vector:
        """The external-torque estimate of the last step."""
    @property
    def q_r(self) -> Vector:
        """The compliant reference of the last step."""
    @property
    def qdot_r(self) -> Vector:
        """``q_r'`` of the last step."""
    @property
    def qddot_r(self) -> Vector:
        """``q_r''`` of the last step."""
    @property
    def measurement(self) -> Dict[str, Vector]:
        """The last measurement: ``q``, ``q_filtered``, ``qdot``, ``qddot``, ``tau_filtered``."""
    @property
    def fault(self) -> Optional[str]:
        """What the controller's last step faulted on (it held safely), or ``None``."""
    @property
    def fault_count(self) -> int:
        """Controller steps that faulted."""
    @property
    def observer_fault_count(self) -> int:
        """Observer updates that faulted."""

class VariantRecorder:
    """The metrics, health checks (divergence) and time series of one variant whose plant runs
    outside Rust (the MuJoCo co-simulation), gathered by the scenario runner's code: ``add``
    after each ``ClosedLoop.step`` and plant step, ``finish`` at the end, then
    ``write_run_folder``. Metrics over ``[evaluation_start, duration]``; a row of
    ``VARIANT.csv`` every ``decimation`` steps."""

    def __init__(
        self,
        name: str,
        m: Model,
        config: Config,
        duration: float,
        evaluation_start: float,
        decimation: int = 10,
        contact_floor: Optional["ContactFloor"] = None,
    ) -> None: ...
    def add(
        self,
        closed_loop: ClosedLoop,
        q: ArrayLike,
        qdot: ArrayLike,
        tau_ext: ArrayLike,
        applied: Optional[ArrayLike] = None,
    ) -> Optional[str]:
        """Gathers the loop's last step and the plant's state after it (true ``q``, ``qdot``,
        external torque, applied torque; ``None``: the command). Returns why the variant
        diverged (stop then), or ``None``."""
    def finish(self, closed_loop: ClosedLoop, network: Optional["Network"] = None) -> None:
        """Ends the variant; ``network``: its observer's, for the training metrics."""
    @property
    def name(self) -> str:
        """The variant's name."""
    @property
    def steps(self) -> int:
        """Control steps gathered."""
    @property
    def divergence(self) -> Optional[Tuple[float, str]]:
        """``(time, reason)`` of a divergence, or ``None``."""
    @property
    def metrics(self) -> Optional[dict]:
        """The variant's ``summary.json`` metrics after ``finish``."""

class CosimStepper:
    """The MuJoCo co-simulation's control steps in Rust (``admittance.mujoco``): the encoder
    read, the ``ClosedLoop`` step, the command and push into MuJoCo, ``mj_step``, the push's
    ``J^T f`` and the ``VariantRecorder``'s gathering, as its stepwise Python loop does them.
    ``plant``: ``MujocoArm.stepper_plant()`` (an arm without contacts); per step: the desired
    motion, the encoder noise (times its standard deviation) ``(steps, n)``, the push
    ``(steps, 3)`` and ``push_on`` ``(steps,)``."""

    def __init__(
        self,
        closed_loop: ClosedLoop,
        recorder: VariantRecorder,
        plant: dict,
        *,
        dt: float,
        q_d: np.ndarray,
        qdot_d: np.ndarray,
        qddot_d: np.ndarray,
        noise: np.ndarray,
        resolution: float,
        push: np.ndarray,
        push_on: List[bool],
    ) -> None: ...
    def run(self, start: int, end: int) -> Optional[str]:
        """Runs the control steps ``start..end``; returns why the variant diverged (stop
        then), or ``None``."""
    @property
    def steps(self) -> int:
        """Control steps in the plan."""

class FreeMotionStepper:
    """The co-simulation's free-motion recording in Rust (``admittance.mujoco``): the encoder
    read, the sensors' conditioning, the PD on the desired motion, the command into MuJoCo and
    ``mj_step``, as its stepwise Python loop does them; the conditioned ``q``, ``qdot``,
    ``qddot``, ``tau`` of each step written into the rows of ``out`` (float64 ``(steps, n)``)."""

    def __init__(
        self,
        m: Model,
        pd_config: Config,
        plant: dict,
        *,
        dt: float,
        sensor_cutoff_hz: float,
        rate_hz: float,
        resolution: float,
        out: Dict[str, np.ndarray],
    ) -> None: ...
    def run(
        self, start: int, q_d: np.ndarray, qdot_d: np.ndarray, qddot_d: np.ndarray, noise: np.ndarray
    ) -> None:
        """Records the steps from ``start`` on, one per row of the desired motion and the
        encoder noise (times its standard deviation) ``(count, n)``."""
    @property
    def steps(self) -> int:
        """Control steps of ``out``."""

def write_run_folder(
    out: StrPath,
    scenario: Config,
    recorders: List[VariantRecorder],
    extra: Optional[Config] = None,
    *,
    force: bool = False,
    protect: Optional[StrPath] = None,
    header: Optional[str] = None,
) -> Tuple[dict, List[str]]:
    """Writes the run folder of finished recorders as ``admittance run`` does (atomic; a
    ``VARIANT.csv`` each, ``summary.json`` with the keys of ``extra``, ``scenario.toml`` from
    the dict ``scenario``, which must load as a scenario with a ``[variants.NAME]`` per
    recorder; ``header`` as its first comment lines). Returns ``(summary, failures)``. Raises
    ``FileExistsError`` when ``out`` may not be replaced (without ``force``)."""

def check_out_dir(out: StrPath, *, force: bool = False, protect: Optional[StrPath] = None) -> None:
    """``admittance run``'s rule for ``--out``: raises ``FileExistsError`` unless ``out`` is
    new, empty or a run folder this tool wrote (or ``force``), and it holds neither the
    current folder nor ``protect``."""

class Network:
    """A trained flat RBF network of the learned or hybrid observer (inputs ``[q, qdot,
    qddot]``, one output per joint)."""

    def grow(
        self,
        nodes: int,
        data: FreeMotionData,
        *,
        validation: Optional[FreeMotionData] = None,
        validation_fraction: Optional[float] = None,
        input_filter_hz: Optional[float] = None,
        nominal: Optional[Model] = None,
        seed: int = 1,
    ) -> None:
        """Adds ``nodes`` nodes without retraining; ``data`` must be the training data. Options
        default to how the network was trained. Releases the GIL."""
    def predict(
        self, q: ArrayLike, qdot: ArrayLike, qddot: ArrayLike, *, out: Optional[npt.Vector] = None
    ) -> npt.Vector:
        """The output for ``(n,)`` inputs (returns ``(n,)``) or ``(N, n)`` inputs (returns
        ``(N, n)``)."""
    def save(self, path: StrPath) -> None:
        """Writes the network (versioned, checksummed, atomically)."""
    @property
    def nodes(self) -> int:
        """Gaussian enhancement nodes."""
    @property
    def n_inputs(self) -> int:
        """Inputs per sample (3n)."""
    @property
    def n_outputs(self) -> int:
        """Outputs per sample (n)."""
    @property
    def friction_features(self) -> bool:
        """Whether the network has ``tanh(qdot / v)`` inputs."""
    @property
    def ridge_lambda(self) -> float:
        """The chosen ridge parameter."""
    @property
    def validation_nrmse(self) -> Optional[Vector]:
        """Per-joint validation NRMSE (cross-validated by default) after training or the last
        ``grow``; ``None`` when loaded or after a growth under cross-validation."""
    @property
    def samples(self) -> Optional[int]:
        """Training rows behind the network."""
    @property
    def validation_samples(self) -> Optional[int]:
        """Validation rows (``None`` when loaded, 0 under cross-validation)."""
    @property
    def seconds(self) -> Optional[float]:
        """Wall time of the fit or of the last ``grow`` (``None`` when loaded)."""
    @property
    def can_grow(self) -> bool:
        """Whether the network holds the Gram matrix that ``grow`` needs."""

def train(
    data: FreeMotionData,
    m: Model,
    nodes: int = DEFAULT_NODES,
    *,
    friction_features: bool = False,
    friction_scales: Optional[Sequence[float]] = None,
    input_filter_hz: Optional[float] = None,
    validation_fraction: Optional[float] = None,
    validation: Optional[FreeMotionData] = None,
    folds: int = 5,
    seed: Optional[int] = None,
    width_scale: float = 2.0,
    width_neighbours: int = 8,
    nominal: Optional[Union[Model, "Identification"]] = None,
) -> Network:
    """Fits the learned observer's network to free-motion data (``admittance train``): a
    separate ``validation`` set, else blocked cross-validation over ``folds`` contiguous
    stretches of the rows (each scored by a fit on the others), chooses the ridge parameter
    and gives ``validation_nrmse``; every row of ``data`` trains. ``validation_fraction``:
    hold out the last rows instead (the tail of the same motion; compatibility only). ``nominal``: learn the hybrid observer's
    residual ``tau - RNEA_nominal`` instead of ``tau``; without ``validation`` (a recording of other
    motion) every output is zero and a warning says why. ``input_filter_hz``: default the nominal
    identification's conditioning (another value is an error), else 0. Releases the GIL."""

def load_network(path: StrPath) -> Network:
    """Loads a network written by ``Network.save`` or ``admittance train``."""

class Identification:
    """An identified arm (``identify``, ``load_identification``): the rigid-body ``model``
    with identified inertias (kept physically possible) and per-joint rotor inertia,
    friction, offset and springs. Every consumer of a nominal model takes it."""

    @property
    def model(self) -> Model:
        """The identified rigid-body model (the URDF's kinematics)."""
    @property
    def joint_terms(self) -> List[dict]:
        """Per joint: armature, viscous, coulomb (two levels), coulomb_width, offset, spring,
        spring_range (the positions the springs were fitted over, linear beyond; or None)."""
    @property
    def summary(self) -> dict:
        """Chosen settings and the expected false torque per joint (N m rms) on motion it was
        not trained on."""
    def predict(self, q: ArrayLike, qdot: ArrayLike, qddot: ArrayLike) -> FloatArray:
        """The torque the identified arm needs: ``(n,)`` or ``(N, n)`` rows. Rows are
        consecutive samples of one motion at the identification's rate: the share of
        ``qddot`` taken rises above ``summary["acceleration_gain"]`` where the motion
        accelerates well beyond the training motion's noise; one state takes the gain."""
    def range_excursions(self, q: ArrayLike) -> List[dict]:
        """Per joint, how the positions ``q`` (``(n,)`` or ``(N, n)``, conditioned as the
        identification was) leave ``summary["training_range"]``: ``samples_outside``,
        ``furthest`` (rad or m beyond), ``lowest``, ``highest``; empty without a range."""
    def speed_excursions(self, qdot: ArrayLike) -> List[dict]:
        """Per joint, how the velocities ``qdot`` (``(n,)`` or ``(N, n)``, conditioned as the
        identification was) exceed ``summary["training_speed"]`` by more than half of it:
        ``samples_faster``, ``fastest`` (rad/s or m/s); empty without recorded speeds."""
    def save(self, path: StrPath, data: Optional[str] = None) -> None:
        """Writes the identification file (JSON, versioned, checksummed, atomic)."""
    def with_payload(self, payload: "Payload") -> "Identification":
        """This identification carrying ``payload`` rigidly at the tip frame (its inertia
        added to the last body); ``save`` records the payload in the file's ``data``."""

class Payload:
    """A rigid payload at the tip frame: ``mass`` (kg), ``com`` (m, tip frame), ``inertia``
    (3 x 3, kg m^2, about the centre of mass, tip axes)."""

    def __init__(self, mass: float, com: ArrayLike, inertia: Optional[ArrayLike] = None) -> None: ...
    @property
    def mass(self) -> float:
        """Mass (kg)."""
    @property
    def com(self) -> Vector:
        """Centre of mass in the tip frame (m), ``(3,)``."""
    @property
    def inertia(self) -> Matrix:
        """Rotational inertia about the centre of mass, tip axes (kg m^2), ``(3, 3)``."""

def identify_payload(
    data: FreeMotionData, ident: Identification, input_filter_hz: Optional[float] = None, from_s: float = 0.0
) -> Payload:
    """The payload at the tip from free motion with it attached (20 s is enough), fitted on
    top of ``ident`` with its input conditioning; physically consistent. Releases the GIL."""

def identify(
    data: FreeMotionData,
    m: Model,
    friction: bool = True,
    validation: Optional[FreeMotionData] = None,
    input_filter_hz: Optional[float] = None,
    springs: bool = True,
    max_mass_ratio: Optional[float] = 2.0,
    coulomb_width: Optional[float] = None,
    fit_acceleration_hz: Optional[float] = 10.0,
) -> Identification:
    """Identifies the arm from free motion (``admittance identify``): settings chosen on
    ``validation`` or by blocked cross-validation over contiguous stretches; each body's mass
    at most ``max_mass_ratio`` times the URDF's (``None``: no bound); ``coulomb_width``: the
    friction's narrower smooth sign ``tanh(qdot / w)`` (rad/s; ``None``: chosen on held-out
    motion among ``COULOMB_WIDTH_CANDIDATES``); ``fit_acceleration_hz``: the zero-phase
    low-pass on the acceleration the fit regresses on (``None``: as measured, for exact
    accelerations). Releases the GIL."""

def excitation(
    m: Model,
    duration: float,
    seed: int = 1,
    harmonics: int = 5,
    period: Optional[float] = None,
    rate_hz: float = 200.0,
    pose: Optional[Sequence[float]] = None,
    range: Union[float, Sequence[float], None] = None,
    velocity_fraction: Optional[float] = None,
    acceleration_fraction: Optional[float] = None,
    acceleration_limit: Optional[float] = None,
) -> Dict[str, Any]:
    """A motion for identification (``admittance excite``): dict of ``t`` ``(N,)``, ``q``,
    ``qdot``, ``qddot`` ``(N, n)`` inside an envelope (default: +-0.5 rad around the middle
    of the limits, 30 % of the velocity limits, 30 % of 3 rad/s^2; ``range=float("inf")``,
    fractions 1: the URDF's whole limits), and ``condition_number``."""

def import_bag(
    path: StrPath,
    profile: str,
    rate: Optional[float] = None,
    accept_damaged: bool = False,
    accept_low_rate: bool = False,
) -> Dict[str, Any]:
    """A rosbag2 MCAP recording (``admittance import``) as the free-motion dict ``t``, ``q``,
    ``qdot``, ``qddot``, ``tau`` (and the vendor's ``label`` when recorded), with ``report``."""

def load_identification(path: StrPath, m: Optional[Model] = None) -> Identification:
    """Reads an identification file with the URDF it names (or applied to ``m``)."""


class ContactFloor:
    """Per-joint contact and collision thresholds (N m at standstill) for a stated false-alarm
    rate (``calibrate_contact``, ``load_contact_floor``)."""

    @property
    def contact_thresholds(self) -> Vector:
        """Contact level per joint at standstill (N m), ``(n,)``."""
    @property
    def collision_thresholds(self) -> Vector:
        """Collision level per joint at standstill (N m), ``(n,)``."""
    @property
    def moving_drop(self) -> Vector:
        """The fraction the levels drop by once the joint moves, ``(n,)``."""
    def contact_levels(self, qdot: ArrayLike, qddot: ArrayLike) -> npt.NDArray[np.float64]:
        """The detector's contact levels (N m) at this motion, ``(n,)`` or ``(N, n)``."""
    @property
    def speed_gain(self) -> Vector:
        """Relative growth of the levels per rad/s, ``(n,)``."""
    @property
    def acceleration_gain(self) -> Vector:
        """Relative growth of the levels per rad/s^2, ``(n,)``."""
    @property
    def smallest_detected(self) -> Vector:
        """The smallest steady torque detected at rest with 95 % probability per sample (N m)."""
    @property
    def false_alarms_per_hour(self) -> float:
        """The promised false contact events per hour, all joints together."""
    def to_json(self) -> str:
        """The floor's whole content as JSON text."""
    def describe(self) -> str:
        """The floor as a table with its guarantee and assumption."""
    def save(self, path: StrPath) -> None:
        """Writes the versioned, checksummed file atomically."""

class ContactDetector:
    """The momentum observer on ``ident`` (conditioned as the identification chose) followed
    by the contact detector of ``floor``."""

    def __init__(self, ident: Identification, floor: ContactFloor, gain: Optional[float] = None) -> None: ...
    def update(
        self,
        t: float,
        q: ArrayLike,
        qdot: ArrayLike,
        qddot: ArrayLike,
        tau: ArrayLike,
        dt: float,
        *,
        out: Optional[Vector] = None,
    ) -> Vector:
        """One period: the estimate ``(n,)``; sets ``contact``, ``collision``, ``link``."""
    def detect(self, estimate: ArrayLike, qdot: ArrayLike, qddot: ArrayLike) -> Tuple[bool, bool, int]:
        """The detector alone on an estimate made elsewhere: ``(contact, collision, link)``."""
    def reset(self) -> None:
        """Back to the state just after construction."""
    @property
    def contact(self) -> bool:
        """Some joint's estimate is above its contact level (with hysteresis)."""
    @property
    def collision(self) -> bool:
        """Some joint's estimate is above its collision level (with hysteresis)."""
    @property
    def link(self) -> int:
        """The last joint whose estimate is significant, -1 when none."""

def calibrate_contact(
    data: Union[StrPath, Dict[str, ArrayLike], List[Union[StrPath, Dict[str, ArrayLike]]]],
    ident: Identification,
    false_alarms_per_hour: float = 1.0,
    gain: float = 50.0,
    constant: bool = False,
) -> ContactFloor:
    """The contact floor from free motion the identification did not fit."""

def load_contact_floor(path: StrPath) -> ContactFloor:
    """Reads a contact-floor file (``ContactFloor.save``, ``admittance calibrate-contact``)."""

class RunFailed(RuntimeError):
    """A scenario run that wrote its folder but failed (a variant diverged or a metric is not
    finite); ``args[0]`` says which, ``summary`` holds the summary dict and ``out`` the
    folder."""

    summary: dict
    out: pathlib.Path

def run(
    scenario_path: StrPath,
    out: StrPath,
    variant: Optional[str] = None,
    overrides: Optional[Union[Mapping[str, object], Sequence[str]]] = None,
    *,
    seed: Optional[int] = None,
    force: bool = False,
    report: bool = True,
    recording: bool = True,
) -> dict:
    """Runs a scenario file as ``admittance run SCENARIO --out OUT`` does and returns
    ``summary.json`` as a dict. ``overrides`` are the command line's ``--set``: a dict
    ``{"duration": 5}`` or ``"key=value"`` strings. ``force`` replaces a folder the tool did
    not write; ``report`` draws the figures and reports. Raises ``ValueError`` for a bad
    scenario or override, ``FileExistsError`` when ``out`` may not be written, ``OSError`` when
    writing fails and ``RunFailed`` when a variant failed. Releases the GIL."""
