"""Typed errors of the twin.

Every error a user can provoke with bad input derives from :class:`TwinError`; the CLI
prints ``str(error)`` as one line and exits with status 2, never a traceback.
"""

from __future__ import annotations


class TwinError(Exception):
    """Base of every error the twin raises on purpose."""


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


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread like Ctrl-C so that every writer's clean-up runs
    (temporary files removed, nothing half-written left under the final name)."""


def raise_terminated(signum, frame):  # noqa: ARG001 - signal handler signature
    """SIGTERM handler: raise :class:`Terminated` in the main thread."""
    raise Terminated()
