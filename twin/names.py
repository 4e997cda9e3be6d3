"""Every MJCF name Python uses, in one place (``tests/test_mujoco_model.py`` resolves each one in
the compiled models), and the layout of a bushing geom's user data. The base model is
``mjcf/bench.xml``, installed as the package ``twin.mjcf``."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Sequence


def _base_xml() -> Path:
    try:
        return Path(str(resources.files("twin.mjcf").joinpath("bench.xml")))
    except ModuleNotFoundError:  # a broken installation: twin.model_xml and the builder report it
        return Path(__file__).resolve().parent / "mjcf" / "bench.xml"


#: the readable base model: the repository's ``mjcf/bench.xml``, shipped as package data of
#: ``twin.mjcf`` (setup.py maps the folder into the package; wheels and editable installs alike)
BASE_XML = _base_xml()

# bodies
CRANK = "crank"
ROD = "rod"
SLIDER = "slider"
BODIES = (CRANK, ROD, SLIDER)

#: the motor rotor of the drive train (drive.mode "motor"/"torque"; added by the builder)
MOTOR = "motor_rotor"

# joints
CRANK_HINGE = "crank_hinge"
#: the motor rotor's hinge (drive train)
MOTOR_HINGE = "motor_hinge"
ROD_HINGE = "rod_hinge"
SLIDER_SLIDE = "slider_slide"
#: slide joints added at a clearance joint A (crank journal relative to the frame's bore, bench
#: frame; before ``crank_hinge``, so that the hinge angle stays the absolute crank angle)
ECC_A_X = "ecc_A_x"
ECC_A_Y = "ecc_A_y"
#: slide joints added at a clearance joint B (rod eye relative to the crank pin, crank frame)
ECC_B_X = "ecc_B_x"
ECC_B_Y = "ecc_B_y"

# geoms
CRANK_ARM = "crank_arm"
ROD_BEAM = "rod_beam"
SLIDER_BLOCK = "slider_block"
GUIDE_RAIL = "guide_rail"


# the flexible structure (structure.mode = "flexible", twin.mujoco_engine.flexible): the rod's chain
# (ROD is its root, the housing at B), the supports of the crank (frame at A) and of the slider (guide)
ROD_END_C = "rod_end_C"
FRAME_SUPPORT = "frame_support"
FRAME_X = "frame_x"
FRAME_Y = "frame_y"
GUIDE_SUPPORT = "guide_support"
GUIDE_Y = "guide_y"
#: site at the rod's mid-span (the deflection channel)
ROD_MID = "rod_mid"
#: sensors of the optional channel group "structure"
SENSOR_ROD_B = "rod_pos_B"
SENSOR_ROD_MID = "rod_pos_mid"
SENSOR_ROD_C = "rod_pos_C"
SENSOR_FRAME_X = "frame_x"
SENSOR_FRAME_Y = "frame_y"
SENSOR_GUIDE_Y = "guide_y"


def rod_segment(k: int) -> str:
    """Body of the flexible rod's k-th segment (1-based, from B)."""
    return f"rod_seg_{k}"


def rod_segment_beam(k: int) -> str:
    """Visual beam geom of the flexible rod's k-th segment."""
    return f"rod_beam_{k}"


def rod_bend(i: int) -> str:
    """The flexible rod's i-th elastic hinge (bending; 1-based, from B)."""
    return f"rod_bend_{i}"


def rod_axial(i: int) -> str:
    """The flexible rod's i-th elastic slide (axial; 1-based, from B)."""
    return f"rod_axial_{i}"


def pin(joint: str) -> str:
    """Pin geom and site of clearance joint ``joint`` ("A": the crank's journal, on the crank at
    its origin; "B" on the crank; "C" on the slider)."""
    return f"pin_{joint}"


def bushing(joint: str) -> str:
    """Bushing geom and site of ``joint`` (B, C: rod eye; A: the frame's bore, on the world body
    at the bench origin)."""
    return f"bushing_{joint}"


def bushing_ring(joint: str) -> str:
    """Visual ring of the bushing of ``joint``."""
    return f"bushing_{joint}_ring"


def pair(joint: str, term: int = 0) -> str:
    """Contact pair pin/bushing of a clearance joint (added by the builder).

    A calibrated contact law may be the sum of several terms, one MuJoCo pair each on the
    same two geoms: term 0 is ``contact_<J>``, term i > 0 is ``contact_<J>_t<i>``.
    """
    return f"contact_{joint}" if term == 0 else f"contact_{joint}_t{term}"


# equality, actuator
JOINT_C_CONNECT = "joint_C"
CRANK_PID = "crank_pid"
#: zero-gain actuator on the motor hinge whose ctrl carries the motor's speed set point [rad/s] or
#: torque [N m] to the native drive train (drive.mode "motor"/"torque")
MOTOR_COMMAND = "motor_command"
#: the drive train's <numeric> (layout :data:`DRIVETRAIN_FIELDS`)
DRIVETRAIN_NUMERIC = "drivetrain"
#: marker in its first field (DT_MAGIC of _drivetrain.h)
DRIVETRAIN_MAGIC = 7303.0
#: field names of the drive train's numeric data, in order (enum dt_field of _drivetrain.h)
DRIVETRAIN_FIELDS: tuple[str, ...] = (
    "marker", "motor_dof", "crank_dof", "actuator", "slot", "mode", "r_m", "r_c", "k", "c",
    "ea", "f_max", "c_slip", "stride", "counts", "alpha", "kp", "ki", "t_ctrl", "peak",
    "account", "guide_dof")
