"""Outputs that alias inputs, dataset readers that trust their files, refusals that come late.

The table :data:`CASES` (run like those of ``test_bad_input.py`` and ``test_bad_input_more.py``:
``twin.cli.main`` in-process, exit status 2, one line ``twin: error: ...`` holding the fragment, no
traceback, nothing on stdout, the workspace unchanged file by file, links and FIFOs not followed)
covers:

* outputs that are, or lie inside, an input the command reads: ``dataset info DIR --json
  DIR/info.json``, a model trained into its own dataset, an output name that is a link to the
  configuration, the trace or the recording;
* the dataset folder's lock file as a link or a FIFO (its target was truncated);
* dataset folders whose ``info.json``, ``runs.parquet``, ``stats.json`` or run-file metadata are
  well-formed but hold other fields, types or values (tracebacks, or silently accepted);
* model files declaring a window hop that would make identification allocate gigabytes;
* ``study taguchi`` specs whose defects are knowable before simulating; ``dataset generate`` on
  a complete dataset whose own files or folders cannot be written (it marked it incomplete first).

Below the table: MuJoCo's warnings neither printed nor written to ``MUJOCO_LOG.TXT``, strict JSON,
a full disk naming the file, and property-based tests (hypothesis) of the dataset readers.
"""

from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

from test_bad_input_more import ZERO_G, _export, _trace, check_case, no_hang, snapshot  # noqa: F401 - no_hang: autouse
from twin.cli import main
from twin.errors import TwinError

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "recordings" / "test6_synthetic.mcap"
SHIPPED_MODEL = ROOT / "twin" / "data" / "identify_default.npz"

DS_SPEC = ('[dataset]\nname = "outs"\nseed = 3\n[base]\ntest = 3\nengine = "mujoco"\nduration_s = 0.02\n'
           'program = "constant"\n[design]\nkind = "grid"\n[factors]\nfault = ["none", "B"]\n'
           'motor_rpm = [300.0, 500.0]\n[outputs]\ntruth = ["accel", "encoder"]\ninstrumented = false\n'
           'rate_hz = 10000.0\n[splits]\ntrain = 0.5\nval = 0.25\ntest = 0.25\n')

TAGUCHI = '''[dataset]
name = "tg"
seed = 1
[base]
preset = "s002"
engine = "mujoco"
duration_s = 0.02
[design]
kind = "list"
{points}
[outputs]
truth = {truth}
instrumented = false
rate_hz = 10000.0
[taguchi]
factors = {{ mu0 = "contact.mu0", crank_rpm = "crank_rpm" }}
responses = {responses}
{extra}
'''
L4 = [(0.01, 800.0), (0.01, 1000.0), (0.05, 800.0), (0.05, 1000.0)]


def _points(levels, extra_first: str = "") -> str:
    out = []
    for k, (mu, rpm) in enumerate(levels):
        out.append(f'[[design.points]]\n"contact.mu0" = {mu}\ncrank_rpm = {rpm}\n' + (extra_first if k == 0 else ""))
    return "\n".join(out)


def _taguchi(path: Path, levels=L4, truth='["slider_accel", "joints"]', responses='["max_slider_accel", "max_force_A"]',
             extra: str = "", extra_first: str = "") -> None:
    path.write_text(TAGUCHI.format(points=_points(levels, extra_first), truth=truth, responses=responses, extra=extra))


# ------------------------------------------------------------------------ dataset mutations
def _manifest(ds: Path, fn) -> None:
    import pyarrow.parquet as pq

    pq.write_table(fn(pq.read_table(ds / "runs.parquet")), ds / "runs.parquet")


def _info(ds: Path, fn) -> None:
    info = json.loads((ds / "info.json").read_text())
    fn(info)
    (ds / "info.json").write_text(json.dumps(info))


def _set(table, name: str, values):
    import pyarrow as pa

    i = table.column_names.index(name)
    return table.set_column(i, name, pa.array(values))


def _drop(name: str):
    return lambda t: t.drop_columns([name])


