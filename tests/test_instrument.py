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


# ------------------------------------------------------------------ streaming chain
# Independent basis: apply_chain on the whole run (its physics is tested above); a run fed to a
# ChainStream in chunks must give the same DAQ samples bit for bit, whatever the chunking.
from twin.instrument import ChainStream, daq_specs, meas_specs  # noqa: E402
from twin.instrument.accel import AccelStream  # noqa: E402
from twin.instrument.daq import DaqSampler, sample  # noqa: E402

STEPS = {"drive.program": "steps", "drive.steps_s": (0.0, 0.5002, 0.50085), "drive.steps_rpm": (750.0, 500.0, -250.0)}


def _pieces(n: int, chunking) -> list[tuple[int, int]]:
    """[start, stop) pieces of range(n): a fixed size, a list of sizes repeated, or 'random'."""
    if chunking == "random":
        cuts = np.sort(np.random.default_rng(n).choice(np.arange(1, n), size=min(40, n - 1), replace=False))
        edges = [0, *cuts.tolist(), n]
        return list(zip(edges[:-1], edges[1:]))
    sizes = chunking if isinstance(chunking, list) else [chunking]
    out, i, j = [], 0, 0
    while i < n:
        step = sizes[j % len(sizes)]
        out.append((i, min(n, i + step)))
        i, j = i + step, j + 1
    return out


def _stream(run: Run, cfg: BenchConfig, chunking, **kw) -> list[Run]:
    chain = ChainStream(cfg, run.rate_hz, **kw)
    return [chain.process(run.slice(a, b)) for a, b in _pieces(run.n, chunking)]


def _assert_same_bits(streamed: list[Run], whole: Run) -> None:
    joined = Run.concat(streamed)
    assert list(joined.channels) == list(whole.channels)
    assert joined.t0 == whole.t0 and joined.rate_hz == whole.rate_hz and joined.meta == whole.meta
    for name, c in whole.channels.items():
        s = joined.channels[name]
        assert (s.unit, s.group, s.data.dtype) == (c.unit, c.group, c.data.dtype), name
        assert s.data.tobytes() == c.data.tobytes(), name  # bit-identical, not just close
    # each chunk starts at the time of its first DAQ sample, on the whole run's time base
    i = 0
    for ch in streamed:
        assert ch.t0 == pytest.approx(whole.t0 + i / whole.rate_hz, abs=1e-12) and ch.rate_hz == whole.rate_hz
        i += ch.n
    assert i == whole.n


def _stream_truth(cfg: BenchConfig, rate: float, n: int, big: bool = False) -> Run:
    rng = np.random.default_rng(7)
    t = 0.5 + np.arange(n) / rate  # starts at 0.5 s; the motor command steps at 0.5002 and 0.50085 s
    amp = 150 * STANDARD_G if big else 3 * STANDARD_G  # 150 g: range saturation and rails
    arrays = {a: (amp * np.sin(2 * np.pi * (900 + 2500 * i) * t) + rng.normal(0, 20, n)).astype(np.float32)
              for i, a in enumerate(ACCELEROMETERS)}
    arrays["encoder_angle"] = 1.0 + 80.0 * (t - 0.5) + 0.01 * np.sin(2 * np.pi * 30 * t)
    return Run.from_arrays(0.5, rate, arrays, cfg)


STREAM_CASES = {
    "datasheet": ({}, RATE, False),
    "lowpass": ({"response": "lowpass"}, RATE, False),
    "anti_alias": ({"anti_alias": True, "anti_alias_hz": 20_000.0}, RATE, False),
    "saturation": ({"zero_g_v": OFFSETS}, RATE, True),
    "ideal": ({"response": "off", "noise": False, "saturation": False, "quantization": False,
               "encoder_quantization": False}, RATE, False),
    "2x_rate": ({"response": "lowpass"}, 2 * RATE, True),
    "2x_rate_anti_alias": ({"anti_alias": True, "anti_alias_hz": 30_000.0}, 2 * RATE, False),
    "3x_rate_anti_alias": ({"anti_alias": True, "seed": 9}, 3 * RATE, False),
}


