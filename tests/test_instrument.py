"""Sensor chain (accelerometers, DAQ, encoder, command) and the static calibration (S003 Eq. 1-4)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import welch

from twin.config import ACCELEROMETERS, BenchConfig, ConfigError, Instrumentation
from twin.errors import RecordingError
from twin.instrument import (STANDARD_G, angle_to_counts, apply_calibration, apply_chain, calibrate_static,
                             calibration_pose_g, check_counts, counts_to_angle, measured_accel,
                             simulated_calibration, unwrap_counts)
from twin.instrument.accel import ACCEL_MODELS, accel_to_volts, response_gain_db
from twin.instrument.chain import static_recording
from twin.instrument.daq import lsb_v, quantize
from twin.run import Run

RATE = 100_000.0
COUNT = 2 * math.pi / 32768
OFFSETS = {"AC1": 2.513, "AC2": 2.488, "AC3": 2.506, "AC4": 2.471, "AC5": 2.522, "AC6": 2.494}


def _cfg(**inst) -> BenchConfig:
    return BenchConfig().replace(**{f"instrumentation.{k}": v for k, v in inst.items()})


def _truth(arrays: dict, cfg: BenchConfig, rate: float = RATE) -> Run:
    return Run.from_arrays(0.0, rate, arrays, cfg)


# ------------------------------------------------------------------- calibration
def test_calibration_pose_readings_per_orientation():
    assert calibration_pose_g(BenchConfig()) == {"AC1": 0, "AC2": 1, "AC3": 1, "AC4": 0, "AC5": 1, "AC6": 0}
    x_up = calibration_pose_g(BenchConfig().replace(**{"mechanism.orientation": "x"}))
    assert x_up == {"AC1": 1, "AC2": 0, "AC3": 0, "AC4": 1, "AC5": 0, "AC6": 1}
    assert set(calibration_pose_g(BenchConfig().replace(**{"mechanism.orientation": "z"})).values()) == {0.0}


def test_calibration_recovers_known_offsets_exactly_without_noise():
    cfg = _cfg(zero_g_v=OFFSETS, noise=False, quantization=False)
    cal = simulated_calibration(cfg, duration_s=0.05)
    # the twin's gravity in standard g (accelerations are stored as float32, like simulated ones)
    g_ratio = float(np.float32(cfg.mechanism.gravity_mps2)) / STANDARD_G
    for a in ACCELEROMETERS:
        s = ACCEL_MODELS[cfg.instrumentation.models[a]].sensitivity_v_per_g
        assert cal.sensitivity_v_per_g[a] == s
        # Eq. 1 is exact for 0 g sensors; Eq. 2 assumes +1 g exactly, so a +1 g sensor's offset
        # is off by S (g_local/g_standard - 1): 6.8 uV at 20 mV/g, as on a real bench
        expected = OFFSETS[a] + cal.expected_g[a] * s * (g_ratio - 1.0)
        assert cal.zero_g_v[a] == pytest.approx(expected, abs=1e-12)


def test_calibration_recovers_known_offsets_through_the_full_chain():
    cfg = _cfg(zero_g_v=OFFSETS, seed=3)
    cal = simulated_calibration(cfg, duration_s=0.5)
    for a in ACCELEROMETERS:
        # noise (~0.13-0.2 mV per sample) and 76 uV quantization average out over 50k samples;
        # the gravity bias above is at most 14 uV
        assert cal.zero_g_v[a] == pytest.approx(OFFSETS[a], abs=2e-5)
        assert 0.5e-4 < cal.std_v[a] < 3e-4  # the noise the static recording showed
    # Eq. 3-4 turn the static volts back into the pose's accelerations
    static = static_recording(cfg, 0.2)
    meas = measured_accel(static, cal)
    for a, e in calibration_pose_g(cfg).items():
        assert np.mean(meas[f"meas_{a}"]) == pytest.approx(e * STANDARD_G, abs=2e-3)


def test_apply_calibration_is_eq3_eq4():
    v = np.array([2.5, 2.52, 2.48])
    np.testing.assert_allclose(apply_calibration(v, 2.5, 0.02), [0.0, 1.0, -1.0])
    cal = calibrate_static({"AC1": np.full(10, 2.51), "AC2": np.full(10, 2.53)}, {"AC1": 0.02, "AC2": 0.02},
                           {"AC1": 0.0, "AC2": 1.0})
    assert cal.zero_g_v == pytest.approx({"AC1": 2.51, "AC2": 2.51})  # Eq. 1 and Eq. 2
    with pytest.raises(RecordingError, match="NaN"):
        calibrate_static({"AC1": np.array([2.5, np.nan])}, {"AC1": 0.02}, {"AC1": 0.0})


# --------------------------------------------------------------------- accelerometer
def test_noise_psd_matches_the_configured_density():
    cfg = _cfg(zero_g_v=OFFSETS, seed=11)
    n = 200_000
    truth = _truth({a: np.zeros(n) for a in ACCELEROMETERS}, cfg)
    daq = apply_chain(truth, cfg, command=False)
    for a in ("AC1", "AC5"):
        m = ACCEL_MODELS[cfg.instrumentation.models[a]]
        density_v = m.noise_g_rthz * m.sensitivity_v_per_g  # V/sqrt(Hz)
        f, p = welch(daq[f"volt_{a}"], fs=RATE, nperseg=4096)
        band = (f > 100) & (f < 45_000)
        # the 18-bit quantization adds LSB^2/12 spread over 0..fs/2: 3 % (AC1) of the noise power
        assert np.mean(p[band]) == pytest.approx(density_v**2, rel=0.10)
        assert np.sqrt(np.mean(p[band])) == pytest.approx(density_v, rel=0.05)
    # seeded: the same seed gives the same noise, another seed another one
    again = apply_chain(truth, cfg, command=False)
    np.testing.assert_array_equal(again["volt_AC1"], daq["volt_AC1"])
    other = apply_chain(truth, cfg.replace(**{"instrumentation.seed": 12}), command=False)
    assert not np.array_equal(other["volt_AC1"], daq["volt_AC1"])
    assert not np.array_equal(daq["volt_AC1"] - OFFSETS["AC1"], daq["volt_AC2"] - OFFSETS["AC2"])


def _sine_gain_db(f_hz: float, inst: Instrumentation, model: str = "ADXL1001") -> float:
    """Gain of the implemented chain for a sine, measured on its output after the transient."""
    n = 40_000
    t = np.arange(n) / RATE
    a = 5.0 * STANDARD_G * np.sin(2 * np.pi * f_hz * t)
    sensor = "AC1" if model == "ADXL1001" else "AC5"
    v = accel_to_volts(a, sensor, inst, RATE, None)
    s = ACCEL_MODELS[model].sensitivity_v_per_g
    y = (v[n // 2:] - inst.zero_g(sensor)) / s
    tt = t[n // 2:]
    # least-squares amplitude of the sine at f
    basis = np.stack([np.sin(2 * np.pi * f_hz * tt), np.cos(2 * np.pi * f_hz * tt)], axis=1)
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    return 20 * math.log10(math.hypot(*coef) / 5.0)


def test_response_3db_near_11khz_and_resonance():
    base = dict(noise=False, saturation=False)
    ds = Instrumentation(**base)  # datasheet response: the 3 dB point is a gain (resonance at 21 kHz, Q 10)
    assert abs(_sine_gain_db(100.0, ds)) < 0.01
    assert abs(_sine_gain_db(1000.0, ds)) < 0.05
    assert _sine_gain_db(11_000.0, ds) == pytest.approx(2.76, abs=0.1)  # analog pole pair: +2.76 dB
    assert _sine_gain_db(21_000.0, ds) == pytest.approx(20.0, abs=0.5)   # Q = 10 peak
    f = np.linspace(8_000, 15_000, 7001)
    g = response_gain_db(f, ACCEL_MODELS["ADXL1001"], ds, RATE)
    assert f[np.argmax(g >= 3.0)] == pytest.approx(11_000, rel=0.05)    # +3 dB crossing near 11 kHz
    lp = Instrumentation(response="lowpass", **base)  # -3 dB at 11 kHz (S003's reading)
    assert _sine_gain_db(11_000.0, lp, "ADXL1002") == pytest.approx(-3.0, abs=0.1)
    assert abs(_sine_gain_db(1000.0, lp, "ADXL1002")) < 0.1
    g = response_gain_db(f, ACCEL_MODELS["ADXL1002"], lp, RATE)
    assert f[np.argmax(g <= -3.0)] == pytest.approx(11_000, rel=0.01)
    off = Instrumentation(response="off", **base)
    assert abs(_sine_gain_db(21_000.0, off)) < 1e-6
    with pytest.raises(ConfigError, match="Nyquist"):
        accel_to_volts(np.zeros(10), "AC1", ds, 30_000.0, None)


def test_range_saturation_and_output_rails():
    n = 20_000
    t = np.arange(n) / RATE
    inst = Instrumentation(noise=False, response="off")
    big = 150 * STANDARD_G * np.sin(2 * np.pi * 50 * t)
    v1 = accel_to_volts(big, "AC1", inst, RATE, None)  # ADXL1001: +-100 g at 20 mV/g
    assert v1.max() == pytest.approx(2.5 + 2.0) and v1.min() == pytest.approx(2.5 - 2.0)
    v5 = accel_to_volts(big, "AC5", inst, RATE, None)  # ADXL1002: +-50 g at 40 mV/g
    assert v5.max() == pytest.approx(4.5) and v5.min() == pytest.approx(0.5)
    assert np.mean(np.isclose(v5, 4.5)) > 0.3  # clipped over most of each half period
    # a 3.3 V supply: mid-supply 1.65 V, 100 g would need 3.65 V; the rails clip at 0.2 / 3.1 V
    low = Instrumentation(noise=False, response="off", supply_v=3.3)
    v = accel_to_volts(big, "AC1", low, RATE, None)
    assert v.max() == pytest.approx(3.1) and v.min() == pytest.approx(0.2)
    # saturation off: linear beyond the range
    lin = accel_to_volts(big, "AC1", Instrumentation(noise=False, response="off", saturation=False), RATE, None)
    assert lin.max() == pytest.approx(2.5 + 150 * 0.02, rel=1e-6)


def test_quantization_18_bit_over_the_range():
    inst = Instrumentation()
    q = lsb_v(inst)
    assert q == pytest.approx(20.0 / 2**18)  # 76.3 uV over +-10 V
    v = np.random.default_rng(0).uniform(-9.9, 9.9, 100_000)
    r = quantize(v, inst)
    codes = (r + 10.0) / q
    np.testing.assert_allclose(codes, np.round(codes), atol=1e-6)  # on the ADC grid
    assert np.max(np.abs(r - v)) <= q / 2 + 1e-12
    assert np.std(r - v) == pytest.approx(q / math.sqrt(12), rel=0.02)
    # range clipping at the end codes
    assert quantize(np.array([12.0, -12.0]), inst).tolist() == [10.0 - q, -10.0]
    five = Instrumentation(daq_range="0-5")
    assert quantize(np.array([5.7, -0.3]), five).tolist() == [5.0 - lsb_v(five), 0.0]
    assert lsb_v(five) == pytest.approx(5.0 / 2**18)


def test_daq_decimation_aliases_without_the_anti_alias_filter():
    # a run at 200 kHz sampled by the DAQ at 100 kHz: a 70 kHz vibration folds to 30 kHz
    rate = 200_000.0
    n = 40_000
    t = np.arange(n) / rate
    a = {s: np.zeros(n) for s in ACCELEROMETERS}
    a["AC1"] = 2 * STANDARD_G * np.sin(2 * np.pi * 70_000 * t)
    common = {"response": "off", "noise": False, "quantization": False}
    raw = apply_chain(_truth(a, _cfg(**common), rate), command=False)
    aa = apply_chain(_truth(a, _cfg(anti_alias=True, anti_alias_hz=20_000.0, **common), rate), command=False)
    assert raw.rate_hz == RATE and raw.n == n // 2
    from twin.signals import hann_spectrum

    for run, lo, hi in ((raw, 0.035, 0.045), (aa, 0.0, 0.004)):
        f, amp = hann_spectrum(run["volt_AC1"][2000:], RATE, remove_mean=True)
        peak = amp[np.argmin(abs(f - 30_000))]
        assert lo <= peak <= hi  # 2 g at 20 mV/g = 40 mV aliased; 4th-order 20 kHz filter: < 1/10
    with pytest.raises(ConfigError, match="daq_rate_hz"):
        apply_chain(_truth(a, _cfg(**common), 150_000.0), command=False)


def test_all_stages_off_is_the_ideal_transducer():
    cfg = _cfg(zero_g_v=OFFSETS, response="off", noise=False, saturation=False, quantization=False,
               encoder_quantization=False)
    n = 1000
    rng = np.random.default_rng(5)
    arrays = {s: rng.normal(0, 50, n) for s in ACCELEROMETERS}
    arrays["encoder_angle"] = np.linspace(0.0, 3.0, n)
    daq = apply_chain(_truth(arrays, cfg), command=False)
    for s in ACCELEROMETERS:
        sens = ACCEL_MODELS[cfg.instrumentation.models[s]].sensitivity_v_per_g
        a32 = arrays[s].astype(np.float32).astype(np.float64)  # accelerations are float32 channels
        np.testing.assert_allclose(daq[f"volt_{s}"], OFFSETS[s] + sens * a32 / STANDARD_G, rtol=0, atol=1e-12)
    np.testing.assert_allclose(daq["encoder_counts"], arrays["encoder_angle"] / COUNT, rtol=1e-12)


def test_motor_command_voltage():
    cfg = BenchConfig().replace(**{"drive.motor_rpm": 750.0, "simulation.duration_s": 0.01})
    n = 1000
    truth = _truth({"encoder_angle": np.zeros(n)}, cfg)
    daq = apply_chain(truth, cfg)
    v = daq["motor_command"]
    assert daq.channels["motor_command"].unit == "V"
    np.testing.assert_allclose(v, 7.5, atol=lsb_v(cfg.instrumentation))  # 750 rpm -> 7.5 V (+-10 V <-> +-1000 rpm)


# --------------------------------------------------------------------------- encoder
def test_encoder_counting_over_many_turns_and_direction_changes():
    t = np.arange(600_000) / RATE
    # 6 s: a drift of 6 rad/s with a +-15 rad/s swing: 12 reversals, ~40 turns travelled in all,
    # at most 21 rad/s (1.1 counts per sample, like the fastest bench speed)
    phi = 6.0 * t + 7.0 * np.sin(2 * np.pi * 0.35 * t) + 0.3
    c = angle_to_counts(phi, 32768)
    np.testing.assert_array_equal(c, np.floor(phi / COUNT))
    assert np.max(np.abs(np.diff(c))) <= 2  # < 1.2 counts of motion per sample here
    back = counts_to_angle(c, 32768)
    assert np.max(np.abs(back - phi)) <= COUNT / 2 + 1e-12  # the count centre is within half a count
    assert abs(np.mean(back - phi)) < 0.02 * COUNT  # unbiased
    # position-based: the same angle reached moving forward and backward gives the same count
    k_fwd = int(np.argmax(phi > 10.0))  # first pass through 10 rad, moving forward
    moving_back = np.flatnonzero((np.diff(phi) < 0) & (np.abs(phi[:-1] - phi[k_fwd]) < COUNT / 4))
    assert moving_back.size > 0
    k_bwd = int(moving_back[0])
    assert abs(c[k_bwd] - c[k_fwd]) <= 1
    # counters that wrap: a 16-bit register and a per-turn counter unwrap to the same counts
    for modulus in (2**16, 32768):
        wrapped = np.mod(c, modulus)
        assert wrapped.max() < modulus
        np.testing.assert_array_equal(unwrap_counts(wrapped, modulus) - wrapped[0] + c[0], c)
    # the sensor chain counts the simulated encoder angle the same way
    cfg = BenchConfig()
    daq = apply_chain(_truth({"encoder_angle": phi[:5000]}, cfg), command=False)
    np.testing.assert_array_equal(daq["encoder_counts"], c[:5000])


def test_encoder_glitches_repaired_or_refused():
    c = np.floor(np.linspace(0, 2000, 2001))
    bad = c.copy()
    bad[700:702] += 9000  # a 2-sample electrical glitch
    bad[1500] = -3  # a one-sample dropout to a wrong value
    fixed, rep = check_counts(bad, RATE, max_step=3.0)
    np.testing.assert_array_equal(fixed, c)
    assert rep.repaired == [(700, 701), (1500, 1500)]
    assert "2-sample glitch of +9001 counts at sample 700" in rep.messages[0]
    with pytest.raises(RecordingError, match="repair disabled"):
        check_counts(bad, RATE, max_step=3.0, repair=False)
    step = c.copy()
    step[900:] += 500  # lost counts: never returns
    with pytest.raises(RecordingError, match=r"jumps by \+501 counts at sample 900 .*cannot repair"):
        check_counts(step, RATE, max_step=3.0)