#: drive-train sensors: motor angle and speed (native), and the native module's user sensor
#: (:data:`DRIVETRAIN_SENSOR_FIELDS`)
SENSOR_MOTOR_ANGLE = "motor_angle"
SENSOR_MOTOR_SPEED = "motor_speed"
SENSOR_DRIVETRAIN = "drivetrain"
DRIVETRAIN_SENSOR_FIELDS: tuple[str, ...] = ("motor_torque", "belt_torque", "belt_slip")
#: the accounts' user sensor (acceleration stage; with the channel group drive_energy only)
SENSOR_DRIVETRAIN_ENERGY = "drivetrain_energy"
DRIVETRAIN_ENERGY_FIELDS: tuple[str, ...] = (
    "motor_work", "energy_belt", "diss_belt_damping", "diss_belt_slip", "diss_guide", "diss_contact",
    "energy_mechanical")

# the slider guide's clearance (joints.clearance_guide_mm > 0, twin.mujoco_engine.guide): the
# slider's transverse slide and tilt hinge (after slider_slide, at the slider frame Cs), the native
# law's <numeric> (layout GUIDE_CLEARANCE_FIELDS, marker GC_MAGIC of _guide.h) and sensors
SLIDER_Y = "slider_transverse"
SLIDER_TILT = "slider_tilt"
GUIDE_CLEARANCE_NUMERIC = "guide_clearance"
GUIDE_CLEARANCE_MAGIC = 7311.0
GUIDE_CLEARANCE_FIELDS: tuple[str, ...] = (
    "marker", "dof_x", "dof_y", "dof_r", "slot", "c", "a", "k", "n", "chi", "v_min",
    "friction_law", "mu0", "v0", "v1", "mu_static", "v_static", "v_kinetic")
SENSOR_SLIDER_Y = "slider_y"
SENSOR_SLIDER_TILT = "slider_tilt"
#: the native module's user sensor on the tilt hinge: rail forces on the slider's ends
SENSOR_GUIDE = "guide_contacts"
GUIDE_SENSOR_FIELDS: tuple[str, ...] = ("fn_guide_front", "fn_guide_rear", "ft_guide_front", "ft_guide_rear")

# sensors (base model)
ACCEL_SENSORS = ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6")
SENSOR_CRANK_ANGLE = "crank_angle"
SENSOR_CRANK_SPEED = "crank_speed"
SENSOR_SLIDER_POSITION = "slider_position"
SENSOR_CRANK_TORQUE = "crank_torque"
# sensor added by the builder for a prescribed drive (drive.mode = "prescribed"): the crank's
# angular acceleration, to take the flywheel's share A θ̈ out of the drive torque
SENSOR_CRANK_ANGACC = "crank_angacc"
# sensors added by the builder for the optional "energy" channel group
SENSOR_ENERGY_KINETIC = "energy_kinetic"
SENSOR_ENERGY_POTENTIAL = "energy_potential"
SENSOR_SLIDER_SPEED = "slider_speed"


def sensor_ecc(joint: str) -> str:
    """framepos sensor: pin centre in the bushing frame (rod frame at B and C, bench frame at A)."""
    return f"ecc_{joint}"


def sensor_contact(joint: str) -> str:
    """contact sensor of the pin/bushing pair (normal force)."""
    return f"contact_{joint}"


def sensor_friction(joint: str) -> str:
    """user sensor: friction force on the pin (filled by the native module's mjcb_sensor)."""
    return f"friction_{joint}"


#: marker of a bushing bore in the geom user data's "marker" field (must match BORE_MAGIC in _native.h)
BORE_MAGIC = 7301.0

