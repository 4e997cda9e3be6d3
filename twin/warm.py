"""Warm starts: one engine run shared by runs that differ only downstream of the engine, and runs
continued from a saved state.

What a run's engine computes depends on its whole configuration except the fields only the sensor
chain reads (:data:`CHAIN_ONLY_FIELDS`: the noise seed, the accelerometers' models, offsets and noise,
the DAQ, the encoder's counting) and its name. :func:`mechanical_key` is that identity. Two ways to
pay a spin-up once:

* **Shared runs** (:func:`simulate_shared`, :func:`share_groups`): configurations with the same
  mechanical key have the same engine run, bit for bit (the repeats of a dataset's design point differ
  only in their noise seed). One engine run feeds each configuration's sinks (each its own sensor
  chain, seed and file), so a group of R repeats costs one engine run plus R sensor chains and
  writers. Exact: every file is the bytes its run alone writes. ``twin dataset generate`` does this by
  default (``--no-warm-start`` runs every run alone).
* **Saved states** (:func:`spin_up`, :class:`WarmState`): the full state of a run at a sample
  boundary, for the calibration's many continuations of one spin-up. MuJoCo: ``mj_getState`` with
  ``mjSTATE_INTEGRATION`` (time, qpos, qvel, act, the controls, the solver warmstart and the user data
  that hold the contact law's stored impact speeds, the force source's previous velocities and the
  drive train's motor, belt and speed-controller state) and the step count; the reference engine:
  its state vector (coordinates, velocities, PID integral, contact events, guide), the drive train's
  state and the step count; and, if asked, the sensor chains' states (filter states, noise generator
  states, decimation phase). Continued in a new engine of the same mechanical configuration
  (``simulate(cfg, sinks, start=state)``) a run gives, from the state's time on, the same bits as the
  uninterrupted run (``tests/test_warm.py``). Refused for another configuration: a run whose varied
  physical parameter (a clearance, the speed) differs does not share its spin-up, and this module
  never pretends it does.

The key is the configuration's text: a recorded drive input (a "trace" program's encoder trace, a motor
command file) counts by its path, not its content, and recorded inputs handed over in memory
(``twin.tracefile.DriveInputs``) are not taken here: warm starts are for runs that read their drive
from the configuration alone, as a dataset's runs do.

State files (:meth:`WarmState.save`, :meth:`WarmState.load`) are NumPy ``.npz`` archives of plain
arrays and one JSON string, read with ``allow_pickle=False`` and checked on load (format, engine,
twin and MuJoCo versions, array names, shapes and finiteness).
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Sequence

import numpy as np

from twin.config import BenchConfig
from twin.errors import TwinError

#: format tag of a state file
FORMAT = "twin-warm-state/1"

#: ``instrumentation`` fields that only the sensor chain (:mod:`twin.instrument`) reads, never an engine
#: (``command_v_per_rpm`` is not one: the motor drive's set point is the command in volts). A field
#: added to the section later counts as mechanical until it is listed here; ``tests/test_warm.py``
#: checks that changing all of these leaves both engines' runs unchanged bit for bit.
CHAIN_ONLY_FIELDS = ("models", "supply_v", "zero_g_v", "rail_margin_v", "response", "resonance_q", "noise",
                     "noise_scale", "saturation", "daq_rate_hz", "daq_range", "adc_bits", "quantization",
                     "anti_alias", "anti_alias_hz", "anti_alias_order", "encoder_counts_per_rev",
                     "encoder_quantization", "seed")


class WarmStateError(TwinError):
    """A saved state cannot be used (unreadable, another format, version or configuration)."""


def mechanical_key(cfg: BenchConfig) -> str:
    """Identity of what ``cfg``'s engine computes: SHA-256 of its configuration without the name and
    the :data:`CHAIN_ONLY_FIELDS` (16 hex digits)."""
    d = tomllib.loads(cfg.to_toml())
    d.pop("name", None)
    inst = d.get("instrumentation", {})
    for f in CHAIN_ONLY_FIELDS:
        inst.pop(f, None)
    text = json.dumps(d, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def share_groups(cfgs: Sequence[BenchConfig]) -> list[list[int]]:
    """Indices of ``cfgs`` grouped by :func:`mechanical_key`, groups in the order of their first
    member, members in the given order."""
    groups: dict[str, list[int]] = {}
    for i, c in enumerate(cfgs):
        groups.setdefault(mechanical_key(c), []).append(i)
    return list(groups.values())


class _Member:
    """A shared run's chunks, as one member configuration's run: the chunk with its own
    configuration, the summary with its own name."""

    def __init__(self, cfg: BenchConfig, sinks: Iterable[Any]):
        self.cfg, self.sinks = cfg, list(sinks)

    def write(self, chunk) -> None:
        from twin.run import Run

        mine = chunk if chunk.config is self.cfg else Run(chunk.t0, chunk.rate_hz, chunk.channels, self.cfg, chunk.meta)
        for s in self.sinks:
            s.write(mine)


class _FanOut:
    """One sink of :func:`twin.simulation.simulate` that hands every chunk to each member's sinks."""

    def __init__(self, members: list[_Member]):
        self.members = members
        self.results: list[list[Any]] = []

    def write(self, chunk) -> None:
        for m in self.members:
            m.write(chunk)

    def close(self, meta: dict[str, Any], summary: dict[str, Any]) -> None:
        for m in self.members:
            mine = dict(summary, name=m.cfg.name) if "name" in summary else summary
            self.results.append([s.close(dict(meta), mine) for s in m.sinks])

    def abort(self) -> None:
        for m in self.members:
            for s in m.sinks:
                try:
                    s.abort()
                except Exception:  # noqa: BLE001 - every sink is aborted; the run's error matters
                    pass


