"""Accelerometers after the rollout for any planar body tree (the flexible structure's; ``mujoco.accelerometers =
"posthoc"``).

:mod:`twin.mujoco_engine.accel` computes the readings of the rigid bench's three bodies in closed form; the
flexible structure (:mod:`twin.mujoco_engine.flexible`) nests the rod's segments, the supports and their joints,
so its readings come from this generic recursion instead, on the same recorded states and the same finite
difference of the velocities (Euler with ``eulerdamp`` disabled: qacc_k = (qvel_{k+1} − qvel_k)/h to round-off;
the joint dampers are explicit, so this holds with them too).

Every body's planar pose, velocity and acceleration (origin p, angle φ and their derivatives) follow from its
parent's, vectorized over the output samples:

* the body's offset d in the parent frame (r = R(φ) d): p += r, v += ω J r, a += α J r − ω² r;
* then its joints in order: a slide along the in-plane axis u of the current frame (s = R(φ) u):
  p += s q, v += s q̇ + ω J s q, a += s q̈ + 2 ω J s q̇ + α J s q − ω² s q; a hinge about +z at the body origin:
  φ += q, ω += q̇, α += q̈ (MuJoCo's kinematics: a slide moves along the axis as rotated by the joints before it);
* a site at s in its body's frame reads (a + α J R(φ)s − ω² R(φ)s − g) · R(φ)n, n its x axis in the body frame.

The model must be planar in that sense (checked: bodies unrotated, hinges about +z at their body's origin, slides
in the plane, sensitive axes in the plane; otherwise :class:`~twin.errors.ModelError`).
"""

from __future__ import annotations

import mujoco
import numpy as np

from twin import names as mjcf_names
from twin.errors import ModelError
from twin.mujoco_engine.accel import _quat_x_axis


