"""Bench configuration: one frozen dataclass per component, loadable from TOML.

Every number of the physical bench is a field here with its source (``S003`` is the bench
paper; tables refer to it). Values the papers leave open are
marked PLACEHOLDER in the docstrings: they are configuration, documented, never hidden
in code.

Numbers the base MuJoCo model ``mjcf/bench.xml`` also holds (Table 1 bodies, pin and bushing
sizes, the bushing friction law, guide friction, gravity, d_off, PID gains, accelerometer
mounts, timestep and solver numerics) are written once, in that file with their sources: the
fields' defaults are read from it by :mod:`twin.model_xml` ("default: mjcf/bench.xml" in
their docstrings). The other defaults are written here.

Bench frame (used by both engines): origin at the crank pivot A, ``x`` along the slider
guide towards the slider, ``y`` perpendicular in the plane of the mechanism (up in the
paper's tests), ``z = x × y`` along the crank axis. The bench angle ``θ`` of the crank is
measured from ``+x`` counter-clockwise about ``+z``; the encoder angle is ``θ + π/2`` so
that it reads zero with the crank along ``−y`` (S003 §2.3.3).

Validation happens in ``__post_init__``; errors are :class:`~twin.errors.ConfigError`
naming the dotted TOML path of the field and what is allowed.

Modules: the schema (:mod:`~twin.config.mechanism`: bodies, materials, joints, frame, contact;
:mod:`~twin.config.drive`: drive program and PID; :mod:`~twin.config.drivetrain`: the motor and
V-belt drive train; :mod:`~twin.config.structure`: the flexible rod, supports and sensor mounts; :mod:`~twin.config.sensors`: sensors and
instrumentation; :mod:`~twin.config.engines`: the engines and their settings;
:mod:`~twin.config.bench`: the whole :class:`BenchConfig`), the conversion to and from plain
dicts with ``--set`` overrides (:mod:`~twin.config.convert`), the readers of TOML files and
stored configurations with their migrations (:mod:`~twin.config.loading`) and the presets, TOML
files shipped in ``twin/config/presets/`` (:mod:`~twin.config.presets`). Everything is
imported from here: ``from twin.config import BenchConfig, load_config, preset``.
"""

from twin.config.bench import BenchConfig, joint_stiffness
from twin.config.common import (ACCELEROMETERS, ALL_CHANNEL_GROUPS, CATALOGUE_DIAMETRAL_MM, CHANNEL_GROUPS,
                                ENGINE_ONLY_GROUPS, JOINTS, OPTIONAL_CHANNEL_GROUPS, ORIENTATIONS, PROGRAMS)
from twin.config.convert import from_dict, with_overrides
from twin.config.drive import PID, Drive
from twin.config.drivetrain import Drivetrain
from twin.config.engines import ENGINE_CLASSES, ENGINES, MujocoSettings, Simulation
from twin.config.loading import config_from_toml, load_config
from twin.config.mechanism import Bodies, BodyParams, Contact, Joints, Material, Materials, Mechanism, ln_stiffness
from twin.config.presets import NAMED_PRESETS, TABLE4, named_preset, preset
from twin.config.spatial import Spatial
from twin.config.structure import STRUCTURE_MODES, StructureConfig
from twin.config.sensors import (ACCEL_MODEL_NAMES, ACCEL_RESPONSES, DAQ_RANGES, AccelMount, Instrumentation,
                                 Sensors)
from twin.errors import ConfigError

__all__ = [
    "ACCELEROMETERS", "ACCEL_MODEL_NAMES", "ACCEL_RESPONSES", "ALL_CHANNEL_GROUPS", "CATALOGUE_DIAMETRAL_MM",
    "CHANNEL_GROUPS", "DAQ_RANGES", "ENGINES", "ENGINE_CLASSES", "ENGINE_ONLY_GROUPS", "JOINTS", "NAMED_PRESETS",
    "OPTIONAL_CHANNEL_GROUPS", "ORIENTATIONS", "PROGRAMS", "STRUCTURE_MODES", "TABLE4",
    "AccelMount", "BenchConfig", "Bodies", "BodyParams", "ConfigError", "Contact", "Drive", "Drivetrain", "Instrumentation",
    "Joints", "Material", "Materials", "Mechanism", "MujocoSettings", "PID", "Sensors", "Simulation", "Spatial", "StructureConfig",
    "config_from_toml", "from_dict", "joint_stiffness", "ln_stiffness", "load_config", "named_preset", "preset",
    "with_overrides",
]
