"""Accelerometers after the rollout for any planar body tree (the flexible structure's; ``mujoco.accelerometers =
"posthoc"``).

:mod:`twin.mujoco_engine.accel` computes the readings of the rigid bench's three bodies in closed form; the
flexible structure (:mod:`twin.mujoco_engine.flexible`) nests the rod's segments, the supports and their joints,
so its readings come from this generic recursion instead, on the same recorded states and the same finite
difference of the velocities (Euler with ``eulerdamp`` disabled: qacc_k = (qvel_{k+1} − qvel_k)/h to round-off;
the joint dampers are explicit, so this holds with them too).

Every body's planar acceleration (its origin's a, its angle φ, ω, α) follows from its parent's, vectorized over the output samples:

* the body's offset d in the parent frame (r = R(φ) d): a += α J r − ω² r;
* then its joints in order: a slide along the in-plane axis u of the current frame (s = R(φ) u):
  a += s q̈ + 2 ω J s q̇ + α J s q − ω² s q; a hinge about +z at the body origin: φ += q, ω += q̇, α += q̈
  (MuJoCo's kinematics: a slide moves along the axis as rotated by the joints before it; the origin's position
  and velocity never enter the acceleration);
* a site at s in its body's frame reads (a + α J R(φ)s − ω² R(φ)s − g) · R(φ)n, n its x axis in the body frame.

The loop is compiled (numba, :mod:`twin.jit`; the flexible structure only: the rigid bench's path keeps
numba out of MuJoCo runs). The model must be planar in that sense (checked: bodies unrotated, hinges about +z at their body's origin, slides
in the plane, sensitive axes in the plane; otherwise :class:`~twin.errors.ModelError`).
"""

from __future__ import annotations

import mujoco
import numpy as np

from twin import names as mjcf_names
from twin.errors import ModelError
from twin.jit import njit
from twin.mujoco_engine.accel import _quat_x_axis, check_euler_update


class TreeAccelerometers:
    """The accelerometer readings of a compiled planar model from its recorded states (module docstring)."""

    def __init__(self, model: mujoco.MjModel, names: tuple[str, ...] = mjcf_names.ACCEL_SENSORS):
        m = model
        self.names = tuple(names)
        check_euler_update(m)
        nq = m.nq
        wanted = {int(m.site_bodyid[m.site(s).id]) for s in self.names}
        # the bodies on the paths from the world to the sensors' bodies, parents first
        need: set[int] = set()
        for b in wanted:
            while b > 0 and b not in need:
                need.add(b)
                b = int(m.body_parentid[b])
        self._bodies: list[tuple[int, int, np.ndarray, list[tuple[str, int, np.ndarray]]]] = []
        iq: list[int] = []
        iv: list[int] = []
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
                    joints.append(("hinge", len(iq), ax[:2].copy()))
                    iq.append(qa)
                    iv.append(da)
                elif m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE:
                    if ax[2] != 0:
                        raise ModelError(f"posthoc accelerometers: slide {m.joint(j).name!r} leaves the plane")
                    joints.append(("slide", len(iq), ax[:2].copy()))
                    iq.append(qa)
                    iv.append(da)
                else:
                    raise ModelError(f"posthoc accelerometers: joint {m.joint(j).name!r} is neither hinge nor slide")
            self._bodies.append((b, int(m.body_parentid[b]), m.body_pos[b][:2].copy(), joints))
        self._iq, self._iv = np.array(iq, dtype=np.int64), np.array(iv, dtype=np.int64)
        self._sites = []
        for name in self.names:
            s = m.site(name).id
            n = _quat_x_axis(m.site_quat[s])
            if abs(n[2]) > 1e-12:
                raise ModelError(f"posthoc accelerometers: the axis of {name} leaves the plane")
            self._sites.append((int(m.site_bodyid[s]), m.site_pos[s][:2].copy(), n[:2].copy()))
        # flat tables for the compiled loop: bodies renumbered in tree order, 0 the world
        local = {0: 0}
        for b, *_ in self._bodies:
            local[b] = len(local)
        nb = len(local)
        self._parent = np.zeros(nb, dtype=np.int64)
        self._offset = np.zeros((nb, 2))
        self._jrange = np.zeros((nb, 2), dtype=np.int64)
        kinds, cols, axes = [], [], []
        for b, parent, d, joints in self._bodies:
            i = local[b]
            self._parent[i], self._offset[i] = local[parent], d
            self._jrange[i, 0] = len(kinds)
            for kind, col, u in joints:
                kinds.append(0 if kind == "hinge" else 1)
                cols.append(col)
                axes.append(u)
            self._jrange[i, 1] = len(kinds)
        self._jkind = np.array(kinds, dtype=np.int64)
        self._jcol = np.array(cols, dtype=np.int64)
        self._jaxis = np.array(axes, dtype=np.float64).reshape(-1, 2)
        self._site_body = np.array([local[b] for b, _, _ in self._sites], dtype=np.int64)
        self._site_pos = np.array([sp for _, sp, _ in self._sites], dtype=np.float64).reshape(-1, 2)
        self._site_axis = np.array([nl for _, _, nl in self._sites], dtype=np.float64).reshape(-1, 2)
        self._g = np.array(m.opt.gravity[:2])
        self._h = float(m.opt.timestep)

    def __call__(self, state0: np.ndarray, states: np.ndarray, stride: int, n: int) -> np.ndarray:
        """Readings (len(names), n) at steps 0, stride, …, (n − 1) stride of a rollout from the
        ``mjSTATE_FULLPHYSICS`` vector ``state0`` whose states after each step are ``states`` (nstep, nstate)."""
        out = np.empty((len(self._site_body), n))
        _tree_readings(state0, states, stride, self._iq, self._iv, self._h, self._parent, self._offset, self._jrange,
                       self._jkind, self._jcol, self._jaxis, self._site_body, self._site_pos, self._site_axis, self._g,
                       out)
        return out


