"""The slider guide's two-sided clearance in the MuJoCo twin (``joints.clearance_guide_mm`` > 0).

The slider body gets two more joints at its frame Cs on the guide line, after the guide slide:
``slider_transverse`` (slide along y) and ``slider_tilt`` (hinge about z). The rails are not
geoms: the two-sided contact of the shoe's front and rear ends (Cs ± a along the slider's axis)
with the upper and lower rails at y = ±c is computed by the native module (``_guide.h``, called
from the passive callback of ``_bore.c``) with the reference engine's law and friction
(:mod:`twin.reference.guide`), parameters in the ``<numeric>`` ``guide_clearance``
(:data:`twin.names.GUIDE_CLEARANCE_FIELDS`), contact events in ``mjData.userdata``. Sensors: the
two joints' positions and the native user sensor with the rail forces
(:data:`twin.names.GUIDE_SENSOR_FIELDS`).
"""

from __future__ import annotations

import mujoco

from twin import names
from twin.config import BenchConfig
from twin.config.mechanism import guide_stiffness
from twin.impact import DAMPING_FACTOR

#: the reference engine's floor of the stored impact speed [m/s] (its build_params default)
MIN_IMPACT_SPEED_MPS = 1e-3


def applies(cfg: BenchConfig) -> bool:
    return cfg.joints.guide_play


def guide_law(cfg: BenchConfig) -> str:
    """The guide's normal law: the configured hysteresis law, else Lankarani–Nikravesh (as the
    reference engine's :func:`twin.reference.guide.guide_law_code`)."""
    return cfg.contact.law if cfg.contact.law in DAMPING_FACTOR else "lankarani-nikravesh"


def add_guide(spec: mujoco.MjSpec, cfg: BenchConfig) -> None:
    """Spec edits: the two joints, the numeric (filled by :func:`finish`) and the sensors."""
    body = spec.body(names.SLIDER)
    body.add_joint(name=names.SLIDER_Y, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0])
    body.add_joint(name=names.SLIDER_TILT, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    spec.add_numeric(name=names.GUIDE_CLEARANCE_NUMERIC, data=[0.0] * len(names.GUIDE_CLEARANCE_FIELDS))
    if "joints" in cfg.sensors.channels:
        for name, joint in ((names.SENSOR_SLIDER_Y, names.SLIDER_Y), (names.SENSOR_SLIDER_TILT, names.SLIDER_TILT)):
            spec.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_JOINTPOS, objtype=mujoco.mjtObj.mjOBJ_JOINT,
                            objname=joint)
        spec.add_sensor(name=names.SENSOR_GUIDE, type=mujoco.mjtSensor.mjSENS_USER, objtype=mujoco.mjtObj.mjOBJ_JOINT,
                        objname=names.SLIDER_TILT, dim=len(names.GUIDE_SENSOR_FIELDS), needstage=mujoco.mjtStage.mjSTAGE_POS)


def finish(spec: mujoco.MjSpec, cfg: BenchConfig, model: mujoco.MjModel) -> None:
    """Write the numeric data (dof addresses from the compiled ``model``) and reserve the user
    data slots; the spec must be compiled again."""
    from twin.native import _bore

    con, j = cfg.contact, cfg.joints
    slot = int(spec.nuserdata)

    def dof(name: str) -> int:
        return int(model.jnt_dofadr[model.joint(name).id])

    vals = dict(
        marker=names.GUIDE_CLEARANCE_MAGIC, dof_x=dof(names.SLIDER_SLIDE), dof_y=dof(names.SLIDER_Y), dof_r=dof(names.SLIDER_TILT),
        slot=slot, c=j.guide_radial_m, a=j.guide_span_m / 2.0, k=guide_stiffness(j, cfg.materials),
        n=con.exponent, chi=DAMPING_FACTOR[guide_law(cfg)](con.restitution), v_min=MIN_IMPACT_SPEED_MPS,
        friction_law=1.0 if con.friction_law == "adams" else 0.0, mu0=con.mu0, v0=con.v0_mps, v1=con.v1_mps,
        mu_static=con.mu_static, v_static=con.v_static_mps, v_kinetic=con.v_kinetic_mps)
    spec.numeric(names.GUIDE_CLEARANCE_NUMERIC).data = [float(vals[f]) for f in names.GUIDE_CLEARANCE_FIELDS]
    spec.nuserdata = slot + _bore.guide_clearance_layout()[1]
