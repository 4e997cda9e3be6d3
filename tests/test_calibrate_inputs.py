"""Bad calibration inputs refused in one line naming the field, before any simulation (no recording needed)."""

from __future__ import annotations

import json

import pytest

from twin.calibration import make_parameters, parse_bounds
from twin.calibration.search import LOG_FORMAT, LOG_VERSION, LogError, read_log
from twin.config import BenchConfig
from twin.errors import ConfigError


def _refused(call, field: str, words: str) -> None:
    with pytest.raises(ConfigError) as err:
        call()
    assert err.value.field == field and words in str(err.value) and "\n" not in str(err.value), str(err.value)


def test_integer_fields_and_sections_are_not_fitted():
    flexible = BenchConfig().replace(**{"structure.mode": "flexible"})
    # a count: the search's real values (4.37 segments) would be refused by the configuration mid-run
    _refused(lambda: make_parameters(["structure.rod_segments"], flexible, {"structure.rod_segments": (4, 8)}),
             "params", "integer field")
    _refused(lambda: make_parameters(["mujoco.iterations"], BenchConfig(), {"mujoco.iterations": (5, 50)}),
             "params", "integer field")
    # a section: named as such, not printed whole
    _refused(lambda: make_parameters(["contact"], BenchConfig()), "params", "is a section")
    # a real-valued field still is fitted
    assert make_parameters(["contact.mu0"], BenchConfig())[0].field == "contact.mu0"


def test_a_field_bounded_twice_is_refused():
    _refused(lambda: parse_bounds(["contact.mu0=0:0.2", "contact.mu0=0:0.3"]), "bounds", "given twice")
    assert parse_bounds(["contact.mu0=0:0.2", "contact.restitution=0.1:0.9"]) == {
        "contact.mu0": (0.0, 0.2), "contact.restitution": (0.1, 0.9)}


@pytest.mark.parametrize("old_version", [1, None])
def test_an_older_log_is_refused_naming_its_version(tmp_path, old_version):
    header = {"format": LOG_FORMAT, "version": LOG_VERSION, "parameters": [{"field": "contact.mu0"}]}
    old = dict(header)
    if old_version is None:
        old.pop("version")  # the first version's logs had no version key
    else:
        old["version"] = old_version
    path = tmp_path / "evaluations.jsonl"
    path.write_text(json.dumps(old) + "\n", encoding="utf-8")
    before = path.read_bytes()
    with pytest.raises(LogError) as err:
        read_log(path, header, 1)
    msg = str(err.value)
    assert err.value.field == "log" and "\n" not in msg and f"resumes version {LOG_VERSION}" in msg
    assert path.read_bytes() == before


@pytest.mark.parametrize("overrides", [
    {"drive.crank_rpm": 200.0},
    {"drive.mode": "torque", "drivetrain.torque_s": (0.02,), "drivetrain.torque_nm": (1.0,)},
], ids=["crank_rpm", "torque"])
def test_the_replay_configuration_of_other_valid_drive_settings_builds(overrides):
    """A recording's configuration with the crank's own speed or the torque drive: the calibration's trace-driven
    configuration (as twin replay's) is valid; before, the configuration refused its own trace program."""
    from types import SimpleNamespace

    from twin.calibration.objective import sim_config
    from twin.config import preset

    target = SimpleNamespace(drive="trace", n_sim=1000, rate=100000.0, zero_g={}, motor=False)
    cfg = sim_config(target, preset(12).replace(**overrides))
    assert cfg.drive.program == "trace" and cfg.drive.crank_rpm == 0.0 and cfg.drive.mode == "pid"


def test_restarts_flag_reaches_the_options_and_a_bad_value_names_it(tmp_path, capsys):
    """``--restarts`` is the options' ``restarts``: a negative count is refused in one line naming the flag,
    before any recording is read or anything written."""
    from twin.cli import main

    out = tmp_path / "out"
    rc = main(["calibrate", str(tmp_path / "missing.mcap"), "--params", "contact.mu0", "--restarts", "-1",
               "--out", str(out), "--no-plots", "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert rc != 0 and "--restarts" in err and len(err.splitlines()) == 1, err
    assert not out.exists()
