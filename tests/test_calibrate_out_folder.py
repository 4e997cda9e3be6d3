"""``twin calibrate --out DIR`` beside its inputs: an input that is one of the files a calibration writes there is
refused in one line before any work (before, the calibration ran to its end and was then refused at the last
write, its log already written into the folder); any other file in the folder, the recording included, is left
as it was (a calibration writes only its own names there)."""

from __future__ import annotations

import pytest

from twin.calibration.calibrate import OUTPUT_FILES
from twin.cli import main


@pytest.mark.parametrize("which", ["config", "recording"])
def test_an_input_the_calibration_would_write_over_is_refused_first(tmp_path, capsys, which):
    out = tmp_path / "cal"
    out.mkdir()
    base = out / "calibrated.toml"  # the last calibration's result, as the next one's base
    base.write_text("[contact]\nrestitution = 0.5\n")
    rec = out / "report.json"  # a recording under an output's name (any content: refused before it is read)
    rec.write_bytes(b"not read")
    argv = ["calibrate", str(rec) if which == "recording" else "sample:test6", "--params", "contact.restitution",
            "--out", str(out), "--no-plots", "--no-progress"]
    if which == "config":
        argv += ["--config", str(base)]
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("twin: error: --out: ") and "written over the input" in err, err
    assert ("--config" if which == "config" else "RECORDING") in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # nothing written, nothing lost


def test_a_recording_inside_the_output_folder_is_left_as_it_was(tmp_path, capsys):
    """The shortest calibration of a short recording kept in its output folder: afterwards the folder holds the
    recording, byte for byte, and files of the calibration's own names only."""
    import twin
    from twin.config import preset

    out = tmp_path / "cal"
    out.mkdir()
    rec = out / "rec.mcap"
    twin.record(preset(6).replace(**{"simulation.duration_s": 0.5, "drive.ramp_s": 0.15}), rec, static_s=0.1)
    before = rec.read_bytes()
    assert main(["calibrate", str(rec), "--params", "contact.restitution", "--out", str(out), "--global-points", "2",
                 "--local-short", "1", "--local-full", "1", "--replicates", "0", "--boot-replicates", "0",
                 "--profile-steps", "0.1", "--no-plots", "--no-progress"]) == 0, capsys.readouterr().err
    assert rec.read_bytes() == before
    assert {p.name for p in out.iterdir()} - {"rec.mcap"} <= set(OUTPUT_FILES)
    assert (out / "calibrated.toml").is_file()
