"""Test 3's engine gap in AC5's 10 kHz band: what the band holds, and which engine's content is physical.

Follows ``analysis/structure_closure.py`` (MuJoCo's gap grows as its loop closure at the ideal C is made stiffer).
Table 4 test 3, ``structure.mode = "flexible"``, 0.6 s from rest, bands over t >= 0.2 s, AC5 (the slider's
accelerometer across the guide) unless said. Experiments, each a controlled change of one thing:

1. *Storage precision.* The accelerometer channels are float32 (the run format). The band carries ~1e-7 m/s² rms
   against the slider's 18 m/s² peak, so float32 rounding (half an ulp, ~1e-6 m/s² at 16-32 m/s²) is within a few
   dB of it: the same runs with the channels kept in float64 (this script patches the channel specs; the engines
   compute in float64 throughout), and the rounding's own band energy (float32 minus float64) re the band.
2. *The reference's convergence*: float64, output at every step (no decimation), steps 1e-5 ... 6.25e-7 s, each
   against 6.25e-7 s.
3. *MuJoCo at a fixed closure time constant, the step refined*: float64, output every step, against the
   reference at the same step.
4. *Output decimation*: the default 100 kHz output takes every k-th step's instantaneous value (k = 1e-5 / h);
   content above 50 kHz folds into the band. The same run at 100 kHz and at every step.
5. *The mount*: the body's acceleration before the 12 kHz mount filter (the filter bypassed), every step.
6. *When the band's content occurs*: AC5 band-passed to the 10 kHz band (8.9-11.2 kHz, 6th-order Butterworth,
   zero phase), rms per 12.5 ms for the reference and for MuJoCo minus the reference, float64, every step; the
   share of the difference's energy in the reference's bursts (bins where its rms exceeds 10x its median).
7. *The z row of MuJoCo's 3-D ``connect``*: its Jacobian row and force in the planar model.
8. *What MuJoCo's floor follows*: MuJoCo alone (τ = 1e-5 s, step 1.25e-6 s, float64, every step) for
   ``--long`` s (default 2.4): the band-passed AC5's floor (median of its 5 ms rms in each 50 ms) against the crank
   angle and speed, as built and with MuJoCo's two unbounded hinge angles (``crank_hinge`` and ``rod_hinge``, the
   rod's angle relative to the crank, ≈ −θ) wrapped by multiples of 2π at every chunk boundary (0.05 s chunks;
   the PID's reference offset by the crank's turns: the same physics, hinge kinematics being 2π-periodic; a
   diagnostic patch of the engine's ``advance`` here, not an option of the twin). A floor set by the rounding of
   an unbounded angle steps up where the angle crosses a power of two (its ulp doubles there).

Writes ``analysis/results/structure/closure_floor.md`` with the versions and the commit.
Run: ``python analysis/structure_closure_floor.py`` (about 30 runs of 0.6 s; a few minutes).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
from pathlib import Path

import numpy as np

from twin.provenance import git_commit, write_stamped_text

DUR, SKIP = 0.6, 0.2


@contextlib.contextmanager
def _float64_accel(on: bool):
    """The accelerometer channels kept in float64 (the run format stores them as float32)."""
    import twin.channels as C

    old = C._STATIC["accel"]
    if on:
        C._STATIC["accel"] = [dataclasses.replace(s, dtype="float64") for s in old]
    try:
        yield
    finally:
        C._STATIC["accel"] = old


@contextlib.contextmanager
def _mount_bypassed(on: bool):
    """The mount filter made the identity: the channels are the bodies' accelerations at the mounting points."""
    import twin.structure.mount as M

    old = M.MountFilter.process
    if on:
        M.MountFilter.process = lambda self, x: np.asarray(x, dtype=np.float64).copy()
    try:
        yield
    finally:
        M.MountFilter.process = old