class TreeAccelerometers:
    """The accelerometer readings of a compiled planar model from its recorded states (module docstring)."""

    def __init__(self, model: mujoco.MjModel, names: tuple[str, ...] = mjcf_names.ACCEL_SENSORS):
        m = model
        self.names = tuple(names)
        if m.opt.integrator != mujoco.mjtIntegrator.mjINT_EULER:
            raise ModelError("posthoc accelerometers need the Euler integrator")
        if not (m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_EULERDAMP) and np.any(m.dof_damping > 0):
            raise ModelError("posthoc accelerometers need eulerdamp disabled (or no joint damping)")
        nq = m.nq
        wanted = {int(m.site_bodyid[m.site(s).id]) for s in self.names}
        # the bodies on the paths from the world to the sensors' bodies, parents first
        need: set[int] = set()
        for b in wanted:
            while b > 0 and b not in need:
                need.add(b)
                b = int(m.body_parentid[b])
        self._bodies: list[tuple[int, int, np.ndarray, list[tuple[str, int, int, np.ndarray]]]] = []
        for b in sorted(need):  # MuJoCo's body order has parents first
            if not np.allclose(m.body_quat[b], [1.0, 0.0, 0.0, 0.0]):
                raise ModelError(f"posthoc accelerometers: body {m.body(b).name} has a rotated frame")
            joints = []
            for j in range(m.body_jntadr[b], m.body_jntadr[b] + m.body_jntnum[b]):
                ax = m.jnt_axis[j]
                qa, da = 1 + int(m.jnt_qposadr[j]), 1 + nq + int(m.jnt_dofadr[j])  # FULLPHYSICS: [time, qpos, qvel]
                if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
                    if not np.array_equal(ax, [0.0, 0.0, 1.0]) or np.any(m.jnt_pos[j] != 0):
                        raise ModelError(f"posthoc accelerometers: joint {m.joint(j).name!r} is not a hinge about +z "
                                         "at its body's origin")
                    joints.append(("hinge", qa, da, ax[:2].copy()))
                elif m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE:
                    if ax[2] != 0:
                        raise ModelError(f"posthoc accelerometers: slide {m.joint(j).name!r} leaves the plane")
                    joints.append(("slide", qa, da, ax[:2].copy()))
                else:
                    raise ModelError(f"posthoc accelerometers: joint {m.joint(j).name!r} is neither hinge nor slide")
            self._bodies.append((b, int(m.body_parentid[b]), m.body_pos[b][:2].copy(), joints))
        self._sites = []
        for name in self.names:
            s = m.site(name).id
            n = _quat_x_axis(m.site_quat[s])
            if abs(n[2]) > 1e-12:
                raise ModelError(f"posthoc accelerometers: the axis of {name} leaves the plane")
            self._sites.append((int(m.site_bodyid[s]), m.site_pos[s][:2].copy(), n[:2].copy()))
        self._g = np.array(m.opt.gravity[:2])
        self._h = float(m.opt.timestep)

    def __call__(self, state0: np.ndarray, states: np.ndarray, stride: int, n: int) -> np.ndarray:
        """Readings (len(names), n) at steps 0, stride, …, (n − 1) stride of a rollout from the
        ``mjSTATE_FULLPHYSICS`` vector ``state0`` whose states after each step are ``states`` (nstep, nstate)."""
        h, last = self._h, (n - 1) * stride
        after = states[:last + 1:stride]  # state after step k (its qvel: qvel_{k+1})
        before = np.concatenate((state0[None], states[stride - 1:last:stride]), axis=0)  # state at t_k

        def col(adr_q: int, adr_v: int):
            q, v = before[:, adr_q], before[:, adr_v]
            return q, v, (after[:, adr_v] - v) / h

        zero = np.zeros(n)
        kin: dict[int, tuple] = {0: (zero, zero, zero, zero, zero, zero, zero)}  # px, py, vx, vy, ax, ay, φ; ω, α
        ang: dict[int, tuple] = {0: (zero, zero, zero)}
        for b, parent, d, joints in self._bodies:
            px, py, vx, vy, ax, ay, _ = kin[parent]
            phi, om, al = ang[parent]
            c, s = np.cos(phi), np.sin(phi)
            rx, ry = c * d[0] - s * d[1], s * d[0] + c * d[1]
            om2 = om * om
            px, py = px + rx, py + ry
            vx, vy = vx - om * ry, vy + om * rx
            ax, ay = ax - al * ry - om2 * rx, ay + al * rx - om2 * ry
            for kind, qa, da, u in joints:
                q, qd, qdd = col(qa, da)
                if kind == "hinge":
                    phi, om, al = phi + q, om + qd, al + qdd
                    c, s = np.cos(phi), np.sin(phi)
                    om2 = om * om
                else:
                    sx, sy = c * u[0] - s * u[1], s * u[0] + c * u[1]
                    px, py = px + sx * q, py + sy * q
                    vx, vy = vx + sx * qd - om * sy * q, vy + sy * qd + om * sx * q
                    ax = ax + sx * qdd - 2 * om * sy * qd - al * sy * q - om2 * sx * q
                    ay = ay + sy * qdd + 2 * om * sx * qd + al * sx * q - om2 * sy * q
            kin[b] = (px, py, vx, vy, ax, ay, None)
            ang[b] = (phi, om, al)
        out = np.empty((len(self._sites), n))
        gx, gy = self._g
        for i, (b, sp, nl) in enumerate(self._sites):
            _, _, _, _, ax, ay, _ = kin[b]
            phi, om, al = ang[b]
            c, s = np.cos(phi), np.sin(phi)
            rx, ry = c * sp[0] - s * sp[1], s * sp[0] + c * sp[1]
            nx, ny = c * nl[0] - s * nl[1], s * nl[0] + c * nl[1]
            om2 = om * om
            out[i] = (ax - al * ry - om2 * rx - gx) * nx + (ay + al * rx - om2 * ry - gy) * ny
        return out