def _data_meta(ds: Path, fn) -> None:
    """Rewrite the twin.dataset metadata of the first ok run's file with ``fn`` (dict -> object, or bytes)
    and record the new file's size and SHA-256 in the manifest: only the metadata is wrong."""
    import pyarrow.parquet as pq

    from twin.util import file_sha256

    runs = pq.read_table(ds / "runs.parquet")
    rows = runs.to_pylist()
    k = next(i for i, r in enumerate(rows) if r["status"] == "ok")
    f = ds / rows[k]["file"]
    tab = pq.read_table(f)
    md = dict(tab.schema.metadata)
    new = fn(json.loads(md[b"twin.dataset"]))
    md[b"twin.dataset"] = new if isinstance(new, bytes) else json.dumps(new).encode()
    pq.write_table(tab.replace_schema_metadata(md), f)
    sha, size = [r["sha256"] for r in rows], [r["bytes"] for r in rows]
    sha[k], size[k] = file_sha256(f), f.stat().st_size
    runs = _set(_set(runs, "sha256", sha), "bytes", size)
    pq.write_table(runs, ds / "runs.parquet")


def _chan0(key, value=None, drop=False):
    def fn(info):
        if drop:
            info["channels"][0].pop(key)
        else:
            info["channels"][0][key] = value
    return fn


INFO_MUTATIONS = {
    "i_no_dtype": (_chan0("dtype", drop=True), "channels[0].dtype"),
    "i_dtype_num": (_chan0("dtype", 5), "channels[0].dtype"),
    "i_name_num": (_chan0("name", 3), "channels[0].name"),
    "i_no_rate": (_chan0("rate_hz", drop=True), "channels[0].rate_hz"),
    "i_rate_zero": (_chan0("rate_hz", 0), "channels[0].rate_hz"),
    "i_rate_two": (lambda i: i["channels"][1].__setitem__("rate_hz", 5000.0), "channels[1].rate_hz"),
    "i_dup_chan": (lambda i: i["channels"][1].__setitem__("name", i["channels"][0]["name"]), "repeats the channel"),
    "i_labels_str": (lambda i: i.__setitem__("label_columns", "fault"), "label_columns"),
    "i_keys_num": (lambda i: i.__setitem__("key_columns", 5), "key_columns"),
    "i_keys_other": (lambda i: i.__setitem__("key_columns", ["t", "run_id"]), "key_columns"),
    "i_runs_list": (lambda i: i.__setitem__("runs", []), "'runs'"),
    "i_runs_partial": (lambda i: i["runs"].pop("pending"), "'runs'"),
    "i_name_num_top": (lambda i: i.__setitem__("name", 5), "'name'"),
    "i_complete_str": (lambda i: i.__setitem__("complete", "yes"), "'complete'"),
    "i_cpr_text": (lambda i: i.__setitem__("encoder_counts_per_rev", "many"), "encoder_counts_per_rev"),
    "i_no_identity": (lambda i: i.pop("identity"), "'identity'"),
}

MANIFEST_MUTATIONS = {
    "m_no_status": (_drop("status"), "'status'"),
    "m_no_sha": (_drop("sha256"), "'sha256'"),
    "m_no_fault": (_drop("fault"), "'fault'"),
    "m_no_bytes": (_drop("bytes"), "'bytes'"),
    "m_no_split": (_drop("split"), "'split'"),
    "m_status_int": (lambda t: _set(t, "status", [1] * t.num_rows), "'status'"),
    "m_status_odd": (lambda t: _set(t, "status", ["done"] * t.num_rows), "'status'"),
    "m_fault_odd": (lambda t: _set(t, "fault", ["X"] * t.num_rows), "'fault'"),
    "m_split_odd": (lambda t: _set(t, "split", ["dev"] * t.num_rows), "'split'"),
    "m_bytes_str": (lambda t: _set(t, "bytes", ["12"] * t.num_rows), "'bytes'"),
    "m_dup_id": (lambda t: _set(t, "run_id", [t.column("run_id")[0].as_py()] * t.num_rows), "repeats a run id"),
    "m_id_path": (lambda t: _set(t, "run_id", ["../x"] + t.column("run_id").to_pylist()[1:]), "'run_id'"),
    "m_clear_null": (lambda t: _set(t, "clearance_b_mm", [None] * t.num_rows), "'clearance_b_mm'"),
    "m_point_float": (lambda t: _set(t, "point", [0.5] * t.num_rows), "'point'"),
    "m_rows_neg": (lambda t: _set(t, "rows", [-1] * t.num_rows), "'rows'"),
}

STATS_MUTATIONS = {
    "s_list": ('{"channels": []}', "stats.json"),
    "s_mean_text": ('{"channels": {"accel_AC1": {"mean": "x", "std": 1.0}}}', "channels.accel_AC1"),
    "s_std_neg": ('{"channels": {"accel_AC1": {"mean": 0.0, "std": -1.0}}}', "channels.accel_AC1"),
    "s_nan": ('{"channels": {"accel_AC1": {"mean": NaN, "std": 1.0}}}', "NaN is not JSON"),
}

