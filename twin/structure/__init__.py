"""The bench's structure, engine-free (numpy/scipy): the flexible rod's discrete model, its closed-form
checks, structural damping, the compliant supports and the accelerometers' mounts. Both engines build
``structure.mode = "flexible"`` from here, so they integrate the same discrete model.

Interface (what the engines use; SI units; configuration :class:`twin.config.structure.StructureConfig`):

``rod_chain(cfg.structure, cfg.bodies.rod, cfg.bodies.slider.mass_kg) -> RodChain``
    The damped chain in the rod frame (origin B, x towards C along the straight rod, y normal in the
    plane). ``chain.bodies``: ``end_B``, ``seg_1`` … ``seg_N``, ``end_C`` (:class:`ChainBody`: x0_m, x1_m,
    mass_kg, com_x_m on the axis, inertia_kgm2 about the centre of mass). ``chain.joints`` in coordinate
    order (:class:`ChainJoint`: kind "hinge"/"slide", child body index, x_m, stiffness, damping): body
    ``child`` is attached to body ``child − 1`` at x_m; at a node with a hinge and a slide the hinge comes
    first, the slide runs along the child's x axis. Joint force −k q − c q̇ (MuJoCo: ``stiffness``,
    ``damping`` of the joint, springref 0). ``end_B`` is the rod's root (it holds the bore at B and the
    rod's rigid-body motion), ``end_C`` holds the bore at C. The rod's accelerometers sit on the segment
    holding their abscissa (:func:`twin.structure.rod._body_at`; x ≤ 0 → end_B, x ≥ L → end_C).
``rod_split(m, L, x_G, I_G, J_e) -> RodSplit``
    Table 1's rod as bar + end masses with the mass, centre of mass and inertia kept exactly.
``linear_matrices(chain, tip_mass_kg) -> (M, K, C)`` and ``modes(chain, boundary, tip_mass_kg) -> Modes``
    The linearized chain in [x_B, y_B, φ, joints…] (MuJoCo's qpos order for the rod), and its modes
    ("mechanism": B pinned, C held normal to the rod with the slider's mass along it; "free").
``closed_forms``: Euler–Bernoulli pinned–pinned bending (with end rotary inertia), the axial bar fixed with a
    tip mass and free with end masses: the independent basis of the modal checks.
``MountFilter(f, ζ, sample_rate)``: ``process(samples × sensors)`` applies the accelerometer mount (exact
    discretization); both engines filter their sampled accelerations with it.
Supports (frame at A: mass on an isotropic spring in the plane; guide: mass on a spring normal to the guide,
    the slider riding on it): k = ``StructureConfig.support_stiffness(m, f)``, c = ``support_damping(m, f, ζ)``.
``checks.check_structure(cfg)``: the cross-field checks (stability of the step, mount below Nyquist).
"""

from twin.structure.closed_forms import (axial_fixed_mass_hz, axial_free_masses_hz, bending_pinned_end_inertia_hz,
                                         bending_pinned_hz)
from twin.structure.mount import MountFilter, mount_coefficients
from twin.structure.rod import (ChainBody, ChainJoint, ChainTuning, Modes, RodChain, RodSplit, highest_frequency_hz,
                                linear_matrices, modes, point_jacobians, rod_chain, rod_split, tuned_parameters,
                                undamped_chain)

__all__ = [
    "ChainBody", "ChainJoint", "ChainTuning", "Modes", "MountFilter", "RodChain", "RodSplit", "axial_fixed_mass_hz",
    "axial_free_masses_hz", "bending_pinned_end_inertia_hz", "bending_pinned_hz", "highest_frequency_hz",
    "linear_matrices", "modes", "mount_coefficients", "point_jacobians", "rod_chain", "rod_split", "tuned_parameters",
    "undamped_chain",
]
