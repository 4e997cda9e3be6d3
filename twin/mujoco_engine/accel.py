"""Accelerometers after the rollout, from the recorded state (``mujoco.accelerometers = "posthoc"``).

MuJoCo's ``<accelerometer>`` sensors make every step run ``mj_rnePostConstraint`` (the bodies'
accelerations and internal forces), although only the output samples are kept. With the Euler
integrator and ``eulerdamp`` disabled (the base model's option), a step updates
qvel_{k+1} = qvel_k + h qacc_k exactly, so the acceleration of step k is
qacc_k = (qvel_{k+1} − qvel_k)/h to round-off (eps |qvel|/h: about 2e-9 rad/s² at the bench's
80 rad/s and h = 1e-5 s). The rollout returns the state after each step (row k: t_{k+1}) and
the sensors at the state before it (t_k), so output sample k takes qpos_k, qvel_k from row k − 1
(the chunk's initial state for k = 0) and qvel_{k+1} from row k.

The readings are the planar kinematics of the compiled model's chain (bench frame = MuJoCo's
world frame):

* crank: origin at its body position + e_A (the slides ``ecc_A_x/y`` when A has a clearance),
  angle θ (``crank_hinge``);
* rod: origin at the crank's point u = p_rod + e_B (its body position in the crank frame plus
  the slides ``ecc_B_x/y``, crank frame), angle φ = θ + ψ (``rod_hinge``);
* slider: translation x along the guide (``slider_slide``).

a(rod origin) = ë_A + R(θ)[θ̈ J u − θ̇² u + 2 θ̇ J u̇ + ü] and a(P) = a(rod origin) + R(φ)[φ̈ J s − φ̇² s]
for a site at s in the rod frame (J: rotation by +90°); a(P) = (ẍ, 0) on the slider. The reading
is (a(P) − g)·n with n the site's x axis in the world (like MuJoCo's accelerometer, the proper
acceleration, which contains −g). Site positions, site orientations and body positions come
from the compiled model, so per-configuration mounts are honoured. ``tests/test_posthoc_accel.py``
compares against MuJoCo's own sensors; ``analysis/bench_mujoco.py`` measures the saving.

Other integrators (implicit, RK4) do not update qvel by h qacc: those runs keep MuJoCo's sensors
(:func:`posthoc_applies`). The prescribed drive (Euler) works the same way, but with the "drive"
group its ``frameangacc`` sensor of the crank runs ``mj_rnePostConstraint`` anyway, so there the
after-the-rollout path saves only the sensors' copies.
"""

from __future__ import annotations

import mujoco
import numpy as np

from twin import names as mjcf_names
from twin.config import BenchConfig
from twin.errors import ModelError

# index layout of the integer parameter vector (state offsets; -1 = no such joint)
_QAX, _QAY, _QTH, _QBX, _QBY, _QPS, _QXS = range(7)
_NIDX = 7  # velocities: the same slots + _NIDX


def posthoc_applies(cfg: BenchConfig) -> bool:
    """Whether the run computes its accelerometers after the rollout: ``mujoco.accelerometers =
    "posthoc"``, the "accel" channel group requested and the Euler integrator (another
    integrator's qvel update is not h qacc, so it keeps MuJoCo's sensors)."""
    return (cfg.mujoco.accelerometers == "posthoc" and "accel" in cfg.sensors.channels
            and cfg.mujoco.integrator == "Euler" and not cfg.joints.guide_play)  # its slider only slides


def _quat_x_axis(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q
    return np.array([1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)])


def check_euler_update(m: mujoco.MjModel) -> None:
    """ModelError unless a step of ``m`` updates qvel by exactly h qacc (Euler, no implicit joint damping): what
    the after-the-rollout accelerations (qvel_{k+1} − qvel_k)/h rely on."""
    if m.opt.integrator != mujoco.mjtIntegrator.mjINT_EULER:
        raise ModelError("posthoc accelerometers need the Euler integrator")
    if not (m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_EULERDAMP) and np.any(m.dof_damping > 0):
        raise ModelError("posthoc accelerometers need eulerdamp disabled (or no joint damping): "
                         "Euler's implicit damping makes qvel_{k+1} - qvel_k differ from h qacc_k")


