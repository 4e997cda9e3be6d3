"""Package layout and the build of the native bushing collider (twin.mujoco_engine._bore).

Metadata and dependencies are declared in pyproject.toml. The collider is compiled against the
C headers shipped in the mujoco-core wheel (a build requirement), located without importing
mujoco.

Layout: the packages under twin/, plus the repository's top-level mjcf/ folder (the base MJCF
model) installed as the package ``twin.mjcf``, so that the model ships in wheels and works in
editable installs alike (twin.names.BASE_XML finds it with importlib.resources).
"""

import importlib.util
import os

from setuptools import Extension, find_namespace_packages, setup

spec = importlib.util.find_spec("mujoco")
if spec is None or not spec.submodule_search_locations:
    raise RuntimeError("building twin needs mujoco-core (for its headers) in the build environment")
include = os.path.join(list(spec.submodule_search_locations)[0], "include")

setup(
    packages=find_namespace_packages(include=["twin*"]) + ["twin.mjcf", "twin.sample_recordings", "twin.dataset_specs"],
    package_dir={"twin.mjcf": "mjcf", "twin.sample_recordings": "recordings", "twin.dataset_specs": "analysis/datasets"},
    package_data={
        "twin": ["data/*.toml", "data/*.json", "data/*.xml", "data/*.npz", "mujoco_engine/*.c", "mujoco_engine/*.h",
                 "dataset/*.md", "config/presets/*.toml"],
        "twin.mjcf": ["*.xml"],
        "twin.sample_recordings": ["*.mcap"],
        "twin.dataset_specs": ["*.toml"],
    },
    ext_modules=[
        Extension(
            "twin.mujoco_engine._bore",
            sources=["twin/mujoco_engine/_bore.c", "twin/mujoco_engine/_socket.c"],
            depends=["twin/mujoco_engine/_drivetrain.h"],
            include_dirs=[include],
            extra_compile_args=["-O2"],
        )
    ]
)