def simulate_shared(cfgs: Sequence[BenchConfig], sinks: Sequence[Iterable[Any]], progress: bool = False,
                    start: "WarmState | None" = None):
    """One engine run shared by ``cfgs`` (all of one :func:`mechanical_key`): every chunk goes to each
    configuration's ``sinks`` (one iterable of sinks per configuration, in order) as that
    configuration's chunk. Returns the run's :class:`~twin.simulation.Outcome` (its summary carries
    the first configuration's name). Each sink sees exactly the chunks a run of its configuration
    alone would give it, so what it writes is the same bytes. On any error every sink is aborted."""
    from twin.simulation import simulate

    cfgs = list(cfgs)
    sinks = [list(s) for s in sinks]
    if not cfgs or len(sinks) != len(cfgs):
        raise ValueError(f"simulate_shared: {len(cfgs)} configurations and {len(sinks)} sink lists")
    keys = {mechanical_key(c) for c in cfgs}
    if len(keys) != 1:
        raise ValueError("simulate_shared: the configurations differ in what the engine computes "
                         f"({len(keys)} mechanical keys); group them with share_groups")
    fan = _FanOut([_Member(c, s) for c, s in zip(cfgs, sinks)])
    return simulate(cfgs[0], [fan], progress=progress, start=start)


# ---------------------------------------------------------------------------------------------- saved states
def _versions() -> dict[str, str]:
    import mujoco

    from twin import __version__

    return {"twin": __version__, "mujoco": mujoco.__version__}