class PosthocAccelerometers:
    """The six accelerometer readings of a compiled bench model from its recorded states."""

    def __init__(self, model: mujoco.MjModel, names: tuple[str, ...] = mjcf_names.ACCEL_SENSORS):
        m = model
        self.names = tuple(names)
        check_euler_update(m)
        crank, rod, slider = (m.body(b).id for b in (mjcf_names.CRANK, mjcf_names.ROD, mjcf_names.SLIDER))
        if m.body_parentid[crank] != 0 or m.body_parentid[rod] != crank or m.body_parentid[slider] != 0:
            raise ModelError("posthoc accelerometers: unexpected body tree (crank and slider on the world, rod on the crank)")
        for b in (crank, rod, slider):
            if not np.array_equal(m.body_quat[b], [1.0, 0.0, 0.0, 0.0]):
                raise ModelError(f"posthoc accelerometers: body {m.body(b).name} has a rotated frame")
        nq = m.nq
        idx = np.full(2 * _NIDX, -1, dtype=np.int64)
        expect = {mjcf_names.ECC_A_X: (_QAX, mujoco.mjtJoint.mjJNT_SLIDE, (1, 0, 0), crank),
                  mjcf_names.ECC_A_Y: (_QAY, mujoco.mjtJoint.mjJNT_SLIDE, (0, 1, 0), crank),
                  mjcf_names.CRANK_HINGE: (_QTH, mujoco.mjtJoint.mjJNT_HINGE, (0, 0, 1), crank),
                  mjcf_names.ECC_B_X: (_QBX, mujoco.mjtJoint.mjJNT_SLIDE, (1, 0, 0), rod),
                  mjcf_names.ECC_B_Y: (_QBY, mujoco.mjtJoint.mjJNT_SLIDE, (0, 1, 0), rod),
                  mjcf_names.ROD_HINGE: (_QPS, mujoco.mjtJoint.mjJNT_HINGE, (0, 0, 1), rod),
                  mjcf_names.SLIDER_SLIDE: (_QXS, mujoco.mjtJoint.mjJNT_SLIDE, (1, 0, 0), slider)}
        seen = set()
        for j in range(m.njnt):
            name = m.joint(j).name
            if name == mjcf_names.MOTOR_HINGE and m.body_parentid[m.jnt_bodyid[j]] == 0:
                continue  # the drive train's rotor, on the world: no sensor on it
            if name not in expect:
                raise ModelError(f"posthoc accelerometers: unexpected joint {name!r}")
            slot, typ, axis, body = expect[name]
            if (m.jnt_type[j] != typ or not np.array_equal(m.jnt_axis[j], axis) or m.jnt_bodyid[j] != body
                    or (typ == mujoco.mjtJoint.mjJNT_HINGE and np.any(m.jnt_pos[j] != 0))):
                raise ModelError(f"posthoc accelerometers: joint {name!r} is not the planar joint they assume")
            # FULLPHYSICS state: [time, qpos (nq), qvel (nv), ...]
            idx[slot] = 1 + m.jnt_qposadr[j]
            idx[_NIDX + slot] = 1 + nq + m.jnt_dofadr[j]
            seen.add(name)
        for name in (mjcf_names.CRANK_HINGE, mjcf_names.ROD_HINGE, mjcf_names.SLIDER_SLIDE):
            if name not in seen:
                raise ModelError(f"posthoc accelerometers: the model has no joint {name!r}")
        sites = np.zeros((len(self.names), 6))
        for i, name in enumerate(self.names):
            s = m.site(name).id
            body = m.site_bodyid[s]
            if body not in (rod, slider):
                raise ModelError(f"posthoc accelerometers: site {name} sits on body {m.body(body).name}, "
                                 "expected the rod or the slider")
            sites[i, 0] = 0.0 if body == rod else 1.0
            sites[i, 1:3] = m.site_pos[s][:2]
            sites[i, 3:6] = _quat_x_axis(m.site_quat[s])
        self._idx = idx
        self._sites = sites
        self._geo = np.array([*m.body_pos[rod][:2], *m.opt.gravity, m.opt.timestep])

    def __call__(self, state0: np.ndarray, states: np.ndarray, stride: int, n: int) -> np.ndarray:
        """Readings (len(names), n) at steps 0, stride, ..., (n − 1) stride of a rollout from the
        ``mjSTATE_FULLPHYSICS`` vector ``state0`` whose states after each step are ``states``
        (nstep, nstate)."""
        out = np.empty((len(self.names), n))
        _readings(state0, states, stride, n, self._idx, self._geo, self._sites, out)
        return out


