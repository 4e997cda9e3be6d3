"""Package layout and the build of the native bushing collider (twin.native._bore).

Metadata and dependencies are declared in pyproject.toml. The collider is compiled against the
C headers shipped in the mujoco-core wheel (a build requirement), located without importing
mujoco. It does not link the MuJoCo library: at run time it calls the library the ``mujoco``
module loaded (twin.native.collider), so a wheel of twin needs no MuJoCo library path.
GCC and Clang compile it with ``-Wall -Wextra -Werror`` (a warning fails the build), MSVC with
``/W3 /WX``.

Layout: the packages under twin/, plus three folders of the repository installed as packages, so
that their files ship in wheels and are found the same way in editable installs (with
importlib.resources) while they stay where the repository keeps them (one copy of each file):

* mjcf/ (the base MJCF model) as ``twin.mjcf`` (twin.names.BASE_XML);
* recordings/ (the synthetic sample recordings, *.mcap: 4.7 MB, with their format, FORMAT.md, and
  the script that made them) as ``twin.sample_recordings``;
* analysis/datasets/ (the dataset specs, *.toml) as ``twin.dataset_specs``.

twin.samples looks the last two up by name (``twin.samples.path("test6")``, ``sample:test6`` and
``twin dataset plan tiny`` on the command line), so the README's examples work after ``pip install``
outside the repository. Each of the three folders holds an ``__init__.py`` (an editable install
finds a mapped folder only as a regular package).
"""

import importlib.util
import os

from setuptools import Extension, find_namespace_packages, setup
from setuptools.command.build_ext import build_ext

spec = importlib.util.find_spec("mujoco")
if spec is None or not spec.submodule_search_locations:
    raise RuntimeError("building twin needs mujoco-core (for its headers) in the build environment")
include = os.path.join(list(spec.submodule_search_locations)[0], "include")

#: warnings are errors in the native code, with each compiler's own flags
WARNINGS = {"msvc": ["/W3", "/WX"]}
WARNINGS_DEFAULT = ["-O2", "-Wall", "-Wextra", "-Werror"]


class BuildExt(build_ext):
    def build_extensions(self):
        flags = WARNINGS.get(self.compiler.compiler_type, WARNINGS_DEFAULT)
        for ext in self.extensions:
            ext.extra_compile_args = list(ext.extra_compile_args or []) + flags
        super().build_extensions()


#: packages whose files live in a folder of the repository outside twin/ (see the docstring)
MAPPED = {"twin.mjcf": "mjcf", "twin.sample_recordings": "recordings", "twin.dataset_specs": "analysis/datasets"}

setup(
    packages=find_namespace_packages(include=["twin*"]) + list(MAPPED),
    package_dir=MAPPED,
    package_data={
        "twin": ["data/*.toml", "data/*.json", "data/*.xml", "data/*.npz", "native/*.c", "native/*.h",
                 "dataset/*.md", "config/presets/*.toml"],
        "twin.mjcf": ["*.xml"],
        "twin.sample_recordings": ["*.mcap", "FORMAT.md"],
        "twin.dataset_specs": ["*.toml"],
    },
    ext_modules=[
        Extension(
            "twin.native._bore",
            sources=["twin/native/_bore.c", "twin/native/_socket.c"],
            depends=["twin/native/_native.h", "twin/native/_guide.h", "twin/native/_drivetrain.h"],
            include_dirs=[include],
        )
    ],
    cmdclass={"build_ext": BuildExt},
)