DATA_MUTATIONS = {
    "d_no_rate": (lambda m: {k: v for k, v in m.items() if k != "rate_hz"}, "rate_hz"),
    "d_rate_text": (lambda m: {**m, "rate_hz": "fast"}, "rate_hz"),
    "d_not_json": (lambda m: b"{not json", "not JSON"),
    "d_list": (lambda m: [1, 2], "JSON object"),
    "d_no_units": (lambda m: {k: v for k, v in m.items() if k != "units"}, "units"),
}


# ------------------------------------------------------------------------ workspace
@pytest.fixture(scope="module")
def ws(tmp_path_factory) -> Path:
    ws = tmp_path_factory.mktemp("bad_outputs")
    (ws / "ds_spec.toml").write_text(DS_SPEC)
    assert main(["dataset", "generate", str(ws / "ds_spec.toml"), "--out", str(ws / "ds"), "--workers", "1",
                 "--no-progress"]) == 0
    ds = ws / "ds"
    shutil.copytree(ds, ws / "ds2")
    shutil.copytree(ds, ws / "pristine")  # the property tests' source: no table case names it
    os.symlink("ds", ws / "ds_link")
    os.symlink("ds/info.json", ws / "ds_info_as.json")
    rid = next(r for r in __import__("pyarrow.parquet", fromlist=["x"]).read_table(ds / "runs.parquet").to_pylist()
               if r["status"] == "ok")["run_id"]
    (ws / "rid").write_text(rid)
    # inputs and output names that are links to them
    (ws / "cfg.toml").write_text("[drive]\nmotor_rpm = 300.0\n")
    for ext in ("mcap", "json", "rrd", "xml"):
        os.symlink("cfg.toml", ws / f"cfg_as.{ext}")
    t = np.arange(2001) / 1000.0
    _trace(ws / "ok_trace.npz", t, 2 * np.pi * (200.0 / 60.0) * t)
    os.symlink("ok_trace.npz", ws / "trace_as.mcap")
    shutil.copy(SAMPLE, ws / "rec.mcap")
    os.symlink("rec.mcap", ws / "rec_as.json")
    os.symlink("rec.mcap", ws / "rec_as.png")
    _export(ws / "export.csv", 200)
    # lock files that are not the twin's
    (ws / "victim.txt").write_text("months of work\n")
    for name, make in (("lock_link", lambda p: os.symlink("../victim.txt", p)),
                       ("lock_dangling", lambda p: os.symlink("../made_by_lock.txt", p)),
                       ("lock_fifo", os.mkfifo)):
        shutil.copytree(ds, ws / name)
        (ws / name / ".twin.lock").unlink(missing_ok=True)
        make(ws / name / ".twin.lock")
    # complete datasets whose own files or folders cannot be written
    for name in ("gen_results_file", "gen_data_file", "gen_runs_dir", "gen_stats_link", "gen_info_link"):
        shutil.copytree(ds, ws / name)
    shutil.rmtree(ws / "gen_results_file" / "results")
    (ws / "gen_results_file" / "results").write_text("a file\n")
    shutil.rmtree(ws / "gen_data_file" / "data")
    (ws / "gen_data_file" / "data").write_text("a file\n")
    (ws / "gen_runs_dir" / "runs.parquet").unlink()
    (ws / "gen_runs_dir" / "runs.parquet").mkdir()
    (ws / "stats_victim.json").write_text('{"mine": true}\n')
    (ws / "gen_stats_link" / "stats.json").unlink()
    os.symlink("../stats_victim.json", ws / "gen_stats_link" / "stats.json")
    shutil.move(ws / "gen_info_link" / "info.json", ws / "info_elsewhere.json")
    os.symlink("../info_elsewhere.json", ws / "gen_info_link" / "info.json")
    # datasets whose own files hold other fields, types or values
    for name, (fn, _) in INFO_MUTATIONS.items():
        shutil.copytree(ds, ws / name)
        _info(ws / name, fn)
    (ws / "i_nan").mkdir()
    shutil.copytree(ds, ws / "i_nan", dirs_exist_ok=True)
    (ws / "i_nan" / "info.json").write_text((ds / "info.json").read_text().replace('"complete": true',
                                                                                    '"complete": true, "x": NaN'))
    for name, (fn, _) in MANIFEST_MUTATIONS.items():
        shutil.copytree(ds, ws / name)
        _manifest(ws / name, fn)
    for name, (text, _) in STATS_MUTATIONS.items():
        shutil.copytree(ds, ws / name)
        (ws / name / "stats.json").write_text(text)
    for name, (fn, _) in DATA_MUTATIONS.items():
        shutil.copytree(ds, ws / name)
        _data_meta(ws / name, fn)
    # model files declaring a window hop that would cut a window at every sample
    from twin.identification.model import ClearanceModel

    for name, hop in (("hop_tiny", 1e-9), ("hop_300", 1e-300), ("hop_small", 0.01)):
        m = ClearanceModel.load(SHIPPED_MODEL)
        m.trained_on["answer_hop_revs"] = hop
        m.save(ws / f"{name}.npz")
    # Taguchi specs whose defects need no simulation
    _taguchi(ws / "tg_inter_unknown.toml", extra='interactions = ["mu0*zz"]')
    _taguchi(ws / "tg_inter_self.toml", extra='interactions = ["mu0*mu0"]')
    _taguchi(ws / "tg_inter_twice.toml", extra='interactions = ["mu0*crank_rpm", "crank_rpm*mu0"]')
    _taguchi(ws / "tg_one_level.toml", levels=[(0.01, r) for _, r in L4])
    _taguchi(ws / "tg_unbalanced.toml", levels=L4[:3])
    _taguchi(ws / "tg_no_slider.toml", truth='["joints"]')
    _taguchi(ws / "tg_no_joints.toml", truth='["slider_accel"]', responses='["max_force_A"]')
    _taguchi(ws / "tg_no_clear_b.toml", responses='["max_force_B"]', extra_first='"joints.clearance_b_mm" = 0.0\n')
    _taguchi(ws / "tg_good.toml")
    # a Taguchi CSV named like one of the analysis's outputs, in the output folder
    (ws / "tga").mkdir()
    table = "A,B,y1,y2\n1,1,1.0,1.1\n1,2,2.0,2.1\n2,1,3.0,3.3\n2,2,4.0,4.2\n"
    for name in ("report.md", "taguchi.json", "main_effects_y1.png", "sn_y1.png"):
        (ws / "tga" / name).write_text(table)
    return ws