@dataclass
class WarmState:
    """The full state of a run after ``samples`` output samples (see the module docstring).

    Attributes:
        key: :func:`mechanical_key` of the configuration that made it.
        engine: ``"mujoco"`` or ``"reference"``.
        samples: output samples done (the state is at t = samples / rate) [-].
        steps: integration steps done [-].
        arrays: the engine's state (MuJoCo: ``state``, the ``mjSTATE_INTEGRATION`` vector; reference:
            ``st``, ``P`` and, with a drive train, ``train_ds``, ``train_D``).
        chains: states of the sensor chains fed the spin-up (:meth:`ChainStream.get_state`), in order.
        info: rate [Hz], timestep [s], versions, the spin-up's wall time [s] and MuJoCo warnings.
    """

    key: str
    engine: str
    samples: int
    steps: int
    arrays: dict[str, np.ndarray]
    chains: list[dict[str, Any]] = field(default_factory=list)
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def t_s(self) -> float:
        """Time of the state [s]."""
        return self.samples / self.info["rate_hz"]

    def check(self, cfg: BenchConfig, what: str = "the saved state") -> None:
        """Refuse a configuration this state cannot continue (one line naming why)."""
        if mechanical_key(cfg) != self.key:
            raise WarmStateError(f"{what} is of another configuration (mechanical key {self.key}, {cfg.name!r} has "
                                 f"{mechanical_key(cfg)}): only runs that differ in the sensor chain or the name "
                                 "continue a saved state")
        if cfg.simulation.engine != self.engine:
            raise WarmStateError(f"{what} is of the {self.engine} engine; {cfg.name!r} runs {cfg.simulation.engine}")
        if self.samples > cfg.n_samples:
            raise WarmStateError(f"{what} is at sample {self.samples}, after the end of {cfg.name!r} "
                                 f"({cfg.n_samples} samples)")

    def restore_engine(self, engine: Any, cfg: BenchConfig) -> int:
        """Put ``engine`` (of ``cfg``) into this state; returns the output samples done
        (:func:`twin.simulation.run_chunks` calls this for ``start``)."""
        self.check(cfg)
        if getattr(engine, "name", None) != self.engine:
            raise WarmStateError(f"the saved state is of the {self.engine} engine, not {getattr(engine, 'name', '?')}")
        if self.engine == "mujoco":
            engine.restore((self.steps, self.arrays["state"]))
        else:
            engine.restore((self.steps, dict(self.arrays)))
        if self.steps != self.samples * cfg.output_stride:
            raise WarmStateError(f"the saved state's {self.steps} steps are not {self.samples} samples of "
                                 f"{cfg.output_stride} steps")
        engine.meta["warm_start"] = {"t_s": self.t_s, "samples": self.samples,
                                     "spin_up_warnings": dict(self.info.get("warnings") or {})}
        return self.samples

    def restore_chains(self, chains: Sequence[Any]) -> None:
        """Put new sensor chains (:class:`twin.instrument.chain.ChainStream`, in the spin-up's order)
        into the saved chains' states."""
        if len(chains) != len(self.chains):
            raise WarmStateError(f"the saved state holds {len(self.chains)} sensor chains, {len(chains)} given")
        for c, s in zip(chains, self.chains):
            c.set_state(s)

    # -- files
    def save(self, path: str | Path) -> Path:
        """Write the state to ``path`` (``.npz``: the arrays and one JSON string; a temporary file,
        then renamed)."""
        from twin.util import atomic_write_bytes

        meta = {"format": FORMAT, "key": self.key, "engine": self.engine, "samples": int(self.samples),
                "steps": int(self.steps), "chains": self.chains, "info": self.info, "arrays": sorted(self.arrays)}
        buf = io.BytesIO()
        np.savez(buf, meta=np.array(json.dumps(meta)), **{f"a_{k}": np.asarray(v, dtype=np.float64)
                                                          for k, v in self.arrays.items()})
        path = Path(path)
        atomic_write_bytes(path, buf.getvalue())
        return path

    @classmethod
    def load(cls, path: str | Path) -> "WarmState":
        """Read and check a state file written by :meth:`save` (one-line :class:`WarmStateError`
        naming the file and what is wrong)."""
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as z:
                files = {k: z[k] for k in z.files}
        except (OSError, ValueError, EOFError) as err:
            raise WarmStateError(f"{path}: not a readable state file ({str(err).splitlines()[0][:200] or type(err).__name__})") from None
        except Exception as err:  # noqa: BLE001 - zipfile.BadZipFile and the like
            raise WarmStateError(f"{path}: not a readable state file ({type(err).__name__})") from None
        if "meta" not in files or files["meta"].dtype.kind != "U" or files["meta"].shape != ():
            raise WarmStateError(f"{path}: not a state file (no 'meta' JSON string)")
        try:
            meta = json.loads(str(files["meta"]))
        except ValueError:
            raise WarmStateError(f"{path}: field 'meta' is not JSON") from None
        if not isinstance(meta, dict) or meta.get("format") != FORMAT:
            raise WarmStateError(f"{path}: field 'format' must be {FORMAT!r}, got "
                                 f"{meta.get('format') if isinstance(meta, dict) else meta!r}"[:300])
        if meta.get("engine") not in ("mujoco", "reference"):
            raise WarmStateError(f"{path}: field 'engine' must be 'mujoco' or 'reference', got {meta.get('engine')!r}")
        for k in ("samples", "steps"):
            if isinstance(meta.get(k), bool) or not isinstance(meta.get(k), int) or meta[k] < 0:
                raise WarmStateError(f"{path}: field {k!r} must be an integer >= 0, got {meta.get(k)!r}")
        if not isinstance(meta.get("key"), str) or not isinstance(meta.get("chains"), list) \
                or not isinstance(meta.get("info"), dict) or not isinstance(meta.get("arrays"), list):
            raise WarmStateError(f"{path}: fields 'key', 'chains', 'info', 'arrays' must be a string, a list, an "
                                 "object and a list")
        rate = meta["info"].get("rate_hz")
        if not isinstance(rate, (int, float)) or not math.isfinite(rate) or rate <= 0:
            raise WarmStateError(f"{path}: field 'info.rate_hz' must be a number > 0, got {rate!r}")
        versions = meta["info"].get("versions")
        if versions != _versions():
            raise WarmStateError(f"{path}: saved by {versions}, this is {_versions()}: a state continues only in "
                                 "the versions that made it (the physics may differ)")
        want = {f"a_{k}" for k in meta["arrays"]}
        have = set(files) - {"meta"}
        if have != want:
            raise WarmStateError(f"{path}: holds arrays {sorted(have)}, its 'arrays' field names {sorted(want)}")
        arrays = {}
        for k in meta["arrays"]:
            a = files[f"a_{k}"]
            if a.dtype != np.float64 or a.ndim != 1 or not np.all(np.isfinite(a)):
                raise WarmStateError(f"{path}: array {k!r} must be a finite 1-D float64 array")
            arrays[k] = a
        return cls(meta["key"], meta["engine"], meta["samples"], meta["steps"], arrays, meta["chains"], meta["info"])


