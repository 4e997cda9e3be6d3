"""Native reference engine of the twin: the bench paper's dependent-coordinate multibody model
(S003 §3): natural coordinates, R-matrix velocity transformation, Lankarani–Nikravesh contact
with regularized Coulomb friction, symplectic Euler. The coordinates, constraints and mass
matrix are :mod:`twin.natural_coordinates`, the dynamics and integration
:mod:`twin.reference.model`; the penalty formulation it is compared with (§4.1) is a study,
:mod:`twin.studies.penalty`."""