def _cases() -> list[tuple[str, str]]:
    c: list[tuple[str, str]] = [
        # ---- outputs inside or equal to an input being read (data loss)
        ("dataset info {ws}/ds --json {ws}/ds/info.json", "lies inside the input"),
        ("dataset info {ws}/ds --json {ws}/ds/stats.json", "lies inside the input"),
        ("dataset info {ws}/ds --json {ws}/ds/summary.json", "lies inside the input"),
        ("dataset info {ws}/ds --json {ws}/ds/data/summary.json", "lies inside the input"),
        ("dataset info {ws}/ds --json {ws}/ds/results/summary.json", "lies inside the input"),
        ("dataset info {ws}/ds_link --json {ws}/ds/summary.json", "lies inside the input"),
        ("dataset info {ws}/ds --json {ws}/ds_link/summary.json", "lies inside the input"),
        ("dataset info {ws}/ds/ --json {ws}/ds/../ds/info.json", "lies inside the input"),
        ("dataset info {ws}/ds --json {ws}/ds_info_as.json", "lies inside the input"),
        ("dataset info {ws}/ds --show 0 --json {ws}/ds/runs.json", "lies inside the input"),
        ("identify train {ws}/ds --out {ws}/ds/m.npz", "lies inside the input"),
        ("identify train {ws}/ds --out {ws}/ds/data/m.npz", "lies inside the input"),
        ("identify train {ws}/ds {ws}/ds2 --out {ws}/ds2/m.npz", "lies inside the input"),
        ("identify train {ws}/ds_link --out {ws}/ds/m.npz", "lies inside the input"),
        ("identify evaluate " + str(SHIPPED_MODEL) + " {ws}/ds --out {ws}/ds/report", "lies inside the input"),
        ("identify evaluate " + str(SHIPPED_MODEL) + " {ws}/ds --out {ws}/ds", "is the input"),
        ("identify evaluate " + str(SHIPPED_MODEL) + " {ws}/ds {ws}/ds2 --out {ws}/ds2/rep", "lies inside the input"),
        ("identify clearance {ws}/rec.mcap --json {ws}/rec_as.json", "is the input"),
        ("view {ws}/ds --run {rid} --save {ws}/ds/v.rrd", "lies inside the input"),
        ("view {ws}/ds --run {rid} --save {ws}/ds/data/v.rrd", "lies inside the input"),
        ("view {ws}/rec.mcap --save {ws}/v.rrd --screenshot {ws}/rec_as.png", "is the input"),
        ("simulate --config {ws}/cfg.toml --duration 0.01 --no-progress --out {ws}/cfg_as.mcap", "is the input"),
        ("simulate --config {ws}/cfg.toml --duration 0.01 --no-progress --no-out --summary-json {ws}/cfg_as.json",
         "is the input"),
        ("simulate --config {ws}/cfg.toml --duration 0.01 --no-progress --no-out --rerun {ws}/cfg_as.rrd",
         "is the input"),
        ("simulate --trace {ws}/ok_trace.npz --duration 0.01 --no-progress --out {ws}/trace_as.mcap", "is the input"),
        ("export-mjcf --config {ws}/cfg.toml --out {ws}/cfg_as.xml", "is the input"),
        ("import {ws}/export.csv --config {ws}/cfg.toml --zero-g " + ZERO_G + " --out {ws}/cfg_as.mcap",
         "is the input"),
        ("check contact --config {ws}/cfg.toml --out {ws}/cfg_as.json", "is the input"),
        # ---- the dataset folder's lock file is the twin's own: never followed
        ("dataset generate {ws}/ds_spec.toml --out {ws}/lock_link --workers 1 --no-progress", "symbolic link"),
        ("dataset generate {ws}/ds_spec.toml --out {ws}/lock_dangling --workers 1 --no-progress", "symbolic link"),
        ("dataset generate {ws}/ds_spec.toml --out {ws}/lock_fifo --workers 1 --no-progress", "not a regular file"),
        # ---- a complete dataset is never marked incomplete before a refusal
        ("dataset generate {ws}/ds_spec.toml --out {ws}/gen_results_file --workers 1 --no-progress", "not a folder"),
        ("dataset generate {ws}/ds_spec.toml --out {ws}/gen_data_file --workers 1 --no-progress", "not a folder"),
        ("dataset generate {ws}/ds_spec.toml --out {ws}/gen_runs_dir --workers 1 --no-progress",
         "not a regular file"),
        ("dataset generate {ws}/ds_spec.toml --out {ws}/gen_stats_link --workers 1 --no-progress",
         "not a regular file"),
        ("dataset generate {ws}/ds_spec.toml --out {ws}/gen_info_link --workers 1 --no-progress",
         "not a regular file"),
        # ---- model files: resources derived from what the file declares, bounded before allocating
        ("identify evaluate {ws}/hop_tiny.npz {ws}/missing_ds --out {ws}/rep", "answer_hop_revs"),
        ("identify evaluate {ws}/hop_300.npz {ws}/missing_ds --out {ws}/rep", "answer_hop_revs"),
        ("identify evaluate {ws}/hop_small.npz {ws}/missing_ds --out {ws}/rep", "answer_hop_revs"),
        # ---- study taguchi: what needs no simulation is checked before the first one
        ("study taguchi {ws}/tg_inter_unknown.toml --out {ws}/tg --workers 1 --no-progress", "taguchi.interactions"),
        ("study taguchi {ws}/tg_inter_self.toml --out {ws}/tg --workers 1 --no-progress", "taguchi.interactions"),
        ("study taguchi {ws}/tg_inter_twice.toml --out {ws}/tg --workers 1 --no-progress", "taguchi.interactions"),
        ("study taguchi {ws}/tg_one_level.toml --out {ws}/tg --workers 1 --no-progress", "taguchi.factors.mu0"),
        ("study taguchi {ws}/tg_unbalanced.toml --out {ws}/tg --workers 1 --no-progress", "orthogonal"),
        ("study taguchi {ws}/tg_no_slider.toml --out {ws}/tg --workers 1 --no-progress", "slider_accel"),
        ("study taguchi {ws}/tg_no_joints.toml --out {ws}/tg --workers 1 --no-progress", "joints"),
        ("study taguchi {ws}/tg_no_clear_b.toml --out {ws}/tg --workers 1 --no-progress", "joint B"),
    ]
    # ---- dataset readers: the schema of the dataset's own files, one line naming the file and field
    for name, (_, frag) in INFO_MUTATIONS.items():
        c.append((f"dataset info {{ws}}/{name}", frag))
        c.append((f"dataset verify {{ws}}/{name} --no-progress", frag))
    c.append(("dataset info {ws}/i_nan", "NaN is not JSON"))
    c.append(("dataset verify {ws}/i_nan --no-progress", "NaN is not JSON"))
    for name, (_, frag) in MANIFEST_MUTATIONS.items():
        c.append((f"dataset info {{ws}}/{name}", frag))
        c.append((f"dataset verify {{ws}}/{name} --no-progress", frag))
    for name, (_, frag) in STATS_MUTATIONS.items():
        c.append((f"dataset info {{ws}}/{name}", frag))
        c.append((f"dataset verify {{ws}}/{name} --no-progress", frag))
    for name, (_, frag) in DATA_MUTATIONS.items():
        c.append((f"dataset verify {{ws}}/{name} --no-progress", frag))
    for name in ("i_no_dtype", "i_labels_str", "i_no_identity", "m_no_status", "m_fault_odd", "s_mean_text"):
        c.append((f"identify train {{ws}}/{name} --out {{ws}}/m.npz", INFO_MUTATIONS.get(name, MANIFEST_MUTATIONS.get(
            name, STATS_MUTATIONS.get(name, ("", "")))) [1]))
    for name in ("report.md", "taguchi.json", "main_effects_y1.png", "sn_y1.png"):
        c.append((f"study taguchi-analyze {{ws}}/tga/{name} --responses y1 --factors A,B --out {{ws}}/tga",
                  f"tga/{name} is the input"))
    for name in ("d_no_rate", "d_rate_text", "d_not_json"):
        c.append((f"view {{ws}}/{name} --run {{rid}} --save {{ws}}/v.rrd", DATA_MUTATIONS[name][1]))
    return c