#: Layout of a bushing bore's geom user data (``nuser_geom`` = its length), read by index by the
#: native module ``twin/native/_bore.c`` (its ``enum bore_user``, same order; the module
#: reports its layout and :func:`twin.native.collider.ensure_installed` compares them):
#:
#: * ``marker``: :data:`BORE_MAGIC` makes the native collider treat the geom as a hollow bore;
#: * ``mu0``, ``v0``, ``v1``: regularized Coulomb friction (S003 Eq. 19-20; μ0 [-], v0, v1 [m/s]),
#:   applied as a passive force; mu0 = 0 switches it off;
#: * ``law``: the contact's normal force: 0 = MuJoCo's own solref/solimp soft constraint,
#:   1 = hysteresis law K δⁿ (1 + χ max(δ̇/v_imp, −1)) (Lankarani–Nikravesh, Hunt–Crossley,
#:   Flores), 2 = linear law K δ + c δ̇, applied exactly by the native module (:data:`BORE_LAWS`);
#: * ``stiffness`` K [N/mⁿ] (linear law: [N/m]), ``exponent`` n [-], ``damping`` χ [-]
#:   (linear law: c [N s/m]);
#: * ``speed_floor``: floor of the stored impact speed v_imp [m/s]; ``slot``: index of the
#:   ``mjData.userdata`` slot that keeps v_imp of the contact event under way (-1 = none);
#: * ``friction``: the friction law (:data:`BORE_FRICTION_LAWS`): 0 = the regularized Coulomb law
#:   of ``mu0``, ``v0``, ``v1``; 1 = the Adams/COSMOS law (``contact.friction_law = "adams"``,
#:   S001 Table II) with μ_d = ``mu0``, stiction transition velocity v_s = ``v0``, friction
#:   transition velocity v_d = ``v1`` and ``mus`` = μ_s [-];
#: * ``dmax``: the ADAMS IMPACT law's (``law`` 3) penetration of full damping [m]; its K, n and
#:   c_max are ``stiffness``, ``exponent`` and ``damping``; Johnson's cylindrical law (``law`` 4):
#:   the radial clearance ΔR [m], with k = π L E* in ``stiffness`` and χ in ``damping``;
#: * ``force_pin``: -1 = the law acts on the collider's contact row; else the pin's geom id: the law
#:   and the friction act as passive forces between pin and bore, with no contact row
#:   (``mujoco.contact_source = "force"``).
BORE_USERDATA_FIELDS: tuple[str, ...] = ("marker", "mu0", "v0", "v1", "law", "stiffness", "exponent", "damping",
                                         "speed_floor", "slot", "friction", "mus", "dmax", "force_pin")
#: codes of the ``friction`` field
BORE_FRICTION_LAWS: dict[str, int] = {"regularized-coulomb": 0, "adams": 1}
#: codes of the ``law`` field
BORE_LAWS: dict[str, int] = {"soft": 0, "hysteresis": 1, "linear": 2, "impact": 3, "cylinder": 4}
#: values of the optional fields when not given (MuJoCo's soft contact, no slot)
_BORE_USERDATA_OPTIONAL = {"marker": BORE_MAGIC, "law": 0.0, "stiffness": 0.0, "exponent": 0.0, "damping": 0.0,
                           "speed_floor": 0.0, "slot": -1.0, "friction": 0.0, "mus": 0.0, "dmax": 0.0,
                           "force_pin": -1.0}


#: marker of a guide joint in its user data's "marker" field (must match GUIDE_MAGIC in _bore.c)
GUIDE_MAGIC = 7302.0

#: Layout of a guide joint's user data (``nuser_jnt`` = its length), read by index by the native
#: module (its ``enum guide_user``): ``marker`` (:data:`GUIDE_MAGIC`: the joint gets the
#: reference's regularized Coulomb friction as a passive force), ``force`` F [N], ``v0``, ``v1``
#: [m/s] (no friction below v0, a linear ramp to F at v1).
GUIDE_USERDATA_FIELDS: tuple[str, ...] = ("marker", "force", "v0", "v1")


def guide_userdata(force: float, v0: float, v1: float) -> list[float]:
    """User data vector of a guide joint (:data:`GUIDE_USERDATA_FIELDS`)."""
    return [GUIDE_MAGIC, float(force), float(v0), float(v1)]


def bore_userdata(**fields: float) -> list[float]:
    """User data vector of a bushing bore from its named fields (:data:`BORE_USERDATA_FIELDS`).

    ``mu0``, ``v0`` and ``v1`` are required; ``marker`` defaults to :data:`BORE_MAGIC`, the
    law fields to MuJoCo's soft contact (law 0) and ``slot`` to -1. Unknown names raise ``KeyError``.
    """
    unknown = set(fields) - set(BORE_USERDATA_FIELDS)
    if unknown:
        raise KeyError(f"unknown bore user data field(s) {sorted(unknown)}; layout: {BORE_USERDATA_FIELDS}")
    values = {**_BORE_USERDATA_OPTIONAL, **fields}
    missing = [f for f in BORE_USERDATA_FIELDS if f not in values]
    if missing:
        raise KeyError(f"bore user data needs {missing}")
    return [float(values[f]) for f in BORE_USERDATA_FIELDS]


def read_bore_userdata(user: Sequence[float]) -> dict[str, float]:
    """Named fields of a bushing bore's user data vector (inverse of :func:`bore_userdata`)."""
    if len(user) != len(BORE_USERDATA_FIELDS):
        raise ValueError(f"bore user data holds {len(user)} numbers, the layout {len(BORE_USERDATA_FIELDS)}: "
                         f"{BORE_USERDATA_FIELDS}")
    return {f: float(v) for f, v in zip(BORE_USERDATA_FIELDS, user)}


def replace_bore_userdata(user: Sequence[float], **fields: float) -> list[float]:
    """``user`` with some named fields changed."""
    return bore_userdata(**{**read_bore_userdata(user), **fields})