def run(engine: str, h: float, every_step: bool, f64: bool = True, raw: bool = False, over: dict | None = None,
        names=("AC3", "AC5")):
    import twin
    from twin.config import preset

    cfg = preset(3).replace(**{"structure.mode": "flexible", "simulation.duration_s": DUR, "simulation.engine": engine,
                               "simulation.timestep_s": h, "sensors.output_rate_hz": 1.0 / h if every_step else 1e5,
                               **(over or {})})
    with _float64_accel(f64), _mount_bypassed(raw):
        r = twin.simulate(cfg)
    i0 = int(round(SKIP * r.rate_hz))
    return {a: np.asarray(r[a], dtype=np.float64)[i0:] for a in names}, r.rate_hz


def energies(sig, rate, centres=None):
    """Band energies per unit time (``band_energies`` scales with the sample rate; this removes it, so runs at
    different rates compare)."""
    from twin.structure.bands import band_energies

    return {a: band_energies(x, rate, centres) / rate for a, x in sig.items()}


def db(a, b):
    return 10.0 * np.log10(a / b)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" / "structure" /
                                         "closure_floor.md"))
    ap.add_argument("--long", type=float, default=2.4, help="duration of experiment 8 [s]")
    args = ap.parse_args()
    import mujoco
    from scipy.signal import butter, sosfiltfilt

    import twin
    from twin.structure.bands import third_octave_centres

    tau = lambda t: {"mujoco.equality_solref": (t, 1.0)}   # noqa: E731
    L = []

    def out(s=""):
        L.append(s)
        print(s, flush=True)

    # 1. storage precision, default step
    out("## 1. Storage precision (default step 1e-5 s, MuJoCo's default closure)")
    out("")
    out("| channels | AC5 10 kHz [dB] | AC3 10 kHz [dB] |")
    out("|---|---:|---:|")
    sig = {}
    for f64 in (False, True):
        m, rate = run("mujoco", 1e-5, True, f64)
        r, _ = run("reference", 1e-5, True, f64)
        sig[f64] = (m, r)
        em, er = energies(m, rate), energies(r, rate)
        out(f"| {'float64' if f64 else 'float32 (the run format)'} | {db(em['AC5'], er['AC5'])[-1]:+.2f} | "
            f"{db(em['AC3'], er['AC3'])[-1]:+.2f} |")
    for k, eng in ((0, "MuJoCo"), (1, "reference")):
        x32, x64 = sig[False][k]["AC5"], sig[True][k]["AC5"]
        e = energies({"d": x32 - x64, "s": x64}, rate)
        out(f"\n{eng}: float32 rounding of AC5 in the 10 kHz band: {db(e['d'], e['s'])[-1]:+.1f} dB re the band "
            f"(max |float32 - float64| {np.abs(x32 - x64).max():.2e} m/s², signal max {np.abs(x64).max():.1f})")
    out("")

    # 2. the reference's convergence
    out("## 2. The reference's step convergence (float64, output every step), against 6.25e-7 s")
    out("")
    out("| step [s] | AC5 10 kHz [dB] | AC5 largest | AC3 10 kHz [dB] | AC3 largest |")
    out("|---|---:|---:|---:|---:|")
    steps = (1e-5, 5e-6, 2.5e-6, 1.25e-6, 6.25e-7)
    ref = {h: energies(*run("reference", h, True)) for h in steps}
    cen = third_octave_centres()
    for h in steps[:-1]:
        cells = []
        for a in ("AC5", "AC3"):
            d = db(ref[h][a], ref[steps[-1]][a])
            i = int(np.argmax(np.abs(d)))
            cells += [f"{d[-1]:+.2f}", f"{abs(d[i]):.2f} ({cen[i]:.0f} Hz)"]
        out(f"| {h:g} | " + " | ".join(cells) + " |")
    out("")

    # 3. MuJoCo at a fixed closure, the step refined
    out("## 3. MuJoCo against the reference at the same step (float64, output every step)")
    out("")
    out("| closure τ [s] | step [s] | AC5 10 kHz [dB] | AC3 10 kHz [dB] | largest over AC3, AC5 |")
    out("|---|---|---:|---:|---:|")
    for t, hs in ((2e-5, steps), (1e-5, (2.5e-6, 1.25e-6, 6.25e-7)), (5e-6, (1.25e-6,)), (1e-4, (1e-5, 1.25e-6))):
        for h in hs:
            m = energies(*run("mujoco", h, True, over=tau(t)))
            d5, d3 = db(m["AC5"], ref[h]["AC5"]), db(m["AC3"], ref[h]["AC3"])
            w = max(np.abs(d5).max(), np.abs(d3).max())
            out(f"| {t:g}{' (default)' if t == 2e-5 else ''} | {h:g} | {d5[-1]:+.2f} | {d3[-1]:+.2f} | {w:.2f} |")
    out("")

    # 4. decimation, 5. mount
    out("## 4-5. Output decimation and the mount (τ = 5e-6 s, step 1.25e-6 s, float64)")
    out("")
    h = 1.25e-6
    wide = third_octave_centres(100.0, 200000.0)
    r_full = run("reference", h, True)
    m_full = run("mujoco", h, True, over=tau(5e-6))
    r_dec = run("reference", h, False)
    m_dec = run("mujoco", h, False, over=tau(5e-6))
    r_raw = run("reference", h, True, raw=True)
    m_raw = run("mujoco", h, True, raw=True, over=tau(5e-6))
    out(f"AC5 10 kHz band, MuJoCo over the reference: output at 100 kHz (every 8th step) "
        f"{db(energies(*m_dec)['AC5'], energies(*r_dec)['AC5'])[-1]:+.2f} dB; output every step "
        f"{db(energies(*m_full)['AC5'], energies(*r_full)['AC5'])[-1]:+.2f} dB; before the mount, every step "
        f"{db(energies(*m_raw)['AC5'], energies(*r_raw)['AC5'])[-1]:+.2f} dB.")
    out("")
    er, em = energies(*r_raw, centres=wide)["AC5"], energies(*m_raw, centres=wide)["AC5"]
    out("Before the mount, every step, third-octave bands from 6.3 kHz: MuJoCo over the reference [dB]:")
    out("")
    sel = [i for i, c in enumerate(wide) if c > 6000]
    out("| " + " | ".join(f"{wide[i] / 1000:.1f} kHz" for i in sel) + " |")
    out("|" + "---:|" * len(sel))
    out("| " + " | ".join(f"{db(em[i], er[i]):+.2f}" for i in sel) + " |")
    out("")

    # 6. when the content occurs
    out("## 6. When the 10 kHz band's content occurs (AC5, float64, every step)")
    out("")
    out("| τ [s] | step [s] | rms ref / MuJoCo [m/s²] | MuJoCo − ref rms | correlation | difference's energy in "
        "the reference's bursts | rms per 12.5 ms, ×1e-9 m/s²: reference / (MuJoCo − reference) |")
    out("|---|---|---:|---:|---:|---:|---|")
    for t, h in ((2e-5, 1e-5), (2e-5, 1.25e-6), (1e-5, 1.25e-6)):
        (r, rate), (m, _) = run("reference", h, True), run("mujoco", h, True, over=tau(t))
        sos = butter(6, [cen[-1] * 10 ** (-1 / 20), cen[-1] * 10 ** (1 / 20)], btype="band", fs=rate, output="sos")
        br, bm = sosfiltfilt(sos, r["AC5"]), sosfiltfilt(sos, m["AC5"])
        d = bm - br
        n = int(round(0.0125 * rate))
        nb = len(br) // n
        rb = np.array([br[i * n:(i + 1) * n].std() for i in range(nb)])
        dbins = np.array([d[i * n:(i + 1) * n].std() for i in range(nb)])
        burst = rb > 10 * np.median(rb)
        share = (dbins[burst] ** 2).sum() / (dbins ** 2).sum()
        prof = " ".join(f"{1e9 * a:.0f}/{1e9 * b:.0f}" for a, b in zip(rb, dbins))
        out(f"| {t:g} | {h:g} | {br.std():.2e} / {bm.std():.2e} | {d.std():.2e} | {np.corrcoef(br, bm)[0, 1]:.2f} | "
            f"{100 * share:.0f} % ({burst.sum()} of {nb} bins) | {prof} |")
    out("")

    # 7. the connect's z row
    from twin.config import preset
    from twin.mujoco_engine.builder import build

    _, model, _ = build(preset(3).replace(**{"structure.mode": "flexible"}))
    data = mujoco.MjData(model)
    zrow = []
    for _ in range(2000):
        mujoco.mj_step(model, data)
        J = data.efc_J.reshape(data.nefc, model.nv)
        zrow.append((np.abs(J[2]).max(), abs(data.efc_force[2])))
    out("## 7. The connect's z row")
    out("")
    out(f"Over 2000 default steps of test 3: max |J| of the z row {max(z[0] for z in zrow):.1e}, max |force| "
        f"{max(z[1] for z in zrow):.1e} N (rows: {data.nefc}, the equality's x, y, z).")

    # 8. the floor against the crank angle (MuJoCo alone)
    import twin as _t

    import math

    from twin import names
    from twin.mujoco_engine.engine import MujocoEngine

    def floors(wrap: bool):
        cfg = preset(3).replace(**{"structure.mode": "flexible", "simulation.duration_s": args.long,
                                   "simulation.engine": "mujoco", "simulation.timestep_s": 1.25e-6,
                                   "sensors.output_rate_hz": 1 / 1.25e-6, "simulation.chunk_s": 0.05, **tau(1e-5)})
        orig = MujocoEngine.advance

        def advance(self, theta_ref, omega_ref, stride):
            m, d = self.model, self.data
            a = m.jnt_qposadr[m.joint(names.CRANK_HINGE).id]
            k = round(d.qpos[a] / (2 * math.pi))
            d.qpos[a] -= 2 * math.pi * k
            self._turns = getattr(self, "_turns", 0.0) + 2 * math.pi * k
            ar = m.jnt_qposadr[m.joint(names.ROD_HINGE).id]
            d.qpos[ar] -= 2 * math.pi * round(d.qpos[ar] / (2 * math.pi))
            return orig(self, np.asarray(theta_ref) - self._turns, omega_ref, stride)

        if wrap:
            MujocoEngine.advance = advance
        try:
            with _float64_accel(True):
                r = _t.simulate(cfg)
        finally:
            MujocoEngine.advance = orig
        rate = r.rate_hz
        x, w = (np.asarray(r[c], dtype=np.float64) for c in ("AC5", "crank_speed"))
        sos = butter(6, [cen[-1] * 10 ** (-1 / 20), cen[-1] * 10 ** (1 / 20)], btype="band", fs=rate, output="sos")
        b = sosfiltfilt(sos, x)
        n = int(round(0.05 * rate))
        # the crank angle integrated from its speed (with the wrap the channel is wrapped too)
        th = np.concatenate([[0.0], np.cumsum(w[:-1]) / rate]) + (np.asarray(r["crank_angle"])[0])
        rows = []
        for i in range(2, len(b) // n):
            seg = b[i * n:(i + 1) * n]
            sub = np.array([seg[j * n // 10:(j + 1) * n // 10].std() for j in range(10)])
            rows.append((i * n / rate, th[i * n], w[i * n], np.median(sub)))
        return rows

    built, wrapped = floors(False), floors(True)
    out("")
    out(f"## 8. MuJoCo's floor against the crank angle (τ = 1e-5 s, step 1.25e-6 s, {args.long:g} s)")
    out("")
    out("| t [s] | crank angle [rad] | crank speed [rad/s] | AC5 10 kHz band floor [m/s² rms], as built | "
        "both hinge angles wrapped |")
    out("|---:|---:|---:|---:|---:|")
    for (t, th, w, f), (_, _, _, g) in zip(built, wrapped):
        out(f"| {t:.2f} | {th:.1f} | {w:.1f} | {f:.1e} | {g:.1e} |")

    commit = git_commit()
    head = (f"twin {twin.__version__}, MuJoCo {mujoco.__version__}, commit {commit or '?'}; Table 4 test 3 (ideal "
            f"joints), structure.mode = flexible (default [structure]); {DUR:g} s from rest, bands over t >= {SKIP:g} "
            f"s; dB = 10 log10(E_mujoco / E_reference) unless said.")
    text = "\n".join([head, ""] + L) + "\n"
    p = write_stamped_text(args.out, text)
    print(f"wrote {p}")


if __name__ == "__main__":
    main()