CASES = _cases()


@pytest.mark.parametrize("line, fragment", CASES, ids=[c[0].replace("{ws}/", "")[:90] for c in CASES])
def test_output_and_reader_cases_are_one_line_exit_2_and_change_nothing(line, fragment, ws, capsys, monkeypatch):
    monkeypatch.chdir(ws)
    check_case(line, fragment, ws, capsys, {"{rid}": (ws / "rid").read_text()})
    assert not (ws / "MUJOCO_LOG.TXT").exists()


def test_the_table_is_large_and_new():
    assert len(CASES) >= 100 and len({c[0] for c in CASES}) == len(CASES)
    from test_bad_input import CASES as OLD
    from test_bad_input_more import CASES as MORE

    assert not {c[0] for c in CASES} & ({c[0] for c in OLD} | {c[0] for c in MORE})


def test_the_unchanged_dataset_is_read_and_a_summary_outside_it_written(ws, capsys, tmp_path):
    """The positive side of the rules above: the same commands on the intact dataset work, and the
    summary goes to a file outside it, as strict JSON."""
    assert main(["dataset", "verify", str(ws / "ds"), "--no-progress"]) == 0
    assert main(["dataset", "info", str(ws / "ds"), "--json", str(tmp_path / "s.json")]) == 0
    capsys.readouterr()

    def strict(name):
        raise ValueError(name)

    s = json.loads((tmp_path / "s.json").read_text(), parse_constant=strict)
    assert s["name"] == "outs" and len(s["runs"]) == 4