@pytest.mark.parametrize("case", list(STREAM_CASES))
@pytest.mark.parametrize("chunking", [1, 7, 64, [1, 7, 3, 0, 250, 2], "random", 10**6])
def test_streamed_chain_is_bit_identical_to_the_whole_run(case, chunking):
    inst, rate, big = STREAM_CASES[case]
    cfg = _cfg(**inst).replace(**STEPS)
    n = 301 if chunking == 1 else 2001  # odd lengths: the last DAQ sample is the run's last sample
    truth = _stream_truth(cfg, rate, n, big)
    whole = apply_chain(truth, cfg, prefix="sim_", stream=2)
    assert whole.n == (n + int(rate / RATE) - 1) // int(rate / RATE)
    assert len(np.unique(whole["sim_motor_command"])) == 3  # the command steps twice inside the run
    if big and cfg.instrumentation.saturation:  # both clippings are exercised
        off = cfg.instrumentation.zero_g("AC1")  # AC1 range: +-100 g at 20 mV/g = +-2 V, plus noise
        assert np.max(np.abs(whole["sim_volt_AC1"] - off)) == pytest.approx(2.0, abs=2e-3)
        rail = cfg.instrumentation.supply_v - cfg.instrumentation.rail_margin_v
        if cfg.instrumentation.zero_g("AC5") + 2.0 > rail:  # AC5: +-50 g at 40 mV/g beyond the rail
            assert np.max(whole["sim_volt_AC5"]) == quantize(np.array([rail]), cfg.instrumentation)[0]
    _assert_same_bits(_stream(truth, cfg, chunking, prefix="sim_", stream=2), whole)


def test_streamed_chain_on_a_simulated_run_streamed_by_simulate():
    """The use it is for: a sink putting simulate()'s chunks through the chain as they come."""
    from twin.config import preset
    from twin.simulation import Collector, simulate

    from conftest import short

    # DAQ at half the output rate (k = 2) and chunks of 127 samples (odd: the decimation phase alternates)
    cfg = short(preset(12), 0.02, **{"simulation.chunk_s": 0.00127, "simulation.engine": "reference",
                                     "instrumentation.daq_rate_hz": 50_000.0, "instrumentation.response": "off",
                                     "instrumentation.anti_alias": True,
                                     "instrumentation.anti_alias_hz": 20_000.0})

    class ChainSink:
        def __init__(self):
            self.chain, self.out = None, []

        def write(self, chunk):
            self.chain = self.chain or ChainStream(cfg, chunk.rate_hz)
            self.out.append(self.chain.process(chunk))

        def close(self, meta, summary):
            pass

        def abort(self):
            pass

    keep, sink = Collector(), ChainSink()
    simulate(cfg, [keep, sink])
    assert len(sink.out) > 10 and {c.n for c in sink.out[:-1]} == {63, 64}
    whole = apply_chain(keep.run, cfg)
    assert [(s.name, s.unit, s.group, s.dtype) for s in daq_specs(cfg)] == \
        [(c.name, c.unit, c.group, str(c.data.dtype)) for c in whole.channels.values()]
    _assert_same_bits(sink.out, whole)
    # calibration is per sample: chunk by chunk gives the whole run's values bit for bit
    cal = simulated_calibration(cfg, 0.02)
    meas_whole = measured_accel(whole, cal)
    meas_chunks = Run.concat([measured_accel(c, cal) for c in sink.out])
    assert [(s.name, s.unit, s.group, s.dtype) for s in meas_specs()] == \
        [(c.name, c.unit, c.group, str(c.data.dtype)) for c in meas_whole.channels.values()]
    for name, c in meas_whole.channels.items():
        assert meas_chunks[name].tobytes() == c.data.tobytes()
    assert [c.t0 for c in sink.out] == [measured_accel(c, cal).t0 for c in sink.out]


