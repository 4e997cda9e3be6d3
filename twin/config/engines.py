"""The engines and their run settings: the one list of engine names (and the class that
implements each, imported on demand by :func:`twin.simulation.make_engine`), the MuJoCo twin's solver
and contact settings, and the run settings shared by both engines."""

from __future__ import annotations

import math
from dataclasses import dataclass

from twin.config.common import XML_DEFAULTS, _check, _choice, check_types

#: Engine name -> "module:class" of its implementation (imported on demand: the reference engine
#: pulls in numba). The one list of engines: :data:`ENGINES` and the simulator read it.
ENGINE_CLASSES: dict[str, str] = {
    "mujoco": "twin.mujoco_engine.engine:MujocoEngine",
    "reference": "twin.reference.engine:ReferenceEngine",
}
#: Engines that speak this configuration.
ENGINES: tuple[str, ...] = tuple(ENGINE_CLASSES)


# --------------------------------------------------------------------------- mujoco
@dataclass(frozen=True)
class MujocoSettings:
    """Solver and contact settings of the MuJoCo twin.

    Attributes:
        integrator: MuJoCo integrator ("Euler", "implicitfast", "implicit", "RK4").
            Default: mjcf/bench.xml (``<option>``, with the reasons there), as are solver,
            iterations and tolerance.
        solver: constraint solver ("Newton", "CG", "PGS") of the rigid structure
            (``structure.mode = "rigid"``).
        flexible_solver: constraint solver ("PGS", default, "Newton", "CG") with
            ``structure.mode = "flexible"``. PGS works in the constraint rows (two contact rows, or
            the loop closure's three), Newton in the flexible model's 14 degrees of freedom: PGS
            cuts test 12's flexible step by about a quarter, converges within the same tolerance
            well below the iteration cap and agrees with the reference engine as Newton does
            (docs/structure-mujoco.md, "Cost"; ``analysis/mujoco_flexible_pgs.py``).
        iterations: maximum solver iterations.
        tolerance: solver tolerance (0 disables the early exit).
        contact_solref: pin/bushing ``solref`` (2 numbers): raw MuJoCo values of a soft contact
            that replaces the native law when given with ``contact_solimp``; empty = the
            ``contact_source``.
        contact_solimp: pin/bushing ``solimp`` (5 numbers); empty = the ``contact_source``.
        equality_solref: ``solref`` of the loop-closure ``connect`` at an ideal joint C.
            Default: mjcf/bench.xml (the ``joint_C`` connect), as is equality_solimp.
        equality_solimp: ``solimp`` of that connect.
        guide_solreffriction: ``solreffriction`` of the guide's dry friction (frictionloss).
            Default: mjcf/bench.xml (the slide joint).
        guide_friction: the slider guide's friction (``mechanism.guide_friction_n``): "native"
            (default): the reference engine's law, F ramp(|v|) against the slider's velocity
            with the ramp of ``contact.v0_mps``/``v1_mps``, a passive force of the native module
            (MuJoCo's frictionloss constraint holds the slider at its reversals where
            the reference's friction vanishes, and shifted the 0.5-5 kHz band energy of the
            250 rpm tests by 4-6 dB); "frictionloss": MuJoCo's dry-friction constraint
            (``frictionloss`` with ``guide_solreffriction``), the base model's.
        bushing: representation of a bushing bore: "bore" (native pin-in-bore collider, exact
            circle; the default, chosen by ``analysis/bushing_representations.py``), "ring"
            (``ring_boxes`` boxes whose faces form a regular polygon tangent to the bore) or
            "tendon" (pin-bushing distance limited to c: exact, frictionless).
        ring_boxes: number of boxes of the "ring" representation.
        friction: clearance-joint friction: "native" (the reference's regularized Coulomb law
            as a passive force, default; bore only) or "cone" (MuJoCo's elliptic friction
            cone, μ0; bore or ring). A tendon bushing is frictionless whatever this says.
        contact_source: "law" (default): the bore bushing's contact force is the reference's
            own law (``contact.law``: Lankarani–Nikravesh K δⁿ (1 + χ δ̇/v_imp) with its stored
            impact speed and floor, Hunt–Crossley, Flores or linear; same K, n, e), applied
            exactly by the native module (``_bore.c``); ring and tendon bushings,
            which the module does not serve, take the first guess. "force": the same law and
            friction as a native passive force between pin and bore, explicit at the step's start as
            in the reference engine's symplectic Euler, with no collision, contact row or solver
            work (the pin/bushing pair is removed; bore bushing only; docs/speed.md). "first-guess": MuJoCo's own
            soft contact, the linear spring-damper with the LN law's duration and restitution
            at 0.1 m/s (``twin.contact_params.first_guess_contact``). ``contact_solref``/``solimp`` override
            both. (Stored configurations with the retired "calibration" read as "law", and their
            retired ``contact_damping`` is dropped.)
        contact_stiffness_scale: factor on the twin's contact stiffness (the law's K, or the
            soft contact's k) [-]; 1 = the reference's. For sensitivity and stress studies.
        contact_damping_scale: factor on the twin's contact damping (the law's χ or linear c,
            or the soft contact's c) [-].
        impact_damping_gain: factor on χ of a hysteresis law [-] (1 = the reference's law).
        accelerometers: how the AC1..AC6 channels are computed: "posthoc" (default) from the
            recorded state after each rollout (qacc_k = (qvel_{k+1} − qvel_k)/h, exact to
            round-off with the Euler integrator, and the planar kinematics of the compiled chain:
            ``twin.mujoco_engine.accel``), or "sensor": MuJoCo's ``<accelerometer>`` sensors,
            which make every step run ``mj_rnePostConstraint``. Same readings to round-off
            (``tests/test_posthoc_accel.py``). "posthoc" needs the Euler integrator: with another
            integrator the run takes the sensors (``meta["accelerometers"]`` says which).
            Measured side by side (``analysis/bench_mujoco.py --repeats 5``, all channels at
            100 kHz, µs per step sensor → posthoc, the readings' cost included): ideal (test 3)
            2.19 → 1.95, C only (test 6) 2.75 → 2.57, B+C (test 12) 3.47 → 3.25 (6-12 % less; a
            whole 4 s run of test 12 spends 1.41-1.58 s in the engine instead of 1.92-2.10 s);
            README "Where a step goes".
    """

    integrator: str = XML_DEFAULTS.integrator
    solver: str = XML_DEFAULTS.solver
    flexible_solver: str = "PGS"
    iterations: int = XML_DEFAULTS.iterations
    tolerance: float = XML_DEFAULTS.tolerance
    contact_solref: tuple[float, ...] = ()
    contact_solimp: tuple[float, ...] = ()
    equality_solref: tuple[float, ...] = XML_DEFAULTS.equality_solref
    equality_solimp: tuple[float, ...] = XML_DEFAULTS.equality_solimp
    guide_solreffriction: tuple[float, ...] = XML_DEFAULTS.guide_solreffriction
    guide_friction: str = "native"
    bushing: str = "bore"
    ring_boxes: int = 48
    friction: str = "native"
    contact_source: str = "law"
    contact_stiffness_scale: float = 1.0
    contact_damping_scale: float = 1.0
    impact_damping_gain: float = 1.0
    accelerometers: str = "posthoc"

    def __post_init__(self) -> None:

        check_types(self)
        _choice(self.accelerometers, "accelerometers", ("sensor", "posthoc"))
        for name in ("contact_stiffness_scale", "contact_damping_scale"):
            v = getattr(self, name)
            _check(isinstance(v, (int, float)) and 0.01 <= v <= 100, name, f"must lie in [0.01, 100], got {v!r}")
        _choice(self.integrator, "integrator", ("Euler", "implicitfast", "implicit", "RK4"))
        _choice(self.bushing, "bushing", ("bore", "ring", "tendon"))
        _check(isinstance(self.ring_boxes, int) and 8 <= self.ring_boxes <= 512, "ring_boxes",
               f"must be an integer in [8, 512], got {self.ring_boxes!r}")
        _choice(self.friction, "friction", ("native", "cone"))
        _choice(self.contact_source, "contact_source", ("law", "force", "first-guess"))
        _choice(self.guide_friction, "guide_friction", ("native", "frictionloss"))
        _check(self.contact_source != "force" or self.integrator != "RK4", "integrator",
               "contact_source = \"force\" needs one force evaluation per step: Euler, implicitfast or implicit, not RK4")
        _check(isinstance(self.impact_damping_gain, (int, float)) and 0.1 <= self.impact_damping_gain <= 10,
               "impact_damping_gain", f"must lie in [0.1, 10], got {self.impact_damping_gain!r}")
        _check(self.bushing == "bore" or self.friction == "cone" or self.bushing == "tendon", "friction",
               "a ring bushing takes MuJoCo's friction cone: set friction = \"cone\" (native friction needs the bore)")
        _choice(self.solver, "solver", ("Newton", "CG", "PGS"))
        _choice(self.flexible_solver, "flexible_solver", ("PGS", "Newton", "CG"))
        _check(isinstance(self.iterations, int) and 1 <= self.iterations <= 1000,
               "iterations", f"must be an integer in [1, 1000], got {self.iterations!r}")
        _check(isinstance(self.tolerance, (int, float)) and 0 <= self.tolerance < 1,
               "tolerance", f"must lie in [0, 1), got {self.tolerance!r}")
        for name, n in (("contact_solref", 2), ("contact_solimp", 5)):
            v = getattr(self, name)
            _check(len(v) in (0, n), name, f"must hold {n} numbers or be empty (contact_source), got {list(v)!r}")
        for name in ("contact_solref", "contact_solimp", "equality_solref", "equality_solimp", "guide_solreffriction"):
            v = getattr(self, name)
            _check(all(math.isfinite(x) for x in v), name, f"must hold finite numbers, got {list(v)!r}")
        for name, n in (("equality_solref", 2), ("equality_solimp", 5), ("guide_solreffriction", 2)):
            v = getattr(self, name)
            _check(len(v) == n, name, f"must hold {n} numbers, got {list(v)!r}")


