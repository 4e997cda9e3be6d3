"""Build of the native bushing collider (twin.mujoco_engine._bore).

Everything else is declared in pyproject.toml. The collider is compiled against the C headers
shipped in the mujoco-core wheel (a build requirement), located without importing mujoco.
"""

import importlib.util
import os

from setuptools import Extension, setup

spec = importlib.util.find_spec("mujoco")
if spec is None or not spec.submodule_search_locations:
    raise RuntimeError("building twin needs mujoco-core (for its headers) in the build environment")
include = os.path.join(list(spec.submodule_search_locations)[0], "include")

setup(
    ext_modules=[
        Extension(
            "twin.mujoco_engine._bore",
            sources=["twin/mujoco_engine/_bore.c"],
            include_dirs=[include],
            extra_compile_args=["-O2"],
        )
    ]
)
