"""The spatial slider–crank of S002 in both engines: a crank turning about x, a rod with spherical
joints at both ends, a slider along a guide; clearance at the base revolute joint A (a journal in a
bearing) and at the spherical joints B and C (a ball in a socket).

* :mod:`twin.spatial.geometry`: the mechanism's constants from a configuration, closed-form kinematics;
* :mod:`twin.spatial.model`: the reference's compiled equations of motion (natural coordinates,
  R-matrix) and stepping loop;
* :mod:`twin.spatial.engine`: the reference engine for :func:`twin.simulation.simulate`.
"""

#: engine name -> "module:class" of the spatial mechanism's engines (imported on demand)
SPATIAL_ENGINE_CLASSES: dict[str, str] = {
    "reference": "twin.spatial.engine:SpatialReferenceEngine",
    "mujoco": "twin.spatial.mujoco:SpatialMujocoEngine",
}