def _readings(s0, st, stride, n, idx, geo, sites, out):
    """The kinematics of :class:`PosthocAccelerometers` (see the module docstring), vectorized
    over the output samples (about 60 ns per sample). numpy rather than a numba loop: the loop was
    41 ns per sample, but importing numba (and the scipy.linalg it pulls in) and loading the cached loop
    made every MuJoCo run start 0.6 s later, more than the loop saves on runs shorter than minutes.
    A rod sensor's reading is taken in the rod frame, where the site's offset and axis are
    constants: (a_o − g)·R(φ)n + (φ̈ J s − φ̇² s)·n with R(φ)ᵀ(a_o − g) computed once for all
    sensors, four products per sensor."""
    px, py, gx, gy, gz, h = geo
    nidx = idx.shape[0] // 2
    last = (n - 1) * stride
    z = np.zeros(n)

    def cols(i):
        """(position, velocity, acceleration) of joint slot i at the output samples (zeros if absent)."""
        if idx[i] < 0:
            return z, z, z
        q, v = st[:last + 1:stride, idx[i]], st[:last + 1:stride, idx[nidx + i]]  # after steps k
        if stride == 1:
            qk = np.concatenate(([s0[idx[i]]], q[:-1]))
            vk = np.concatenate(([s0[idx[nidx + i]]], v[:-1]))
        else:
            qk = np.concatenate(([s0[idx[i]]], st[stride - 1:last:stride, idx[i]]))
            vk = np.concatenate(([s0[idx[nidx + i]]], st[stride - 1:last:stride, idx[nidx + i]]))
        return qk, vk, (v - vk) / h

    th, om, al = cols(_QTH)
    c, s = np.cos(th), np.sin(th)
    qbx, vbx, abx = cols(_QBX)
    qby, vby, aby = cols(_QBY)
    # rod origin: θ̈ J u − θ̇² u + 2 θ̇ J u̇ + ü in the crank frame, u = p_rod + e_B
    ux, uy = px + qbx, py + qby
    om2 = om * om
    lx = -al * uy - om2 * ux - 2.0 * om * vby + abx
    ly = al * ux - om2 * uy + 2.0 * om * vbx + aby
    _, _, aax = cols(_QAX)
    _, _, aay = cols(_QAY)
    ex = aax + c * lx - s * ly - gx  # a_o − g, bench frame
    ey = aay + s * lx + c * ly - gy
    qps, vps, aps = cols(_QPS)
    ph = th + qps
    W2 = (om + vps) ** 2
    A = al + aps
    cp, sp = np.cos(ph), np.sin(ph)
    bx = cp * ex + sp * ey  # R(φ)ᵀ (a_o − g): rod frame
    by = cp * ey - sp * ex
    _, _, xs_acc = cols(_QXS)
    for i in range(sites.shape[0]):
        nx, ny, nz = sites[i, 3], sites[i, 4], sites[i, 5]
        if sites[i, 0] == 0.0:  # rod: site s and axis n are constants of the rod frame
            sx, sy = sites[i, 1], sites[i, 2]
            out[i] = bx * nx + by * ny - W2 * (sx * nx + sy * ny) + A * (sx * ny - sy * nx) - gz * nz
        else:  # slider: translation along x only
            out[i] = (xs_acc - gx) * nx - gy * ny - gz * nz