def spin_up(cfg: BenchConfig, t_s: float, chains: Sequence[Any] = (), engine: Any = None) -> WarmState:
    """Run ``cfg`` from rest to ``t_s`` [s] (rounded to a whole output sample) and return its full
    state there; ``chains`` (sensor chains, :class:`twin.instrument.chain.ChainStream`) are fed the
    spin-up's chunks and their states kept too. Continue with
    ``twin.simulation.simulate(cfg2, sinks, start=state)`` for any ``cfg2`` of the same
    :func:`mechanical_key` (and :meth:`WarmState.restore_chains` for new chains)."""
    import time

    from twin.simulation import make_engine, run_chunks

    rate = cfg.output_rate_hz
    n0 = int(round(t_s * rate))
    if not (math.isfinite(t_s) and 0 < n0 <= cfg.n_samples):
        raise WarmStateError(f"must lie in (0, {cfg.duration_s:g}] s (the run's duration) and span at least one "
                             f"output sample, got {t_s!r}", field="t_s")
    engine = engine if engine is not None else make_engine(cfg)
    t0 = time.perf_counter()
    for chunk in run_chunks(cfg, engine, until=n0):
        for c in chains:
            c.process(chunk)
    k, arrays = engine.snapshot()
    if not isinstance(arrays, dict):
        arrays = {"state": arrays}
    info = {"rate_hz": rate, "timestep_s": cfg.simulation.timestep_s, "versions": _versions(),
            "wall_s": time.perf_counter() - t0, "warnings": dict(engine.meta.get("warnings") or {})}
    return WarmState(mechanical_key(cfg), engine.name, n0, int(k), {n: np.array(a, dtype=np.float64)
                                                                     for n, a in arrays.items()},
                     [c.get_state() for c in chains], info)