@pytest.mark.parametrize("sizes", [[1] * 50, [7] * 20, [3, 0, 1, 96, 13, 1000]])
def test_generator_normal_draws_do_not_depend_on_the_batching(sizes):
    """The noise stage draws rng.normal(0, sigma, size) per chunk: sequential draws of any sizes
    must continue the one stream (numpy's Generator keeps no buffer between calls)."""
    sigma = 1.3e-4
    whole = np.random.default_rng([0, 2, 5]).normal(0.0, sigma, sum(sizes))
    rng = np.random.default_rng([0, 2, 5])
    parts = np.concatenate([rng.normal(0.0, sigma, s) for s in sizes])
    assert parts.tobytes() == whole.tobytes()


def test_stage_streams_match_their_whole_signal_functions():
    inst = Instrumentation(anti_alias=True, anti_alias_hz=30_000.0)
    x = np.random.default_rng(3).normal(0, 200, 999).astype(np.float32)
    whole = sample(accel_to_volts(x, "AC5", inst, 2 * RATE, np.random.default_rng(1)), 2 * RATE, inst)
    acc, daq = AccelStream("AC5", inst, 2 * RATE, np.random.default_rng(1)), DaqSampler(2 * RATE, inst)
    parts = [daq.process(acc.process(x[a:b])) for a, b in _pieces(x.size, [1, 7, 2, 33])]
    assert np.concatenate(parts).tobytes() == whole.tobytes() and daq.seen == x.size
    # the steady-state start is taken from the signal's first sample only: a constant input
    # gives a constant output from the first sample, in every chunk
    ideal = Instrumentation(noise=False, anti_alias=True)
    acc = AccelStream("AC1", ideal, RATE, None)
    out = np.concatenate([acc.process(np.full(s, 4 * STANDARD_G)) for s in (1, 5, 50)])
    np.testing.assert_allclose(out, 2.5 + 4 * 0.02, rtol=0, atol=1e-12)


def test_chain_stream_refuses_chunks_that_do_not_follow():
    cfg = _cfg()
    truth = _stream_truth(cfg, RATE, 100)
    chain = ChainStream(cfg, RATE)
    chain.process(truth.slice(0, 10))
    with pytest.raises(RecordingError, match="consecutive"):
        chain.process(truth.slice(20, 30))  # a gap
    with pytest.raises(RecordingError, match="carries"):
        chain.process(truth.slice(10, 20).select(["AC1", "encoder_angle"]))
    with pytest.raises(RecordingError, match="Hz"):
        chain.process(Run.from_arrays(truth.t0 + 10 / RATE, 2 * RATE, {a: truth[a][10:20] for a in truth.channels},
                                      cfg))
    assert chain.process(truth.slice(10, 100)).n == 90  # the refused chunks changed nothing
    with pytest.raises(RecordingError, match="no AC1"):
        ChainStream(cfg, RATE, command=False).process(Run.from_arrays(0.0, RATE, {"crank_speed": np.zeros(5)}, cfg))


def test_daq_specs_without_running_anything():
    cfg = BenchConfig()
    names = [s.name for s in daq_specs(cfg, prefix="sim_")]
    assert names == [f"sim_volt_{a}" for a in ACCELEROMETERS] + ["sim_encoder_counts", "sim_motor_command"]
    assert {(s.group, s.dtype) for s in daq_specs(cfg)} == {("daq", "float64")}
    assert [s.unit for s in daq_specs(cfg)] == ["V"] * 6 + ["count", "V"]
    only = daq_specs(cfg, command=False, inputs=["AC2", "encoder_angle"])
    assert [s.name for s in only] == ["volt_AC2", "encoder_counts"]
    no_accel = cfg.replace(**{"sensors.channels": ("encoder", "crank")})
    assert [s.name for s in daq_specs(no_accel)] == ["encoder_counts", "motor_command"]
    # the specs are what apply_chain makes
    truth = _stream_truth(cfg, RATE, 50).select(["AC2", "encoder_angle"])
    run = apply_chain(truth, cfg, command=False)
    assert [(s.name, s.unit, s.group, s.dtype) for s in only] == \
        [(c.name, c.unit, c.group, str(c.data.dtype)) for c in run.channels.values()]
    assert [s.name for s in meas_specs("sim_", ["AC3", "AC1"])] == ["sim_meas_AC1", "sim_meas_AC3"]
