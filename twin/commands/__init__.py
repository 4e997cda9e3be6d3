"""Subcommands of the ``twin`` CLI, one module each (see :mod:`twin.cli`)."""
