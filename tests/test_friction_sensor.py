"""The friction sensors of the clearance joints at MuJoCo's position stage (issue 16, item 2).

``friction_A/B/C`` are user sensors of the native module (``_bore.c``). Declared
``needstage="vel"`` they made MuJoCo run ``mj_subtreeVel`` at every step (MuJoCo computes subtree
velocities for any velocity-stage user sensor) and the friction was computed twice, once in the
passive callback that applies it and once in the sensor callback. The model now declares them at
the position stage and the passive callback writes the value it applies into the sensor's slot
in the same forward pass.

Independent basis: the old path. The native module still serves velocity-stage friction sensors
by computing them in the sensor callback, so the same model compiled with ``needstage="vel"``
gives the reference values; every sensor of a run must equal them bit for bit, with Euler (the
default) and with RK4, whose intermediate forward passes skip sensors and must leave the
step's value in place.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from mujoco import rollout

from twin import names
from twin.config import preset
from twin.drive import DriveReference
from twin.mujoco_engine.engine import MujocoEngine
from twin.simulation import run_chunks

_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


def _sensor_runs(test_id: int, integrator: str, steps: int):
    """Sensor data of the engine's model (position stage) and of the same model with velocity-stage
    friction sensors, over ``steps`` steps continuing a run at speed (pins in contact, sliding)."""
    cfg = preset(test_id).replace(**{"mujoco.integrator": integrator, "joints.clearance_a_mm": 0.1,
                                     "simulation.duration_s": 0.1, "drive.ramp_s": 0.05})
    eng = MujocoEngine(cfg)
    for _ in run_chunks(eng.cfg, engine=eng):
        pass
    state = np.empty(mujoco.mj_stateSize(eng.model, _STATE))
    mujoco.mj_getState(eng.model, eng.data, state, _STATE)
    th, om = DriveReference(eng.cfg)(eng.data.time + np.arange(steps) * eng.model.opt.timestep)
    ctrl = np.stack([th, om], -1)[None]
    for sensor in eng.spec.sensors:
        if sensor.type == mujoco.mjtSensor.mjSENS_USER:
            sensor.needstage = mujoco.mjtStage.mjSTAGE_VEL
    old = eng.spec.compile()
    old.opt.timestep, old.opt.integrator = eng.model.opt.timestep, eng.model.opt.integrator
    assert (old.nq, old.nv, old.nsensordata) == (eng.model.nq, eng.model.nv, eng.model.nsensordata)
    out = {}
    for name, model in (("pos", eng.model), ("vel", old)):
        sd = np.empty((1, steps, model.nsensordata))
        rollout.rollout(model, mujoco.MjData(model), state[None], ctrl, nstep=steps, sensordata=sd)
        out[name] = sd[0]
    return eng.model, old, out


@pytest.mark.parametrize("integrator", ["Euler", "RK4"])
def test_position_stage_friction_sensors_equal_the_velocity_stage_computation(integrator):
    model, old, out = _sensor_runs(12, integrator, 2000)
    user = [i for i in range(model.nsensor) if model.sensor_type[i] == mujoco.mjtSensor.mjSENS_USER]
    assert [model.sensor(i).name for i in user] == [names.sensor_friction(j) for j in "ABC"]
    assert all(model.sensor_needstage[i] == mujoco.mjtStage.mjSTAGE_POS for i in user)
    assert all(old.sensor_needstage[i] == mujoco.mjtStage.mjSTAGE_VEL for i in user)
    for i in user:  # the pins slide with friction in these steps: the comparison is not of zeros
        adr = model.sensor_adr[i]
        assert np.count_nonzero(out["vel"][:, adr]) > 100, model.sensor(i).name
    assert out["pos"].tobytes() == out["vel"].tobytes()
