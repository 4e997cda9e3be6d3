"""numba's compiled code is cached on disk and its compilation announced (twin.jit): the first process
with an empty cache compiles and prints one line; the second loads the code and prints nothing."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from twin.jit import NOTICE

# one small compiled function of the reference engine, compiled (or loaded) in a fresh process; prints
# numba's own count of cache hits for it
PROBE = ("from twin.physics.contact import _hysteresis as f\n"
         "f(1e-6, 0.1, 0.2, 1e9, 1.5, 0.5)\n"
         "print(sum(f.stats.cache_hits.values()), sum(f.stats.cache_misses.values()))\n")


def _fresh(cache_dir: str) -> tuple[str, str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache_dir}  # a cache of its own, empty at first
    proc = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip(), proc.stderr


@pytest.mark.long  # two fresh processes, 3-5 s
def test_the_second_process_loads_the_compiled_code_and_only_the_first_says_it_compiles(tmp_path):
    announce = NOTICE.split("{what}")[0]
    out, err = _fresh(str(tmp_path))
    assert out == "0 1"  # compiled: nothing to load yet
    assert err.count(announce) == 1 and "reference engine" in err
    assert list(tmp_path.rglob("*.nbi")) and list(tmp_path.rglob("*.nbc"))  # the index and the code on disk
    out, err = _fresh(str(tmp_path))
    assert out == "1 0"  # loaded from the cache, not compiled
    assert announce not in err


@pytest.mark.skipif(not hasattr(os, "getuid"), reason="POSIX user ids")
def test_the_fallback_cache_folder_is_used_only_when_it_is_this_users_alone(tmp_path, monkeypatch):
    """Where neither the install nor ~/.cache can be written, numba's cache moves to a per-user folder of
    the temporary directory; its files are loaded as code, so a folder others can write is refused."""
    import tempfile

    from numba.core import config

    from twin import jit

    monkeypatch.setattr(config, "CACHE_DIR", config.CACHE_DIR)  # restored after the test
    monkeypatch.setattr(tempfile, "gettempdir", lambda: str(tmp_path))
    assert jit._fallback_cache_dir()
    folder = tmp_path / f"twin-numba-cache-{os.getuid()}"
    assert config.CACHE_DIR == str(folder) and folder.stat().st_mode & 0o077 == 0
    folder.chmod(0o777)  # as if another user had made it first
    config.CACHE_DIR = ""
    assert not jit._fallback_cache_dir() and config.CACHE_DIR == ""
