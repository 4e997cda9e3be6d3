"""The Python API (``import twin``): its docstring examples, lazy imports, names, errors and the
packaging edges it shows (``twin --version``, the cluster extra's message)."""

from __future__ import annotations

import doctest
import importlib
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import twin
from twin.cli import main
from twin.errors import ConfigError, MissingExtraError, TwinError

ROOT = Path(__file__).resolve().parent.parent
TINY = ROOT / "analysis" / "datasets" / "tiny.toml"


@pytest.mark.parametrize("module", ["twin", "twin.api"])
def test_docstring_examples_run(module, capsys):
    """The API's docstring examples (quick: 0.05 s runs) are checked here, in the default run."""
    res = doctest.testmod(importlib.import_module(module), optionflags=doctest.ELLIPSIS)
    out = capsys.readouterr().out
    assert res.attempted >= 3 and res.failed == 0, out


def _fresh(code: str) -> str:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          cwd=ROOT).stdout.strip()


def test_import_twin_imports_nothing_heavy():
    mods = _fresh("import sys, twin; print(sorted(m for m in sys.modules if m.split('.')[0] in "
                  "('twin', 'numpy', 'mujoco', 'scipy', 'pyarrow', 'sklearn', 'matplotlib')))")
    assert mods == "['twin']"
    # the first call imports what it needs
    mods = _fresh("import sys, twin; twin.preset(6); print('twin.config' in sys.modules, 'mujoco' in sys.modules)")
    assert mods == "True False"


def test_the_calls_are_functions_even_after_their_modules_are_imported():
    import twin.bench_replay
    import twin.identification.model
    import twin.simulation  # noqa: F401 - the modules behind the calls, imported first

    from twin import api
    assert twin.simulate is api.simulate and twin.replay is api.replay and twin.identify is api.identify
    assert twin.preset is api.preset and callable(twin.dataset.open)
    assert twin.Run is twin.run.Run and twin.__version__
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        twin.nope  # noqa: B018


def test_preset_by_id_and_by_name():
    assert twin.preset(6) == twin.preset("test6") == twin.preset("6")
    assert (twin.preset(6).joints.clearance_b_mm, twin.preset(6).joints.clearance_c_mm) == (0.0, 0.1)
    assert twin.preset("S001").name == "s001"
    from twin.config import NAMED_PRESETS

    names = ", ".join(NAMED_PRESETS)
    assert {"s000", "s001", "s004"} <= set(NAMED_PRESETS)
    with pytest.raises(ConfigError, match=rf"^preset: must be one of {names}, got 'x'$"):
        twin.preset("x")
    with pytest.raises(ConfigError, match="1..12"):
        twin.preset(0)


def test_simulate_returns_a_run_with_numpy_channels_and_options(tmp_path):
    out = tmp_path / "r.mcap"
    run = twin.simulate(6, duration=0.02, engine="mujoco", overrides={"sensors.channels": ["crank", "accel"]}, out=out)
    assert isinstance(run, twin.run.Run) and run.n == 2000 and run.config.simulation.duration_s == 0.02
    assert sorted(run.groups) == ["accel", "crank"] and isinstance(run["AC6"], np.ndarray)
    np.testing.assert_array_equal(run.time, np.arange(2000) / 1e5)
    from twin.mcapfile import read_run

    back = read_run(out)  # the file written alongside holds the same samples
    np.testing.assert_array_equal(back["AC6"], run["AC6"])
    with pytest.raises(ConfigError, match="simulation.duration_s"):
        twin.simulate(6, duration=-1.0)
    with pytest.raises(ConfigError, match="^cfg: must be a BenchConfig"):
        twin.simulate(6.0)


def test_to_pandas_keeps_values_dtypes_times_and_units():
    import pandas as pd  # in the test extra
    run = twin.simulate(6, duration=0.01, overrides={"sensors.channels": ["crank", "accel"]})
    df = run.to_pandas()
    assert isinstance(df, pd.DataFrame) and list(df.columns) == list(run.channels) and len(df) == run.n
    assert df.index.name == "t"
    np.testing.assert_array_equal(df.index.to_numpy(), run.time)
    for name, ch in run.channels.items():
        assert df[name].dtype == ch.data.dtype
        np.testing.assert_array_equal(df[name].to_numpy(), ch.data)
    assert df.attrs["units"]["AC6"] == "m/s^2" and df.attrs["units"]["crank_angle"] == "rad"


def test_to_pandas_without_pandas_names_the_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # what `import pandas` does where it is missing
    run = twin.run.Run.from_arrays(0.0, 10.0, {"AC6": np.zeros(3)})
    with pytest.raises(MissingExtraError) as err:
        run.to_pandas()
    assert str(err.value) == "Run.to_pandas needs pandas, which is not installed: pip install pandas"
    assert isinstance(err.value, ImportError) and isinstance(err.value, TwinError)


def test_identify_answers_for_a_sample_recording():
    a = twin.identify(ROOT / "recordings" / "test6_synthetic.mcap")
    # the recording is synthetic test 6: 0.1 mm at C only; the shipped model's location answer
    assert a.fault == "C" and a.joint("B").size_mm == 0.0
    lo, hi = a.joint("C").interval_mm
    assert 0 < lo <= a.joint("C").size_mm <= hi
    held = a.joint("C").size_held_out  # the docstring's attributes: how often sizes held at this speed
    assert held.within_factor == 1.5 and 0 <= held.share <= 1 and held.runs > 0
    with pytest.raises(TwinError, match="no such model file"):
        twin.identify(ROOT / "recordings" / "test6_synthetic.mcap", model=ROOT / "nope.joblib")


def test_version_option(capsys):
    from importlib.metadata import version

    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out.strip() == f"twin {twin.__version__}"
    assert version("twin") == twin.__version__  # pyproject reads the version from the package


def test_dask_scheduler_without_the_cluster_extra_is_one_line(tmp_path, monkeypatch, capsys):
    for mod in ("distributed", "dask"):
        monkeypatch.setitem(sys.modules, mod, None)  # as if the cluster extra were not installed
    out = tmp_path / "ds"
    for scheduler in ("local", "tcp://127.0.0.1:8786"):
        rc = main(["dataset", "generate", str(TINY), "--out", str(out), "--scheduler", scheduler, "--no-progress"])
        err = capsys.readouterr().err
        assert rc == 2 and err.count("\n") == 1, err
        assert err == (f"twin: error: --scheduler: {scheduler}: Dask is not installed; a Dask scheduler needs the "
                       "cluster extra: pip install 'twin[cluster]'\n")
        assert not out.exists()  # refused before anything was written


def test_local_generation_never_imports_dask(tmp_path):
    """The default executors (threads, processes) run without the cluster extra: Dask blocked."""
    code = (f"import sys\nsys.modules['dask'] = sys.modules['distributed'] = None\n"
            "from twin.dataset.generate import executor, generate\nfrom twin.dataset.spec import load_spec\n"
            "executor('processes', 2)\n"
            f"info = generate(load_spec({str(TINY)!r}), {str(tmp_path / 'ds')!r}, workers=1, scheduler='threads', "
            "limit=1, progress=False)\n"
            "print(info['generation']['runs_this_call'], info['generation']['failed_this_call'])\n")
    assert _fresh(code) == "1 0"