def test_a_taguchi_spec_that_passes_the_checks_still_runs(ws):
    """The checks before simulating refuse nothing valid: the good spec's plan passes them."""
    from twin.studies.taguchi_run import load_taguchi, preflight

    assert len(preflight(load_taguchi(ws / "tg_good.toml"))) == 4
    for f in ("s002_l27.toml", "s002_l27_reference.toml"):
        assert len(preflight(load_taguchi(ROOT / "analysis" / "datasets" / f))) == 27


# --------------------------------------------------------------------------- MuJoCo's log
def test_mujoco_warnings_are_neither_printed_nor_logged_by_any_model_building_module(tmp_path):
    """A process that builds a model through any module of the twin (here the builder alone, without the
    engine module that once installed the handler) and makes MuJoCo warn: nothing printed, no
    MUJOCO_LOG.TXT in the working folder, the warning kept for messages."""
    code = ("import math, mujoco\n"
            "import twin.mujoco_engine.builder\n"
            "m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><body><freejoint/><geom size=\"0.1\"/></body>"
            "</worldbody></mujoco>')\n"
            "d = mujoco.MjData(m)\n"
            "d.qvel[:] = math.nan\n"
            "mujoco.mj_step(m, d)\n"
            "from twin.mujoco_log import MUJOCO_WARNINGS\n"
            "assert MUJOCO_WARNINGS and 'Nan' in MUJOCO_WARNINGS[-1], MUJOCO_WARNINGS\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout == "" and "WARNING" not in r.stderr, (r.stdout, r.stderr)
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------- strict JSON
def test_json_the_twin_writes_is_strict(tmp_path):
    """NaN and infinities become null (a missing value); what is written parses with a strict parser."""
    from twin.util import atomic_write_json, json_text

    obj = {"a": float("nan"), "b": [1.0, float("inf"), np.float32("nan")], "c": np.array([np.nan, 2.0]),
           "d": np.float64(-np.inf), "e": 3}
    atomic_write_json(tmp_path / "x.json", obj)

    def strict(name):
        raise ValueError(name)

    for text in ((tmp_path / "x.json").read_text(), json_text(obj)):
        assert json.loads(text, parse_constant=strict) == {"a": None, "b": [1.0, None, None], "c": [None, 2.0],
                                                            "d": None, "e": 3}


# ------------------------------------------------------------------------------ full disk
def test_a_full_disk_names_the_file_being_written(tmp_path):
    """A write that fails for room (here a file-size limit: EFBIG, as ENOSPC) is one line naming the output
    the user gave, not a bare system message (the MCAP writer's clean-up once raised a second, anonymous
    error over the first), and no temporary is left."""
    code = ("import resource, signal, sys\n"
            "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
            "resource.setrlimit(resource.RLIMIT_FSIZE, (3000, 3000))\n"
            "from twin.cli import main\n"
            "sys.exit(main(sys.argv[1:]))\n")
    r = subprocess.run([sys.executable, "-c", code, "simulate", "--test", "6", "--duration", "0.2", "--no-progress",
                        "--out", "x.mcap"], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("twin: error: x.mcap: cannot write"), r.stderr
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ property-based readers
hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

json_values = st.recursive(st.one_of(st.none(), st.booleans(), st.integers(-10**12, 10**12),
                                     st.floats(allow_nan=False, allow_infinity=False), st.text(max_size=8)),
                           lambda inner: st.one_of(st.lists(inner, max_size=3),
                                                   st.dictionaries(st.sampled_from(["name", "planned", "ok", "pending",
                                                                                    "engine", "x"]), inner, max_size=3)),
                           max_leaves=6)
#: examples per property (``TWIN_READER_EXAMPLES=500`` for a long search)
EXAMPLES = int(os.environ.get("TWIN_READER_EXAMPLES", "30"))
INFO_KEYS = ["format", "name", "complete", "identity", "runs", "channels", "key_columns", "label_columns",
             "encoder_counts_per_rev", "splits", "labels"]


def _reader_contract(d: Path, capsys) -> None:
    """``dataset info``, ``dataset verify`` and ``twin.dataset.open`` on ``d``: a result, or one line
    (a TwinError whose message has no newline); never a traceback; not a byte of the folder changed."""
    from twin.dataset import open as open_dataset
    from twin.errors import TwinError

    before = snapshot(d)
    for argv in (["dataset", "info", str(d)], ["dataset", "verify", str(d), "--no-progress"],
                 ["dataset", "info", str(d), "--json"]):
        rc = main(argv)
        out, err = capsys.readouterr()
        assert rc in (0, 1, 2), (argv, rc, err[-2000:])
        assert "Traceback" not in err
        if rc == 2:
            assert err.startswith("twin: error: ") and err.count("\n") == 1, err[-2000:]
        if rc == 0 and argv[-1] == "--json":
            json.loads(out, parse_constant=lambda n: (_ for _ in ()).throw(ValueError(n)))
    try:
        ds = open_dataset(d)
        ds.rows()
    except TwinError as err:
        assert "\n" not in str(err), str(err)
    assert snapshot(d) == before


@pytest.fixture(scope="module")
def pristine(ws) -> Path:
    return ws / "pristine"


def _copy(src: Path) -> Path:
    d = Path(tempfile.mkdtemp(prefix="twin_ds_prop_")) / "ds"
    shutil.copytree(src, d)
    return d


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(key=st.sampled_from(INFO_KEYS), value=json_values,
       chan_key=st.sampled_from(["name", "unit", "dtype", "rate_hz", "group", None]), chan_value=json_values)
def test_any_info_file_is_read_or_refused_in_one_line(key, value, chan_key, chan_value, pristine, capsys):
    d = _copy(pristine)
    try:
        info = json.loads((d / "info.json").read_text())
        if key != "format":
            info[key] = value
        if chan_key is not None and isinstance(info.get("channels"), list) and info["channels"] and \
                isinstance(info["channels"][0], dict):
            info["channels"][0][chan_key] = chan_value
        (d / "info.json").write_text(json.dumps(info))
        _reader_contract(d, capsys)
    finally:
        shutil.rmtree(d.parent, ignore_errors=True)


manifest_values = st.one_of(st.none(), st.booleans(), st.integers(-5, 10**6), st.floats(allow_nan=True),
                            st.text(max_size=10), st.sampled_from(["ok", "failed", "pending", "train", "none", "B"]))


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(column=st.sampled_from(["run_id", "split", "status", "fault", "clearance_b_mm", "clearance_c_mm", "point",
                               "duration_s", "simulated_s", "rows", "bytes", "sha256", "reason", "file",
                               "orientation"]),
       value=manifest_values, drop=st.booleans())
def test_any_manifest_is_read_or_refused_in_one_line(column, value, drop, pristine, capsys):
    import pyarrow as pa

    d = _copy(pristine)
    try:
        def change(t):
            if drop:
                return t.drop_columns([column])
            try:
                arr = pa.array([value] * t.num_rows)
            except (pa.ArrowInvalid, pa.ArrowTypeError, OverflowError):
                arr = pa.array([str(value)] * t.num_rows)
            return t.set_column(t.column_names.index(column), column, arr)

        _manifest(d, change)
        _reader_contract(d, capsys)
    finally:
        shutil.rmtree(d.parent, ignore_errors=True)


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(target=st.sampled_from(["runs.parquet", "stats.json", "info.json", "data"]),
       offset=st.integers(0, 10**6), data=st.binary(min_size=1, max_size=16), truncate=st.booleans())
def test_any_damaged_file_is_read_or_refused_in_one_line(target, offset, data, truncate, pristine, capsys):
    d = _copy(pristine)
    try:
        f = d / target if target != "data" else sorted((d / "data").glob("*.parquet"))[0]
        raw = bytearray(f.read_bytes())
        k = offset % max(1, len(raw))
        raw = raw[:k] if truncate else raw[:k] + data + raw[k + len(data):]
        f.write_bytes(bytes(raw))
        _reader_contract(d, capsys)
    finally:
        shutil.rmtree(d.parent, ignore_errors=True)


def test_a_full_disk_during_the_rrd_is_one_line_without_the_sdks_log(tmp_path):
    """rerun's own log lines ("ERROR re_log_encoding::rrd::file_sink ...") no longer precede the twin's one
    line when the disk fills while `twin view` writes; nothing is left behind."""
    assert main(["simulate", "--test", "6", "--duration", "0.2", "--no-progress", "--out",
                 str(tmp_path / "r.mcap")]) == 0
    out = tmp_path / "out"
    out.mkdir()
    code = ("import resource, signal, sys\n"
            "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
            "resource.setrlimit(resource.RLIMIT_FSIZE, (400000, 400000))\n"
            "from twin.cli import main\n"
            "sys.exit(main(sys.argv[1:]))\n")
    env = {k: v for k, v in os.environ.items() if k != "RUST_LOG"}
    r = subprocess.run([sys.executable, "-c", code, "view", str(tmp_path / "r.mcap"), "--save", "x.rrd"],
                       cwd=out, capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("twin: error: x.rrd: cannot write"), r.stderr
    assert list(out.iterdir()) == []


def test_a_disk_without_room_for_the_rrd_is_refused_before_rerun_starts(tmp_path, monkeypatch):
    """rerun's save() blocks for good when its first write fails: a disk without the room is refused first."""
    import shutil as sh
    from collections import namedtuple

    import twin.viz.writer as writer

    assert main(["simulate", "--test", "6", "--duration", "0.05", "--no-progress", "--out",
                 str(tmp_path / "r.mcap")]) == 0
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(writer.shutil, "disk_usage", lambda p: usage(10 ** 9, 10 ** 9 - 4096, 4096))
    assert writer.shutil is sh
    with pytest.raises(TwinError, match=r"x\.rrd: cannot write \(no space left on the device: 4096 bytes free\)"):
        from twin.viz import convert_file
        convert_file(tmp_path / "r.mcap", tmp_path / "x.rrd")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.mcap"]
