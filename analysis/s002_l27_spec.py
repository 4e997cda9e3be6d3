"""Write the S002 L27 study specs (``analysis/datasets/s002_l27.toml`` for the MuJoCo twin,
``s002_l27_reference.toml`` for the reference engine) from the paper's design.

Method: the 27 runs of S002's Taguchi L27 in run order (``twin.studies.taguchi.s002_design``: the
standard L27(3^13) array, crank length in column 1, clearance in 2, friction in 5, speed in 8, the
levels of S002 §2.1) as a list design over the ``s002`` preset. One run sets: the crank length and,
with it, the crank's placeholder mass distribution (centre of mass at mid-length, I_G = m r²/12 of a
uniform bar); S002's clearance c = r_B − r_j (Eq. 1, radial) at A, B and C, i.e. 2c diametral in the
configuration; μ0; the crank speed. Run: ``python analysis/s002_l27_spec.py``; then
``twin study taguchi s002_l27 --out DIR`` (the specs ship with twin, named).
"""

from __future__ import annotations

from pathlib import Path

from twin.config import named_preset
from twin.studies.taguchi import s002_design

HERE = Path(__file__).resolve().parent / "datasets"
DURATION_S = 0.5
SETTLE_S = 0.1


def spec_text(engine: str) -> str:
    d = s002_design()
    m = named_preset("s002").bodies.crank.mass_kg
    lines = [
        "# S002's Taguchi L27 (crank length x clearance x friction x speed), simulated: written by",
        "# analysis/s002_l27_spec.py (the method is in its docstring). The responses are the paper's: the",
        "# slider's maximum acceleration and the maximum contact force in the revolute clearance joint A.",
        f"# `twin study taguchi {'s002_l27' if engine == 'mujoco' else 's002_l27_reference'} --out DIR`",
        "[dataset]",
        f'name = "s002-l27{"" if engine == "mujoco" else "-reference"}"',
        "seed = 2",
        'description = "S002 Taguchi L27 in run order"',
        "",
        "[base]",
        'preset = "s002"',
        f'engine = "{engine}"',
        f"duration_s = {DURATION_S}  # PLACEHOLDER run length: 6.7 turns at 800 rpm, 10 at 1200 rpm",
        "",
        "[design]",
        'kind = "list"',
        "",
    ]
    for i in range(27):
        r = float(d["crank_length"][i]) / 1000.0
        c = float(d["clearance"][i])
        lines += ["[[design.points]]  # run %d" % (i + 1),
                  f'"bodies.crank.length_m" = {r!r}',
                  f'"bodies.crank.x_g_m" = {r / 2!r}',
                  f'"bodies.crank.inertia_kgm2" = {m * r * r / 12!r}',
                  f'"joints.clearance_a_mm" = {2 * c!r}',
                  f'"joints.clearance_b_mm" = {2 * c!r}',
                  f'"joints.clearance_c_mm" = {2 * c!r}',
                  f'"contact.mu0" = {float(d["friction"][i])!r}',
                  f"crank_rpm = {float(d['speed'][i])!r}", ""]
    lines += [
        "[factors]",
        '"bodies.crank.length_m" = { range = [0.08, 0.12] }',
        '"bodies.crank.x_g_m" = { range = [0.04, 0.06] }',
        '"bodies.crank.inertia_kgm2" = { range = [3e-4, 9e-4] }',
        '"joints.clearance_a_mm" = { range = [0.2, 1.4] }',
        '"joints.clearance_b_mm" = { range = [0.2, 1.4] }',
        '"joints.clearance_c_mm" = { range = [0.2, 1.4] }',
        '"contact.mu0" = { range = [0.01, 0.1] }',
        "crank_rpm = { range = [800.0, 1200.0] }",
        "",
        "[outputs]",
        'truth = ["crank", "slider", "slider_accel", "joints"]',
        "instrumented = false",
        "rate_hz = 100000.0",
        "",
        "[taguchi]",
        "# the analysis factors (the other varied fields follow them), named as S002's",
        'factors = { crank_length_m = "bodies.crank.length_m", clearance_a_mm = "joints.clearance_a_mm", '
        'mu0 = "contact.mu0", crank_rpm = "crank_rpm" }',
        'responses = ["max_slider_accel", "max_force_A"]',
        f"settle_s = {SETTLE_S}  # responses over t >= 0.1 s: the start at speed from centred joints excluded",
        'sn = "smaller"',
        "",
    ]
    return "\n".join(lines)


def main() -> None:
    for engine, name in (("mujoco", "s002_l27.toml"), ("reference", "s002_l27_reference.toml")):
        (HERE / name).write_text(spec_text(engine), encoding="utf-8")
        print("wrote", HERE / name)


if __name__ == "__main__":
    main()
