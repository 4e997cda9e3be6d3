"""The twin's native MuJoCo hooks, shared by the planar and the spatial MuJoCo models.

One C extension, ``_bore`` (``_bore.c`` with ``_socket.c``; the headers ``_native.h``, ``_guide.h``
and ``_drivetrain.h``): the pin-in-bore and ball-in-socket colliders, the clearance joints' contact
law and friction, the guide clearance and the drive train in the passive callback, and the
friction sensors. :mod:`twin.native.collider` installs it into the MuJoCo library the ``mujoco``
module loaded and refuses a model the native code cannot read.

Neither engine owns it: ``twin.mujoco_engine`` (planar) and ``twin.spatial`` (spatial) both build
models that it runs, and it imports neither (nor the configuration).
"""
