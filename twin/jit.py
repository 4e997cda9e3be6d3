"""numba's ``njit`` for twin's compiled loops: cached on disk, and announced when it compiles.

Every compiled function of the reference engines and studies is decorated with :func:`njit` from here
(numba's, ``cache=True``). numba then stores the machine code beside the module
(``__pycache__/*.nbi, *.nbc``) or, where that folder is not writable (a system-wide install), in the
user's cache folder (``~/.cache/numba``; ``NUMBA_CACHE_DIR`` when set comes first), or where neither can
be written in a per-user folder of the temporary directory. The index is keyed by the source file's
content hash and the CPU, so a changed module or another CPU compiles again. (numba keys a function by
its own file only: after editing a compiled function that another module's compiled function calls,
clear the caller's cache, ``find twin -name '*.nb[ic]' -delete``.)

Compiling the reference engine's loop takes 18–47 s on two cores (measured from a quiet machine to
one loaded by other work, docs/speed.md), once after an install; a later process loads it in a
fraction of a second. So that a first run does not sit silent, the first
compilation of a process prints one line to stderr (:data:`NOTICE`); a cache hit prints nothing.
"""

from __future__ import annotations

import os
import sys
from typing import Any

NOTICE = ("twin: compiling the {what} with numba, once after an install (20-50 s; later runs load it "
          "from the cache)")

UNCACHED = ("twin: no folder to cache numba's compiled code in (the install, ~/.cache and the temporary "
            "directory are read-only): every run compiles; set NUMBA_CACHE_DIR to a writable folder")

_state = {"registered": False, "announced": False, "uncached": False}


def _what(module: str) -> str:
    if module.startswith("twin.spatial"):
        return "spatial reference engine"
    if module.startswith("twin.studies"):
        return "study's compiled loops"
    return "reference engine"


def _announce(module: str) -> None:
    if _state["announced"]:
        return
    _state["announced"] = True
    line = NOTICE.format(what=_what(module)) + ("\n" + UNCACHED if _state["uncached"] else "")
    tqdm_mod = sys.modules.get("tqdm")
    if tqdm_mod is not None:  # a progress bar may be on screen: print above it
        tqdm_mod.tqdm.write(line, file=sys.stderr)
    else:
        print(line, file=sys.stderr, flush=True)


def _register() -> None:
    """Listen (once per process) to numba's compile events: numba raises one only when a function
    is compiled, not when it is loaded from the cache (``numba.core.dispatcher.Dispatcher.compile``)."""
    if _state["registered"]:
        return
    from numba.core import event

    class _Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            disp = ev.data.get("dispatcher") if isinstance(ev.data, dict) else None
            module = getattr(getattr(disp, "py_func", None), "__module__", "") or ""
            if module.startswith("twin."):
                _announce(module)

        def on_end(self, ev: Any) -> None:
            pass

    event.register("numba:compile", _Listener())
    _state["registered"] = True


def _fallback_cache_dir() -> bool:
    """Point numba's cache at a per-user folder of the temporary directory (``NUMBA_CACHE_DIR``'s
    slot) when neither the install's folders nor the user's cache folder can be written; False
    where that folder cannot be written or is not this user's alone."""
    import tempfile

    from numba.core import config

    uid = os.getuid() if hasattr(os, "getuid") else None
    path = os.path.join(tempfile.gettempdir(), f"twin-numba-cache-{uid if uid is not None else 'user'}")
    try:
        os.makedirs(path, mode=0o700, exist_ok=True)
        st = os.stat(path)
        # numba's cache files are loaded as code: only a folder of this user that nobody else can write
        if uid is not None and (st.st_uid != uid or st.st_mode & 0o022):
            return False
        tempfile.TemporaryFile(dir=path).close()
    except OSError:
        return False
    config.CACHE_DIR = path
    return True


def _decorate(func: Any, kwargs: dict[str, Any]) -> Any:
    from numba import njit as numba_njit

    try:
        return numba_njit(**kwargs)(func)
    except RuntimeError as err:  # numba: "cannot cache function ...: no locator available for file ..."
        if not kwargs.get("cache") or "no locator available" not in str(err):
            raise
    if not _fallback_cache_dir():
        _state["uncached"] = True
        return numba_njit(**{**kwargs, "cache": False})(func)
    return numba_njit(**kwargs)(func)


def njit(*args: Any, **kwargs: Any) -> Any:
    """``numba.njit`` with ``cache=True`` (unless told otherwise) and the compilation notice; where
    no cache folder can be written (a read-only install without a writable home), the cache moves to
    the temporary directory, and without that the functions compile in every process (said once)."""
    _register()
    kwargs.setdefault("cache", True)
    if len(args) == 1 and callable(args[0]) and not kwargs.keys() - {"cache"}:
        return _decorate(args[0], kwargs)
    if args:
        raise TypeError("twin.jit.njit takes keyword options only (no signatures)")
    return lambda func: _decorate(func, kwargs)
