"""Physics shared by the engines, engine-free: what the planar reference, the planar MuJoCo twin and
the spatial mechanism (both engines) all use, so that no engine imports another.

* :mod:`twin.physics.contact`: the compiled normal-force laws and regularized friction of a
  clearance joint (the reference engines step them; the MuJoCo models' native module applies the
  same formulas);
* :mod:`twin.physics.mujoco_params`: the contact law of a clearance joint as MuJoCo's native module
  applies it, the pair's solref/solimp, the prescribed drive's flywheel (numbers only; no ``mujoco``
  import).

Their constants come from the neutral modules :mod:`twin.contact_params` (stiffness, effective
masses), :mod:`twin.impact` (damping factors of the hysteresis laws) and
:mod:`twin.natural_coordinates` (the planar mechanism's coordinates). Nothing here imports an engine
package (``twin.reference``, ``twin.mujoco_engine``, ``twin.spatial``); the test
``tests/test_engine_independence.py`` checks it.
"""
