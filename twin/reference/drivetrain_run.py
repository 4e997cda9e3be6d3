"""The drive train of a reference-engine run (``drive.mode`` "motor" or "torque"): the
parameters and state of :mod:`twin.reference.drivetrain`, the chunk call of
:func:`twin.reference.model.run_motor` and the drive train's channels."""

from __future__ import annotations

import numpy as np

from twin.natural_coordinates import initial_state as mechanism_state
from twin.reference import drivetrain as DT
from twin.reference import model as ref_model

_WARM = False


class ReferenceTrain:
    """The drive train of a :class:`twin.reference.engine.ReferenceEngine` run: parameters,
    state, the chunk call of :func:`twin.reference.model.run_motor` and its channels."""

    def __init__(self, cfg, inputs=None) -> None:
        self.cfg = cfg
        self.inputs = inputs  # recorded motor command in memory (twin.tracefile.DriveInputs), if any
        self.D = DT.build(cfg)
        self.ds = DT.initial_state()
        self._dbuf = np.empty((0, DT.N_DO))
        self._last: tuple[int, int, int] = (0, 0, 1)  # (first step, samples, stride) of the last chunk

    def describe(self) -> str:
        dt = self.cfg.drivetrain
        return (f"{self.cfg.drive.mode}: rotor {dt.rotor_inertia_kgm2:g} kg m^2, V-belt k {dt.stiffness_npm:.6g} N/m, "
                f"F_max {dt.max_pull_n:.6g} N, speed loop {dt.controller_rate_hz:g} Hz on {dt.encoder_counts} counts")

    def warm_up(self) -> float:
        """Compile or load the drive-train loop once per process; seconds spent."""
        global _WARM
        if _WARM:
            return 0.0
        import time

        t0 = time.perf_counter()
        P = ref_model.build_params(self.cfg)
        st = mechanism_state(self.cfg, 0.0)
        ref_model.run_motor(P, self.D.copy(), st, DT.initial_state(), np.zeros(1), 1, np.empty((1, ref_model.N_OUT)),
                    np.empty((1, DT.N_DO)), True)
        _WARM = True
        return time.perf_counter() - t0

    def reset(self) -> None:
        self.ds = DT.initial_state()

    def run(self, P, st, k0: int, omega_ref, stride: int, buf, n_out: int):
        from twin.motor_drive import motor_input

        nstep = len(omega_ref)
        if self._dbuf.shape[0] < n_out:
            self._dbuf = np.empty((n_out, DT.N_DO))
        sp = motor_input(self.cfg, k0, nstep, omega_ref, self.inputs)
        self._last = (k0, n_out, stride)
        return ref_model.run_motor(P, self.D, st, self.ds, sp, stride, buf, self._dbuf, True)

    def chunk_inputs(self, k0: int, omega_ref, stride: int, n_out: int):
        """(set points, sample buffer) of a chunk of ``len(omega_ref)`` steps from step ``k0`` (the flexible
        structure's loop, :mod:`twin.reference.flexible`, calls the drive train's hooks itself)."""
        from twin.motor_drive import motor_input

        if self._dbuf.shape[0] < n_out:
            self._dbuf = np.empty((n_out, DT.N_DO))
        self._last = (k0, n_out, stride)
        return motor_input(self.cfg, k0, len(omega_ref), omega_ref), self._dbuf

    def channels(self, n: int) -> dict[str, np.ndarray]:
        from twin.motor_drive import command_voltage

        groups = self.cfg.sensors.channels
        d = self._dbuf[:n]
        cols: dict[str, np.ndarray] = {}
        if "motor" in groups:
            k0, _, stride = self._last
            t = (k0 + stride * np.arange(n)) * self.cfg.simulation.timestep_s
            cols.update(motor_angle=d[:, DT.DO_PHI], motor_speed=d[:, DT.DO_OMEGA], motor_torque=d[:, DT.DO_TORQUE],
                        belt_torque=d[:, DT.DO_BELT_TORQUE], belt_slip=d[:, DT.DO_SLIP],
                        command_voltage=command_voltage(self.cfg, t, self.inputs))
        if "drive_energy" in groups:
            cols.update(motor_work=d[:, DT.DO_WORK], energy_mechanical=d[:, DT.DO_EMECH], energy_belt=d[:, DT.DO_EBELT],
                        diss_belt_damping=d[:, DT.DO_DDAMP], diss_belt_slip=d[:, DT.DO_DSLIP], diss_guide=d[:, DT.DO_DGUIDE],
                        diss_contact=d[:, DT.DO_DCONTACT])
        return {k: np.array(v) for k, v in cols.items()}
