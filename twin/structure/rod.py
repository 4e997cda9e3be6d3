"""The flexible connecting rod's discrete model, the same for both engines: a chain of rigid bodies joined by
elastic hinges and slides, its linearized matrices about the straight rod and its modes.

Rod frame: origin at B (the centre of the rod's eye at B), x along the straight rod towards C, y normal to it
in the mechanism's plane (z out of the plane). Bodies, in chain order (parent before child):

* ``end_B``: the housing at B, point mass m_B at x = 0 with its rotary inertia J_e. It carries the rod's
  bore at B, its rigid-body motion is the rod's (the root of the chain).
* ``seg_1`` … ``seg_N``: rigid pieces of the uniform bar, length l_j, mass m_bar l_j / L at the middle, inertia
  (m_bar l_j / L) l_j²/12 about it: equal lengths L/N in the uniform chain; in the tuned chain (the default,
  :func:`tuned_parameters`) the two outer segments have their own length and the N − 2 inner ones share the rest.
* ``end_C``: the housing at C, point mass m_C at x = L with J_e; it carries the bore at C.

Joints (each joins a body to the previous one; a node with two joints applies the hinge first, then the
slide along the child's own x axis):

* a slide at x = 0 (end_B → seg_1) and at x = L (seg_N → end_C), stiffness 2 M E A / L;
* at each interior node x_j = j l (seg_j → seg_{j+1}): a hinge, stiffness E I / l, and where j is a multiple
  of N/M also a slide, stiffness M E A / L (uniform chain; with unequal segments each slide holds E A over the
  distance between the neighbouring groups' mass centres and each hinge E I over the mean length of the two
  segments it joins, times the tuned multipliers).

Why this chain (rigid finite elements; measured by ``tests/test_structure.py``): a rigid uniform segment's
kinetic energy in its end displacements is exactly the consistent linear-interpolation mass (its rotary
inertia included), and the hinge springs E I / l give the central difference of w''. Their errors cancel at
second order: for the pinned–pinned bar the discrete frequencies are ω_n/ω_n,exact = (sin(φ/2)/(φ/2))² ·
√(3/(2 + cos φ)), φ = nπ/N, ≈ 1 − φ⁴/1440: uniform N = 6 resolves three bending modes within 0.8 %, N = 8 four;
a lumped-mass chain would need N ≈ 27 for the third mode (error ≈ φ²/6). Axially each group of N/M
segments is rigid (its mass lumped at its centre) and each spring holds the compliance between two
neighbouring mass centres (the rigid finite element rule): the static stretch is exact and the first axial
mode's effective mass is m_bar (1/3 − 1/(12 M²)), within 0.6 % of the continuum for M = 2. Fewer axial DOFs
than bending DOFs keeps the highest axial mode (≈ 2 M √(EA/(L m_bar)) scaled by the end masses) below the
step's stability limit and the cost low. The linearized model has bending and axial motion uncoupled;
the engines integrate the nonlinear chain (large rotations, the joints as written).

The tuned chain (``rod_chain = "tuned"``, the default with N = 4, M = 2): four uniform segments miss the third
bending mode by 6.3 %; with three shape parameters (the outer segments' length, the outermost hinges' and the inner
hinges' stiffness multipliers) solved at the model's build the chain's first three bending modes equal the
continuum's (Euler–Bernoulli pinned–pinned with the housings' rotary inertia, which the uniform chain resolves
slowly), and one multiplier of the axial springs sets the first axial mode (B fixed, the slider at C) to the
continuum's; the free rod's first axial mode with its end masses then stays within 1 % for M = 2 (20 % off for
M = 1). Table 1's mass, centre of mass and inertia are kept (the segments are pieces of the same uniform bar).

Structural damping: stiffness-proportional (Rayleigh β) per joint, c = β k, β_bending = 2 ζ_b / ω_b1 (the
discrete model's first pinned–pinned bending mode), β_axial = 2 ζ_a / ω_a1 (its first axial mode with B
fixed and the end mass and the slider at C): joint dampers, native to MuJoCo's joints.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import eigh, null_space

from twin.errors import ConfigError


@dataclass(frozen=True)
class RodSplit:
    """Table 1's rod as a uniform bar plus two end masses (the bushing housings), all three moments kept.

    Attributes:
        bar_mass_kg: mass of the uniform bar between B and C [kg].
        end_b_kg: point mass at B [kg].
        end_c_kg: point mass at C [kg].
        end_inertia_kgm2: rotary inertia of each end housing about its own centre [kg m²].
        length_m: B–C distance L [m].
    """

    bar_mass_kg: float
    end_b_kg: float
    end_c_kg: float
    end_inertia_kgm2: float
    length_m: float

    @property
    def mass_kg(self) -> float:
        return self.bar_mass_kg + self.end_b_kg + self.end_c_kg

    @property
    def x_g_m(self) -> float:
        """Centre of mass from B [m]."""
        return (self.bar_mass_kg * self.length_m / 2 + self.end_c_kg * self.length_m) / self.mass_kg

    @property
    def inertia_g_kgm2(self) -> float:
        """Inertia about the centre of mass [kg m²]."""
        L, xg = self.length_m, self.x_g_m
        i_b = self.bar_mass_kg * L * L / 3 + self.end_c_kg * L * L + 2 * self.end_inertia_kgm2
        return i_b - self.mass_kg * xg * xg


def rod_split(mass_kg: float, length_m: float, x_g_m: float, inertia_kgm2: float,
              end_inertia_kgm2: float) -> RodSplit:
    """Split a rod of mass m, length L, centre of mass x_G from B and inertia I_G into a uniform bar m_bar and
    end masses m_B, m_C (each end with its own rotary inertia J_e) keeping m, x_G and I_G exactly:

        m_bar + m_B + m_C = m,   m_bar L/2 + m_C L = m x_G,   m_bar L²/3 + m_C L² + 2 J_e = I_G + m x_G².

    S003 Table 1 (3.55 kg, 0.6 m, 0.3 m, 0.197 kg m², J_e = 0): m_bar = 2.042 kg, m_B = m_C = 0.754 kg.
    ConfigError (``bodies.rod.inertia_kgm2``) if a mass comes out negative (a rod with less inertia than its
    centre of mass allows for a bar with end masses)."""
    L = length_m
    s1 = mass_kg * x_g_m / L
    s2 = (inertia_kgm2 + mass_kg * x_g_m ** 2 - 2.0 * end_inertia_kgm2) / (L * L)
    bar = 6.0 * (s1 - s2)
    end_c = s2 - bar / 3.0
    end_b = mass_kg - bar - end_c
    if not (bar > 0.0 and end_b >= 0.0 and end_c >= 0.0):
        # the housings' inertia J_e takes 2 J_e / L² from s2; the end masses stay >= 0 (and the bar > 0) down to
        # s2 = max(2 s1 / 3, (4 s1 − m) / 3): the largest J_e this rod allows
        s2_min = max(2.0 * s1 / 3.0, (4.0 * s1 - mass_kg) / 3.0)
        j_max = 0.5 * (inertia_kgm2 + mass_kg * x_g_m ** 2 - s2_min * L * L)
        s2_0 = (inertia_kgm2 + mass_kg * x_g_m ** 2) / (L * L)  # without the housings' inertia
        if s2_min <= s2_0 < s1 and end_inertia_kgm2 > j_max:  # the rod splits; the housings' inertia is too much
            raise ConfigError("structure.rod_end_inertia_kgm2",
                              f"must lie in [0, {j_max:.4g}] kg m^2 with this rod (bodies.rod: mass {mass_kg:g} kg, "
                              f"x_G {x_g_m:g} m, I_G {inertia_kgm2:g} kg m^2: more housing inertia leaves the end "
                              f"masses negative), got {end_inertia_kgm2!r}")
        raise ConfigError("bodies.rod.inertia_kgm2",
                          "the flexible rod needs Table 1's rod as a uniform bar with end masses; "
                          f"mass {mass_kg:g} kg, "
                          f"x_G {x_g_m:g} m and I_G {inertia_kgm2:g} kg m^2 (with structure.rod_end_inertia_kgm2 = "
                          f"{end_inertia_kgm2:g}) give bar {bar:.4g}, ends {end_b:.4g} / {end_c:.4g} kg (must be >= 0)")
    return RodSplit(bar, end_b, end_c, end_inertia_kgm2, L)


@dataclass(frozen=True)
class ChainBody:
    """A rigid body of the chain (rod frame, straight rod)."""

    name: str
    x0_m: float          #: start of the body along the rod [m]
    x1_m: float          #: end of the body along the rod [m]
    mass_kg: float       #: mass [kg]
    com_x_m: float       #: centre of mass along the rod [m] (on the axis)
    inertia_kgm2: float  #: inertia about the centre of mass, about z [kg m²]


@dataclass(frozen=True)
class ChainJoint:
    """An elastic joint of the chain: ``kind`` "hinge" (about z at (x_m, 0)) or "slide" (along the child's
    x axis), joining body ``child`` to body ``child − 1``; generalized force −k q − c q̇."""

    kind: str
    child: int             #: index of the child body in :attr:`RodChain.bodies`
    x_m: float             #: position of the joint along the straight rod [m]
    stiffness: float       #: [N m/rad] (hinge) or [N/m] (slide)
    damping: float         #: [N m s/rad] or [N s/m]


@dataclass(frozen=True)
class RodChain:
    """The discrete rod: bodies in chain order, joints in the order of their coordinates."""

    bodies: tuple[ChainBody, ...]
    joints: tuple[ChainJoint, ...]
    split: RodSplit
    ea_n: float
    ei_nm2: float

    @property
    def length_m(self) -> float:
        return self.split.length_m

    @property
    def n_joints(self) -> int:
        return len(self.joints)

    def with_damping(self, beta_bending: float, beta_axial: float) -> "RodChain":
        """The same chain with joint dampers c = β k (β per joint kind) [s]."""
        joints = tuple(dataclasses.replace(j, damping=(beta_bending if j.kind == "hinge" else beta_axial) * j.stiffness)
                       for j in self.joints)
        return dataclasses.replace(self, joints=joints)


def undamped_chain(split: RodSplit, ea_n: float, ei_nm2: float, segments: int, axial_groups: int,
                   tuned: bool = False, tip_mass_kg: float = 0.0) -> RodChain:
    """The chain of the module docstring without damping (dampers: :func:`rod_chain`): uniform segments with
    E I / l hinges and the rigid-finite-element slides, or with ``tuned`` the chain whose outer segments' length
    and hinge stiffnesses reproduce the first three bending modes and whose slides reproduce the first axial mode
    of the continuum (:func:`tuned_parameters`; needs N >= 4)."""
    N, M = segments, axial_groups
    if N < 1 or M < 1 or N % M:
        raise ValueError(f"segments ({N}) must be a positive multiple of axial_groups ({M})")
    if not tuned:
        return _chain(split, ea_n, ei_nm2, N, M, ChainTuning.uniform(N))
    return _chain(split, ea_n, ei_nm2, N, M, tuned_parameters(split, ea_n, ei_nm2, N, M, tip_mass_kg))


@dataclass(frozen=True)
class ChainTuning:
    """The chain's shape parameters: the two outer segments' length as a fraction of L (the N − 2 inner segments
    share the rest equally), the multipliers of the hinge stiffness E I / l̄ (l̄ the mean length of the two
    segments the hinge joins) at the two outermost hinges and at the others, and of every axial spring."""

    outer_fraction: float
    k_outer: float
    k_inner: float
    k_axial: float

    @staticmethod
    def uniform(segments: int) -> "ChainTuning":
        return ChainTuning(1.0 / segments, 1.0, 1.0, 1.0)


def _chain(split: RodSplit, ea_n: float, ei_nm2: float, N: int, M: int, tu: ChainTuning) -> RodChain:
    L = split.length_m
    uniform = tu == ChainTuning.uniform(N)
    if uniform:   # the uniform chain's numbers exactly as written in the module docstring
        l = L / N
        lengths = [l] * N
        x = [j * l for j in range(N + 1)]
        seg_mass = [split.bar_mass_kg / N] * N
    else:
        a = tu.outer_fraction * L
        lengths = [a] + [(L - 2.0 * a) / (N - 2)] * (N - 2) + [a]
        x = [0.0] + [float(v) for v in np.cumsum(lengths)]
        x[-1] = L
        seg_mass = [split.bar_mass_kg * lj / L for lj in lengths]
    bodies = [ChainBody("end_B", 0.0, 0.0, split.end_b_kg, 0.0, split.end_inertia_kgm2)]
    for j in range(N):
        ms, lj = seg_mass[j], lengths[j]
        bodies.append(ChainBody(f"seg_{j + 1}", x[j], x[j + 1], ms, (j + 0.5) * lj if uniform else (x[j] + x[j + 1]) / 2,
                                ms * lj * lj / 12.0))
    bodies.append(ChainBody("end_C", L, L, split.end_c_kg, L, split.end_inertia_kgm2))
    # axial springs: each holds the bar's compliance between two neighbouring mass centres (rigid finite elements):
    # 2 M E A / L at the ends and M E A / L between groups for uniform segments
    per = N // M
    if uniform:
        k_ax = [2.0 * M * ea_n / L] + [M * ea_n / L] * (M - 1) + [2.0 * M * ea_n / L]
    else:
        centres = [0.0] + [(x[g * per] + x[(g + 1) * per]) / 2.0 for g in range(M)] + [L]
        k_ax = [tu.k_axial * ea_n / (centres[g + 1] - centres[g]) for g in range(M + 1)]
    joints = [ChainJoint("slide", 1, 0.0, k_ax[0], 0.0)]
    for j in range(1, N):
        mult = tu.k_outer if j in (1, N - 1) else tu.k_inner
        k_h = ei_nm2 / l if uniform else mult * ei_nm2 / ((lengths[j - 1] + lengths[j]) / 2.0)
        joints.append(ChainJoint("hinge", j + 1, x[j], k_h, 0.0))
        if j % per == 0:
            joints.append(ChainJoint("slide", j + 1, x[j], k_ax[j // per], 0.0))
    joints.append(ChainJoint("slide", N + 1, L, k_ax[M], 0.0))
    return RodChain(tuple(bodies), tuple(joints), split, ea_n, ei_nm2)


@functools.lru_cache(maxsize=64)
def tuned_parameters(split: RodSplit, ea_n: float, ei_nm2: float, segments: int, axial_groups: int,
                     tip_mass_kg: float = 0.0) -> ChainTuning:
    """The tuned chain's shape (:class:`ChainTuning`), solved at the model's build.

    Method: three unknowns (the outer segments' length fraction r, the hinge multipliers κ_o and κ_i) and three
    equations, the first three bending frequencies of the chain's linearization with B pinned and C held normal to
    the rod (:func:`modes`, a generalized eigenproblem of size N + M + 1 − 2) equal to Euler–Bernoulli's pinned–pinned
    bar with the housings' rotary inertia (:func:`twin.structure.closed_forms.bending_pinned_end_inertia_hz`),
    solved by scipy's ``least_squares`` (trust region, finite-difference Jacobian) from the uniform chain
    (r = 1/N, κ = 1) in the logarithms of the frequency ratios; then one unknown, the axial springs' multiplier α,
    from the first axial mode with B fixed and the end mass plus ``tip_mass_kg`` at C against the bar fixed with a
    tip mass (:func:`~twin.structure.closed_forms.axial_fixed_mass_hz`): the chain's axial mode scales as √α, so
    α = (f_exact / f_chain)² in one step. Bending and axial motion are uncoupled in the linearization, so the two
    fits are independent. ValueError if N < 4 (three bending modes need three elastic hinges) or if the fit leaves
    a bending mode more than 0.1 % off."""
    from scipy.optimize import least_squares

    from twin.structure.closed_forms import axial_fixed_mass_hz, bending_pinned_end_inertia_hz

    N, M, L = segments, axial_groups, split.length_m
    if N < 4:
        raise ValueError(f"the tuned chain needs at least 4 segments (three elastic hinges), got {N}")
    mu = split.bar_mass_kg / L
    target = np.log(bending_pinned_end_inertia_hz(ei_nm2, mu, L, split.end_inertia_kgm2, 3))

    def resid(p: np.ndarray) -> np.ndarray:
        tu = ChainTuning(float(p[0]), float(np.exp(p[1])), float(np.exp(p[2])), 1.0)
        f = modes(_chain(split, ea_n, ei_nm2, N, M, tu), "mechanism").of_kind("bending")[:3]
        return np.log(f) - target

    lo = 0.25 / N
    hi = 0.5 - 0.25 / N if N > 2 else 0.5
    sol = least_squares(resid, [1.0 / N, 0.0, 0.0], bounds=([lo, -3.0, -3.0], [hi, 3.0, 3.0]),
                        xtol=1e-14, ftol=1e-14, gtol=1e-14)
    if np.max(np.abs(sol.fun)) > 1e-3:
        raise ValueError(f"the tuned chain with {N} segments misses a bending mode by {np.max(np.abs(sol.fun)):.2%}")
    tu = ChainTuning(float(sol.x[0]), float(np.exp(sol.x[1])), float(np.exp(sol.x[2])), 1.0)
    fa = modes(_chain(split, ea_n, ei_nm2, N, M, tu), "mechanism", tip_mass_kg).of_kind("axial")[0]
    fa_exact = axial_fixed_mass_hz(ea_n, mu, L, split.end_c_kg + tip_mass_kg, 1)[0]
    return dataclasses.replace(tu, k_axial=float((fa_exact / fa) ** 2))


# ------------------------------------------------------------------------------------------ linearization
def linear_matrices(chain: RodChain, tip_mass_kg: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass, stiffness and damping matrices of the chain linearized about the straight rod at rest, in the
    coordinates [x_B, y_B, φ, q_1 … q_J]: the translation and rotation of ``end_B`` (the rod's rigid-body
    motion) then the joints' coordinates in :attr:`RodChain.joints` order (MuJoCo's qpos order for the
    rod's joints). ``tip_mass_kg`` adds a point mass moving with the axial motion of C (the slider).

    Body b's small displacement: u_x = x_B + Σ slides up to b; u_y(x) = y_B + φ x + Σ hinges h up to b of
    q_h (x − x_h); its rotation ψ = φ + Σ hinges up to b. T = ½ Σ m (u̇_x² + u̇_y(x_G)²) + I ψ̇²."""
    nq = 3 + chain.n_joints
    M = np.zeros((nq, nq))
    K = np.zeros((nq, nq))
    C = np.zeros((nq, nq))
    for b, body in enumerate(chain.bodies):
        jx, jy, jp = _body_jacobians(chain, b, body.com_x_m)
        M += body.mass_kg * (np.outer(jx, jx) + np.outer(jy, jy)) + body.inertia_kgm2 * np.outer(jp, jp)
    if tip_mass_kg:
        jx, _, _ = _body_jacobians(chain, len(chain.bodies) - 1, chain.length_m)
        M += tip_mass_kg * np.outer(jx, jx)
    for i, j in enumerate(chain.joints):
        K[3 + i, 3 + i] = j.stiffness
        C[3 + i, 3 + i] = j.damping
    return M, K, C


def _body_jacobians(chain: RodChain, body: int, x: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows mapping the linearized coordinates to (u_x, u_y at rod abscissa x, ψ) of ``body``."""
    nq = 3 + chain.n_joints
    jx, jy, jp = np.zeros(nq), np.zeros(nq), np.zeros(nq)
    jx[0], jy[1], jy[2], jp[2] = 1.0, 1.0, x, 1.0
    for i, j in enumerate(chain.joints):
        if j.child > body:
            break
        if j.kind == "slide":
            jx[3 + i] = 1.0
        else:
            jy[3 + i] = x - j.x_m
            jp[3 + i] = 1.0
    return jx, jy, jp


def point_jacobians(chain: RodChain, x: float) -> tuple[np.ndarray, np.ndarray]:
    """Rows giving the linearized (u_x, u_y) of the rod's material point at abscissa x (on the axis)."""
    body = _body_at(chain, x)
    jx, jy, _ = _body_jacobians(chain, body, x)
    return jx, jy


def _body_at(chain: RodChain, x: float) -> int:
    """Index of the segment holding rod abscissa x (the end bodies hold x <= 0 and x >= L; a node belongs to the
    segment that starts there)."""
    if x <= 0.0:
        return 0
    if x >= chain.length_m:
        return len(chain.bodies) - 1
    n = len(chain.bodies) - 2
    starts = [b.x0_m for b in chain.bodies[1:-1]]
    return 1 + min(n - 1, int(np.searchsorted(starts, x, side="right")) - 1)


@dataclass(frozen=True)
class Modes:
    """Modes of the linearized chain under some boundary conditions."""

    frequencies_hz: np.ndarray   #: undamped natural frequencies, ascending [Hz]
    shapes: np.ndarray           #: mass-normalized shapes (columns) in the coordinates of :func:`linear_matrices`
    kinds: tuple[str, ...]       #: "axial" or "bending" per mode (where its kinetic energy is)
    damping_ratios: np.ndarray   #: modal damping ratios φᵀCφ / (2ω) (C is diagonal in modes for Rayleigh β
    #                               per decoupled family)

    def of_kind(self, kind: str) -> np.ndarray:
        """Frequencies [Hz] of the modes of ``kind``, ascending."""
        return self.frequencies_hz[[k == kind for k in self.kinds]]


def modes(chain: RodChain, boundary: str = "mechanism", tip_mass_kg: float = 0.0) -> Modes:
    """Modes of the linearized chain. ``boundary``: "mechanism" (B pinned: x_B = y_B = 0; C held normal to
    the rod, y_C = 0, free along it; the slider's mass ``tip_mass_kg`` moves with C along the rod: bending is
    pinned–pinned, axial is B fixed with a mass at C) or "free" (the rod alone; its three rigid-body modes
    are dropped)."""
    M, K, C = linear_matrices(chain, tip_mass_kg)
    if boundary == "mechanism":
        _, jy_c = point_jacobians(chain, chain.length_m)
        rows = np.zeros((3, M.shape[0]))
        rows[0, 0] = rows[1, 1] = 1.0
        rows[2] = jy_c
        T = null_space(rows)
        drop = 0
    elif boundary == "free":
        T = np.eye(M.shape[0])
        drop = 3
    else:
        raise ValueError(f"boundary must be 'mechanism' or 'free', got {boundary!r}")
    Mr, Kr, Cr = T.T @ M @ T, T.T @ K @ T, T.T @ C @ T
    w2, V = eigh(Kr, Mr)
    w2, V = w2[drop:], V[:, drop:]
    omega = np.sqrt(np.maximum(w2, 0.0))
    shapes = T @ V
    kinds = []
    for i in range(shapes.shape[1]):
        v = shapes[:, i]
        axial = sum(v[3 + k] ** 2 * chain.joints[k].stiffness for k in range(chain.n_joints)
                    if chain.joints[k].kind == "slide")
        total = sum(v[3 + k] ** 2 * chain.joints[k].stiffness for k in range(chain.n_joints))
        if boundary == "free" and total == 0.0:
            total = axial = 1.0
        kinds.append("axial" if axial > 0.5 * total else "bending")
    zeta = np.array([V[:, i] @ Cr @ V[:, i] / (2.0 * omega[i]) if omega[i] > 0 else 0.0 for i in range(len(omega))])
    return Modes(omega / (2.0 * math.pi), shapes, tuple(kinds), zeta)


def rod_chain(structure, rod, slider_mass_kg: float) -> RodChain:
    """The damped chain of a configuration: ``structure`` a :class:`~twin.config.structure.StructureConfig`,
    ``rod`` the rod's :class:`~twin.config.mechanism.BodyParams` (S003 Table 1), ``slider_mass_kg`` the
    slider's mass (the axial damping is set on the mode with the slider at C)."""
    split = rod_split(rod.mass_kg, rod.length_m, rod.x_g_m, rod.inertia_kgm2, structure.rod_end_inertia_kgm2)
    if structure.rod_chain == "tuned":
        try:
            tu = tuned_parameters(split, structure.rod_ea_n, structure.rod_ei_nm2, structure.rod_segments,
                                  structure.rod_axial_groups, slider_mass_kg)
        except ValueError as exc:
            raise ConfigError("structure.rod_chain", f"{exc}; use rod_chain = \"uniform\" or more segments") from None
        chain = _chain(split, structure.rod_ea_n, structure.rod_ei_nm2, structure.rod_segments,
                       structure.rod_axial_groups, tu)
    else:
        chain = undamped_chain(split, structure.rod_ea_n, structure.rod_ei_nm2, structure.rod_segments,
                               structure.rod_axial_groups)
    md = modes(chain, "mechanism", slider_mass_kg)
    w_b = 2.0 * math.pi * float(md.of_kind("bending")[0])
    w_a = 2.0 * math.pi * float(md.of_kind("axial")[0])
    return chain.with_damping(2.0 * structure.bending_damping_ratio / w_b, 2.0 * structure.axial_damping_ratio / w_a)


def highest_frequency_hz(chain: RodChain, tip_mass_kg: float = 0.0) -> float:
    """Highest natural frequency of the chain in the mechanism [Hz] (the explicit step's limit: ω h < 2)."""
    return float(modes(chain, "mechanism", tip_mass_kg).frequencies_hz[-1])