# ----------------------------------------------------------------------- simulation
@dataclass(frozen=True)
class Simulation:
    """Run settings shared by both engines.

    Attributes:
        engine: "mujoco" (the twin) or "reference" (R-matrix, Lankarani–Nikravesh).
        duration_s: simulated time [s]; 0 = the protocol's length (38 s for the paper's) with
            ``drive.program = "protocol"``, the trace's length with ``drive.program = "trace"``
            (filled in by the run when it reads the trace: the configuration never reads files).
            The other programs need a duration > 0.
        timestep_s: integration step [s]. Default: mjcf/bench.xml (source S003 §4.3, matching
            the 100 kHz logging). It must divide the output period ``1/sensors.output_rate_hz``
            (an integer number of steps per output sample): a step that does not divide
            1/100 kHz needs the output rate set explicitly.
        chunk_s: simulated time per chunk streamed to the sinks [s] (memory per chunk grows
            with it; the result does not depend on it).
    """

    engine: str = "mujoco"
    duration_s: float = 2.0
    timestep_s: float = XML_DEFAULTS.timestep_s
    chunk_s: float = 0.5

    def __post_init__(self) -> None:

        check_types(self)
        _choice(self.engine, "engine", ENGINES)
        _check(isinstance(self.duration_s, (int, float)) and 0 <= self.duration_s <= 3600,
               "duration_s", f"must lie in [0, 3600] s (0 = the protocol's or the trace's length), got "
                               f"{self.duration_s!r}")
        _check(isinstance(self.timestep_s, (int, float)) and 1e-7 <= self.timestep_s <= 1e-3,
               "timestep_s", f"must lie in [1e-7, 1e-3] s, got {self.timestep_s!r}")
        _check(isinstance(self.chunk_s, (int, float)) and math.isfinite(self.chunk_s) and 1e-3 <= self.chunk_s <= 10,
               "chunk_s", f"must lie in [0.001, 10] s, got {self.chunk_s!r}")
