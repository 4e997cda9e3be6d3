"""Every MJCF name Python uses, in one place (``tests/test_names.py`` resolves each one in
the compiled models). The base model is ``mjcf/bench.xml``."""

from __future__ import annotations

from pathlib import Path

#: the readable base model
BASE_XML = Path(__file__).resolve().parent.parent / "mjcf" / "bench.xml"

# bodies
CRANK = "crank"
ROD = "rod"
SLIDER = "slider"
BODIES = (CRANK, ROD, SLIDER)

# joints
CRANK_HINGE = "crank_hinge"
ROD_HINGE = "rod_hinge"
SLIDER_SLIDE = "slider_slide"
#: slide joints added at a clearance joint B (rod eye relative to the crank pin, crank frame)
ECC_B_X = "ecc_B_x"
ECC_B_Y = "ecc_B_y"

# geoms
CRANK_ARM = "crank_arm"
ROD_BEAM = "rod_beam"
SLIDER_BLOCK = "slider_block"
GUIDE_RAIL = "guide_rail"


def pin(joint: str) -> str:
    """Pin geom and site of clearance joint ``joint`` ("B" on the crank, "C" on the slider)."""
    return f"pin_{joint}"


def bushing(joint: str) -> str:
    """Bushing geom and site of ``joint`` (rod eye)."""
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

# sensors (base model)
ACCEL_SENSORS = ("AC1", "AC2", "AC3", "AC4", "AC5", "AC6")
SENSOR_CRANK_ANGLE = "crank_angle"
SENSOR_CRANK_SPEED = "crank_speed"
SENSOR_SLIDER_POSITION = "slider_position"
SENSOR_CRANK_TORQUE = "crank_torque"
# sensors added by the builder for the optional "energy" channel group
SENSOR_ENERGY_KINETIC = "energy_kinetic"
SENSOR_ENERGY_POTENTIAL = "energy_potential"
SENSOR_SLIDER_SPEED = "slider_speed"


def sensor_ecc(joint: str) -> str:
    """framepos sensor: pin centre in the bushing frame (added by the builder)."""
    return f"ecc_{joint}"


def sensor_contact(joint: str) -> str:
    """contact sensor of the pin/bushing pair (normal force)."""
    return f"contact_{joint}"


def sensor_friction(joint: str) -> str:
    """user sensor: friction force on the pin (filled by the native module's mjcb_sensor)."""
    return f"friction_{joint}"


#: marker of a bushing bore in geom user[0] (must match BORE_MAGIC in _bore.c); user[1:4] = mu0, v0, v1
BORE_MAGIC = 7301.0