@njit
def _tree_readings(state0, states, stride, iq, iv, h, parent, offset, jrange, jkind, jcol, jaxis, site_body, site_pos,
                   site_axis, g, out):
    """The recursion of the module docstring, sample by sample (bodies in tree order, index 0 the world). Output
    sample k is at step k·stride: its state is the row before it (``state0`` for k = 0), its acceleration the
    difference of the velocities across that step."""
    nb = parent.shape[0]
    ax = np.zeros(nb)
    ay = np.zeros(nb)
    ph = np.zeros(nb)
    om = np.zeros(nb)
    al = np.zeros(nb)
    co = np.ones(nb)
    si = np.zeros(nb)
    for k in range(out.shape[1]):
        row = k * stride
        before = state0 if row == 0 else states[row - 1]
        after = states[row]
        for b in range(1, nb):
            p = parent[b]
            a_x, a_y, phi, w, alpha, c, s = ax[p], ay[p], ph[p], om[p], al[p], co[p], si[p]
            w2 = w * w
            dx, dy = offset[b, 0], offset[b, 1]
            if dx != 0.0 or dy != 0.0:
                rx, ry = c * dx - s * dy, s * dx + c * dy
                a_x += -alpha * ry - w2 * rx
                a_y += alpha * rx - w2 * ry
            for j in range(jrange[b, 0], jrange[b, 1]):
                col = jcol[j]
                q, qd = before[iq[col]], before[iv[col]]
                qdd = (after[iv[col]] - qd) / h
                if jkind[j] == 0:  # hinge about +z
                    phi += q
                    w += qd
                    alpha += qdd
                    c, s = np.cos(phi), np.sin(phi)
                    w2 = w * w
                else:  # slide
                    sx = c * jaxis[j, 0] - s * jaxis[j, 1]
                    sy = s * jaxis[j, 0] + c * jaxis[j, 1]
                    t1 = qdd - w2 * q
                    t2 = 2.0 * w * qd + alpha * q
                    a_x += sx * t1 - sy * t2
                    a_y += sy * t1 + sx * t2
            ax[b], ay[b], ph[b], om[b], al[b], co[b], si[b] = a_x, a_y, phi, w, alpha, c, s
        for i in range(site_body.shape[0]):
            b = site_body[i]
            c, s = co[b], si[b]
            rx = c * site_pos[i, 0] - s * site_pos[i, 1]
            ry = s * site_pos[i, 0] + c * site_pos[i, 1]
            nx = c * site_axis[i, 0] - s * site_axis[i, 1]
            ny = s * site_axis[i, 0] + c * site_axis[i, 1]
            w2 = om[b] * om[b]
            out[i, k] = ((ax[b] - al[b] * ry - w2 * rx - g[0]) * nx
                         + (ay[b] + al[b] * rx - w2 * ry - g[1]) * ny)
