"""MuJoCo's own warnings, kept away from the user's terminal and folder.

MuJoCo's default warning handler prints each warning to standard output and appends it to
``MUJOCO_LOG.TXT`` in the working folder: a refused input then showed MuJoCo's text and a blank
line before the twin's one-line error, and left a log file behind. Importing this module (every
module of the twin that imports ``mujoco`` does, before building a model) installs one handler
for the whole process: the last few warnings are kept in :data:`MUJOCO_WARNINGS` for the messages
that need them (a diverging run names the quantity and the time), nothing is printed or written.
"""

from __future__ import annotations

import mujoco

#: MuJoCo's warnings of this process, the last few, as one-line texts
MUJOCO_WARNINGS: list[str] = []


def _on_mujoco_warning(message: str) -> None:
    MUJOCO_WARNINGS.append(" ".join(str(message).split()))
    del MUJOCO_WARNINGS[:-5]


mujoco.set_mju_user_warning(_on_mujoco_warning)
