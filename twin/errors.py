"""Typed errors of the twin.

Every error a user can provoke with bad input derives from :class:`TwinError`; the CLI
prints ``str(error)`` as one line and exits with status 2, never a traceback.
"""

from __future__ import annotations

from typing import Iterable


class TwinError(Exception):
    """Base of every error the twin raises on purpose.

    ``field`` (keyword) names what the error is about in the library's own terms: a dotted TOML path
    (``joints.clearance_b_mm``) or the Python argument's name (``max_lag_s``), never a command-line
    flag. The message then reads ``"field: message"``, and :attr:`field` and :attr:`message` keep the
    two parts apart so that a front end can name the field its own way (the CLI shows the flag that
    sets it). Errors about no single input leave ``field`` as None.
    """

    #: the parameter or configuration field the error is about, or None
    field: str | None = None
    #: the message without the field
    message: str = ""

    def __init__(self, *args: object, field: str | None = None):
        if field is not None:
            self.field, self.message = field, " ".join(str(a) for a in args)
            args = (f"{field}: {self.message}",)
        super().__init__(*args)


class ConfigError(TwinError, ValueError):
    """A configuration value is missing, unknown or out of its allowed range.

    The message names the field by its dotted TOML path (``joints.clearance_b_mm``)
    and states what is allowed.
    """

    def __init__(self, field: str, message: str):
        self.field = field
        self.message = message
        super().__init__(f"{field}: {message}")

    def __reduce__(self):
        # pickled with its two arguments: an error raised in a process-pool worker (dataset generation,
        # studies) reaches the parent as itself; the default (one message argument) failed to unpickle
        # there and broke the pool instead
        return (type(self), (self.field, self.message))


class ModelError(TwinError):
    """The MJCF model could not be built or compiled from a configuration."""


class SimulationError(TwinError):
    """A run diverged or the engine refused to continue (NaN, solver warnings)."""


class RecordingError(TwinError):
    """A run or recording file is missing, truncated, corrupt or inconsistent."""


class EngineUnavailableError(TwinError):
    """An engine or native extension is not available in this installation."""


class MissingExtraError(TwinError, ImportError):
    """An optional dependency is not installed; the message names the pip command that adds it."""


class NameNotFoundError(TwinError, LookupError):
    """A sample recording or a dataset spec asked for by a name that does not ship with the package
    (:mod:`twin.samples`); the message lists the names there are."""


def did_you_mean(given: object, allowed: Iterable[object]) -> str:
    """`` (did you mean 'x'?)`` for the entry of ``allowed`` closest to ``given`` (difflib's ratio
    at least 0.6, compared without case), or ``""`` when none is close: the one suggestion every
    "unknown name" error of the twin appends (preset names, configuration fields, ``--set`` keys,
    dataset spec keys, sample names)."""
    import difflib

    if not isinstance(given, str) or not given:
        return ""
    names = [str(a) for a in allowed]
    by_lower = {n.lower(): n for n in reversed(names)}  # the first spelling of a name wins
    match = difflib.get_close_matches(given.lower(), list(by_lower), n=1, cutoff=0.6)
    return f" (did you mean {by_lower[match[0]]!r}?)" if match and by_lower[match[0]] != given else ""


def unknown(what: str, given: object, allowed: Iterable[object]) -> str:
    """The message of a name that is not one of ``allowed``: ``unknown field (did you mean 'x'?);
    allowed: a, b, c`` (``what`` = field, key, section...)."""
    allowed = list(allowed)
    return f"unknown {what}{did_you_mean(given, allowed)}; allowed: {', '.join(str(a) for a in allowed)}"


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread like Ctrl-C so that every writer's clean-up runs
    (temporary files removed, nothing half-written left under the final name)."""


def raise_terminated(signum, frame):  # noqa: ARG001 - signal handler signature
    """SIGTERM handler: raise :class:`Terminated` in the main thread."""
    raise Terminated()
